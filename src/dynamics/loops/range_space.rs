//! The constrained equations `M v̇ = f + Gᵀλ`, `G v̇ + γ = 0` solved by the range-space method,
//! beside the null-space method of `solve`: where the kept rows are few and the allowed motions
//! many (a long closed chain: one loop of N rods, 3 kept rows, N − 2 allowed motions), it costs
//! what the rows cost, O(N k) for k kept rows, where the null-space method costs what the
//! mobility costs (a basis of N − k motions, their reduced mass matrix and its factorisation).
//!
//! With the velocities split into the tree's, t, and the complementary links' own, c (which
//! carry no inertia), and Gₛ = [Gₜ G꜀] the kept rows made dimensionless:
//!
//! ```text
//! a₀ = Mₜ⁻¹ fₜ                                (ABA with the efforts, gravity, velocity products)
//! Y  = Mₜ⁻¹ Gₜᵀ                               (k passes of ABA on its articulated inertias)
//! [ Gₜ Y  G꜀ ] [ λ  ]   [ −γₛ − Gₜ a₀ ]
//! [ G꜀ᵀ   0  ] [ a꜀ ] = [ −f꜀         ]        (k + c unknowns, Gaussian elimination)
//! aₜ = a₀ + Y λ
//! ```
//!
//! The second block row says that no force acts on a complementary coordinate, which has no
//! inertia: the constraint forces balance the efforts on it. The idle coordinates (a
//! complementary link's own that no kept row touches) are left at rest, as the null-space
//! method leaves them. The constraint forces through articulated-body responses: Featherstone,
//! *Rigid Body Dynamics Algorithms*, 2008, §8.3 and §8.5 (the range-space form, the "constraint
//! forces via ABA"); Ascher and Petzold 1998, §9.2.
//!
//! The accelerations are those of the null-space method: both solve the same saddle-point
//! system exactly where the rows are independent (the null-space method's damping, 1e-9 of the
//! largest row, changes them by (μ/σ)², below round-off away from singular configurations).

use nalgebra::{DMatrix, DVector};

use super::factored::Factored;
use super::structure::Structure;
use crate::dynamics::algorithms::mass_solve::{mass_solve_after_aba, MassSolveScratch};
use crate::dynamics::algorithms::{aba_after_kinematics, Data, DynamicsError};
use crate::dynamics::dense::solve_in_place;
use crate::dynamics::model::Model;
use crate::dynamics::planar::algorithms::{self as planar_algorithms, PlanarData};
use crate::dynamics::planar::PlanarModel;
use crate::spatial::Force;

/// The tree the range-space method solves on, with its kinematics at the state: in planar
/// form (`planar::algorithms::kinematics`, the external forces set), or spatial
/// (`algorithms::forward_kinematics`), with the efforts' external forces on the bodies.
pub enum Tree<'a> {
    Planar(&'a PlanarModel, &'a mut PlanarData),
    Spatial(&'a mut Data, &'a [Force]),
}

/// Which method solves the loops' equations of motion.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    /// On the allowed motions (`solve`): cost grows with the mobility.
    NullSpace,
    /// On the kept rows (this file): cost grows with the rows.
    RangeSpace,
}

/// The method the loops' block takes for `structure`, on a model where the range-space method
/// applies (`applies_to`): the range-space method where the free coordinates (one per allowed
/// motion) number at least twice the kept rows, the null-space method otherwise. Per
/// evaluation the null-space method makes one sparse solve and one pass over the bodies per
/// allowed motion, then forms and factors their m × m reduced mass matrix (m² products over
/// the bodies, m³); the range-space method one pass of ABA, then two passes over the bodies per
/// kept row and k² products over the rows' columns. Measured on the necklace of N rods (k = 3
/// rows, m = N − 2; `benches/loop_scaling.rs`, `switch`), the null-space right-hand side is the
/// cheaper up to m = 5 and the range-space one from m = 6 = 2k on.
pub fn method_for(structure: &Structure, applies: bool) -> Method {
    match applies && structure.free.len() >= 2 * structure.choice.rows.len() {
        true => Method::RangeSpace,
        false => Method::NullSpace,
    }
}

/// Whether the range-space method applies to `model`: its tree's mass matrix is positive
/// definite, since ABA divides by every joint's articulated inertia. So every body has mass
/// and a rotational inertia of full rank (its spatial inertia positive definite, its smallest
/// eigenvalue above 1e-12 of its largest: a point-mass rod, whose spin about its own axis
/// moves no mass, does not qualify). Then the loops allow no motion without mass but of the
/// complementary coordinates, which the saddle-point system solves for (the structure's
/// count of such motions, `massless`, is not read). Nor does it apply to a model with
/// geared rotors (ABA's rotor steps are not among the responses' passes), or one whose
/// actuators' laws read the model in their coordinates (`dynamics::reduced_model`, which works
/// on the allowed motions). Decided once per model.
pub fn applies_to(model: &Model) -> bool {
    let full = |body: &crate::dynamics::elements::BodyInertia| {
        let values = body.inertia.symmetric_eigenvalues();
        !body.massless && values.min() > 1e-12 * values.max()
    };
    let reads_motions = model.actuation.as_ref().is_some_and(|a| a.reads.any());
    model.rotors.is_empty() && !reads_motions && model.dynamic_bodies.iter().all(full)
}

