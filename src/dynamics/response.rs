//! The response of a mechanism's accelerations to generalised forces, X = S (SᵀMS)⁻¹ Sᵀ, with
//! S a basis of the motions its equations of motion move along and M the tree's mass matrix:
//!
//! - a tree: S = I, X = M⁻¹;
//! - a tree with mimic couplings: S the couplings' basis (`mimics::basis`), so that X F keeps
//!   them (they are eliminated, not solved as rows);
//! - a mechanism with closed loops: S = N, the loops' allowed motions of the last constrained
//!   solve (`LoopScratch::solved_motions`), so that X F keeps the loops' rows (G X = 0).
//!
//! Every other constraint row E (contacts, couplings with loops, coordinates held at rest) is
//! solved on X (`rows`): its forces change the accelerations by X Eᵀλ, and a state moved along
//! X Eᵀ keeps the rows X already keeps, to first order. Nothing is allocated once the storage is
//! sized for the basis and for the number of force columns.

use nalgebra::{DMatrix, DMatrixView, DVector};

use super::dense::Factor;

/// X's factorisation at one state, in storage kept between evaluations.
#[derive(Clone, Debug)]
pub struct Response {
    /// S over the state's velocities (n × k), unused when `identity`.
    basis: DMatrix<f64>,
    identity: bool,
    /// M S (tree velocities × k), SᵀMS's factor, and Sᵀ F (k × columns).
    moved: DMatrix<f64>,
    factor: Factor,
    reduced: DMatrix<f64>,
    projected: DMatrix<f64>,
    projected_vector: DVector<f64>,
    /// Whether the last `form` succeeded (X is usable).
    pub formed: bool,
}

impl Default for Response {
    fn default() -> Self {
        Response {
            basis: DMatrix::zeros(0, 0),
            identity: true,
            moved: DMatrix::zeros(0, 0),
            factor: Factor::new(0),
            reduced: DMatrix::zeros(0, 0),
            projected: DMatrix::zeros(0, 0),
            projected_vector: DVector::zeros(0),
            formed: false,
        }
    }
}

impl Response {
    /// Forms X = M⁻¹ for the tree's mass matrix `mass`: false where M is not positive definite.
    pub fn on_tree(&mut self, mass: &DMatrix<f64>) -> bool {
        self.identity = true;
        self.size_factor(mass.nrows());
        self.formed = self.factor.factor(mass);
        self.formed
    }

    /// Forms X = S (SᵀMS)⁻¹ Sᵀ for the basis `basis` (over the state's velocities, the tree's
    /// first) and the tree's mass matrix `mass`: false where SᵀMS is not positive definite (an
    /// allowed motion without mass).
    pub fn on_basis(&mut self, mass: &DMatrix<f64>, basis: DMatrixView<'_, f64>) -> bool {
        let (n, k) = basis.shape();
        self.identity = false;
        if self.basis.shape() != (n, k) {
            self.basis = DMatrix::zeros(n, k);
            self.moved = DMatrix::zeros(mass.nrows(), k);
            self.reduced = DMatrix::zeros(k, k);
            self.projected_vector = DVector::zeros(k);
        }
        self.size_factor(k);
        self.basis.copy_from(&basis);
        let tree = self.basis.rows(0, mass.nrows());
        self.moved.gemm(1.0, mass, &tree, 0.0);
        self.reduced.gemm_tr(1.0, &tree, &self.moved, 0.0);
        self.formed = self.factor.factor(&self.reduced);
        self.formed
    }

    fn size_factor(&mut self, size: usize) {
        if self.factor.size() != size {
            self.factor = Factor::new(size);
        }
    }

    /// X F for the generalised forces `forces` (columns over the state's velocities) into `out`
    /// (of `forces`' shape). X must be formed.
    pub fn apply(&mut self, forces: &DMatrix<f64>, out: &mut DMatrix<f64>) {
        if self.identity {
            out.copy_from(forces);
            self.factor.solve_mut(out);
            return;
        }
        let columns = forces.ncols();
        if self.projected.shape() != (self.basis.ncols(), columns) {
            self.projected = DMatrix::zeros(self.basis.ncols(), columns);
        }
        self.projected.gemm_tr(1.0, &self.basis, forces, 0.0);
        self.factor.solve_mut(&mut self.projected);
        out.gemm(1.0, &self.basis, &self.projected, 0.0);
    }

    /// X f for one force vector, in place. X must be formed.
    pub fn apply_vector(&mut self, force: &mut DVector<f64>) {
        if self.identity {
            self.factor.solve_vector_mut(force);
            return;
        }
        self.projected_vector.gemv_tr(1.0, &self.basis, force, 0.0);
        self.factor.solve_vector_mut(&mut self.projected_vector);
        force.gemv(1.0, &self.basis, &self.projected_vector, 0.0);
    }
}