/// Why the range-space solve failed: a joint whose articulated inertia is singular (the state
/// velocity it moves), or kept rows dependent here (the row, among the 6 per loop).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Failure {
    MasslessMotion { velocity: usize },
    Singular { row: usize },
}

/// The range-space method's storage, sized at the first evaluation and when the rows change:
/// an evaluation allocates nothing once sized.
#[derive(Default)]
pub struct RangeSpace {
    /// Y = Mₜ⁻¹Gₜᵀ over the state's velocities (zero on the complementary ones), one column
    /// per kept row.
    responses: DMatrix<f64>,
    /// A kept row's tree part, as generalised forces.
    force: Vec<f64>,
    /// A product of the kept rows with a vector.
    rows: Vec<f64>,
    /// The spatial responses' passes.
    passes: MassSolveScratch,
    /// The complementary coordinates some kept row touches, and each one's position among
    /// them (by complementary index), or `usize::MAX`.
    complementary: Vec<usize>,
    position: Vec<usize>,
    /// The saddle-point system and its right-hand side, then solution.
    system: DMatrix<f64>,
    rhs: Vec<f64>,
}

impl RangeSpace {
    /// The accelerations of every state velocity into `accelerations`, from the kept rows in
    /// `factored` (made dimensionless), `minus_gamma` = −γₛ on them, the efforts' generalised
    /// forces `tau` over the state's velocities and the tree at the state.
    #[allow(clippy::too_many_arguments)]
    pub fn solve(
        &mut self,
        model: &Model,
        mut tree: Tree<'_>,
        structure: &Structure,
        factored: &Factored,
        minus_gamma: &[f64],
        tau: &DVector<f64>,
        accelerations: &mut DVector<f64>,
    ) -> Result<(), Failure> {
        let (nv, velocities, k) = (model.nv, accelerations.len(), factored.len());
        self.size_for(factored, nv, velocities);
        accelerations.fill(0.0);
        let joint_velocity = |joint: usize| model.joints[joint].v_offset;
        let forward = match &mut tree {
            Tree::Planar(planar, data) => {
                planar_algorithms::aba(planar, data, tau.as_slice(), accelerations)
            }
            Tree::Spatial(data, external) => {
                aba_after_kinematics(model, data, tau.as_slice(), external, accelerations)
            }
        };
        forward.map_err(|e| match e {
            DynamicsError::Singular { joint, .. } => Failure::MasslessMotion {
                velocity: joint_velocity(joint),
            },
            DynamicsError::Evaluation(_) => unreachable!("the planar ABA evaluates no expression"),
        })?;
        // Y: one response of the tree per kept row, on ABA's articulated inertias.
        for j in 0..k {
            self.force.fill(0.0);
            for (column, value) in factored.row_entries(j).filter(|&(c, _)| c < nv) {
                self.force[column] = value;
            }
            let mut column = self.responses.column_mut(j);
            let response = &mut column.as_mut_slice()[..nv];
            match &mut tree {
                Tree::Planar(planar, data) => {
                    planar_algorithms::mass_solve_after_aba(planar, data, &self.force, response)
                }
                Tree::Spatial(data, _) => {
                    mass_solve_after_aba(model, data, &self.force, response, &mut self.passes)
                }
            }
        }
        // The saddle-point system: Gₜ Y, G꜀ and its transpose, zero below.
        self.system.fill(0.0);
        for l in 0..k {
            factored.times_into(self.responses.column(l).as_slice(), &mut self.rows);
            for (j, &value) in self.rows.iter().enumerate() {
                self.system[(j, l)] = value;
            }
        }
        for j in 0..k {
            for (column, value) in factored.row_entries(j).filter(|&(c, _)| c >= nv) {
                let p = self.position[column - nv];
                if p != usize::MAX {
                    self.system[(j, k + p)] = value;
                    self.system[(k + p, j)] = value;
                }
            }
        }
        factored.times_into(accelerations.as_slice(), &mut self.rows);
        self.rhs.clear();
        self.rhs
            .extend(minus_gamma.iter().zip(&self.rows).map(|(g, r)| g - r));
        self.rhs.extend(self.complementary.iter().map(|&c| -tau[c]));
        if let Err(pivot) = solve_in_place(&mut self.system, &mut self.rhs) {
            let row = structure.choice.rows[pivot.min(k.saturating_sub(1))];
            return Err(Failure::Singular { row });
        }
        for (l, &lambda) in self.rhs[..k].iter().enumerate() {
            accelerations.axpy(lambda, &self.responses.column(l), 1.0);
        }
        for (&c, &rate) in self.complementary.iter().zip(&self.rhs[k..]) {
            accelerations[c] = rate;
        }
        Ok(())
    }

    /// Sizes the storage for the rows in `factored` (allocates only when their number or the
    /// complementary columns they touch change).
    fn size_for(&mut self, factored: &Factored, nv: usize, velocities: usize) {
        let k = factored.len();
        self.complementary.clear();
        self.complementary
            .extend((nv..velocities).filter(|&c| factored.touches(c)));
        self.position.clear();
        self.position.resize(velocities - nv, usize::MAX);
        for (p, &c) in self.complementary.iter().enumerate() {
            self.position[c - nv] = p;
        }
        let n = k + self.complementary.len();
        if self.responses.shape() != (velocities, k) {
            self.responses = DMatrix::zeros(velocities, k);
        }
        if self.system.shape() != (n, n) {
            self.system = DMatrix::zeros(n, n);
        }
        self.force.resize(nv, 0.0);
    }
}
