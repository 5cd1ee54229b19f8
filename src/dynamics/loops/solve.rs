//! The constrained equations `M v̇ = f + Gᵀλ`, `G v̇ + γ = 0`, solved on the rows the loops'
//! `Structure` keeps, by the null-space method on the sparse factorisation of their normal
//! matrix A = GₛGₛᵀ (`Factored`). Then
//!
//! - the particular acceleration a₀ = −GₛᵀA⁻¹γₛ, the smallest with Gₛa₀ = −γₛ;
//! - the allowed motions N, one per free coordinate of the structure (the allowed part of its
//!   unit motion), and a = a₀ + Nz with (NᵀMN) z = Nᵀ(f − Ma₀) by Cholesky;
//! - the multipliers λₛ = A⁻¹Gₛ(Ma − f).
//!
//! The kept rows are fixed along the run and independent wherever the mechanism is regular, so
//! the accelerations are a smooth function of the state there; they do not depend on the basis
//! N of the allowed motions, only on the space it spans. Motions that move no mass
//! (their number is part of the structure) are left at rest.

use nalgebra::{Cholesky, DMatrix, DVector};

use super::factored::{Envelope, Factored, RowChoice, Singular, DAMPING};
use super::rows::{constraints, Constraints};
use super::structure::Structure;
use crate::dynamics::algorithms::{crba, Data};
use crate::dynamics::model::Model;
use crate::kinematics::eval::EvalError;

/// How the constraints are kept: by projecting the state after each step (exact), by Baumgarte's
/// feedback in the accelerations (with this rate, in 1/s, critically damped), by the integrator's
/// own equations (the symplectic integrator's RATTLE steps), or not at all.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Stabilisation {
    Projection,
    Baumgarte(f64),
    Integrator,
    None,
}

/// What the constrained solve keeps from one evaluation to the next, so that it allocates
/// nothing once sized: the constraint rows (filled by the caller, `rows::constraints_into`),
/// their factorisation, the solve's vectors, and its results.
pub struct LoopScratch {
    pub constraints: Constraints,
    pub factored: Factored,
    /// The damped factor's storage between evaluations.
    factor: Envelope,
    /// Vectors over the kept rows, over all the rows, over the state's velocities.
    kept: Vec<f64>,
    gamma: DVector<f64>,
    particular: DVector<f64>,
    applied: DVector<f64>,
    /// The allowed motions N, M times their tree part, NᵀMN (and its factor), and Nᵀ(f − Ma₀),
    /// then z.
    null: DMatrix<f64>,
    mass_null: DMatrix<f64>,
    null_transposed: DMatrix<f64>,
    inertial: DVector<f64>,
    reduced_mass: DMatrix<f64>,
    reduced_factor: DMatrix<f64>,
    reduced_force: DVector<f64>,
    /// Accelerations of every state velocity.
    pub accelerations: DVector<f64>,
    /// Constraint wrench of each loop on its second body, at the loop point in fixed axes:
    /// moment, then force (6 per loop).
    pub multipliers: DVector<f64>,
}

impl LoopScratch {
    pub fn new(model: &Model) -> LoopScratch {
        let constraints = Constraints::new(model);
        let (rows, columns) = (constraints.residual.len(), model.velocities());
        LoopScratch {
            factored: Factored::new(&constraints.jacobian, &RowChoice::NONE),
            constraints,
            factor: Envelope::default(),
            kept: Vec::new(),
            gamma: DVector::zeros(rows),
            particular: DVector::zeros(columns),
            applied: DVector::zeros(columns),
            null: DMatrix::zeros(columns, 0),
            mass_null: DMatrix::zeros(model.nv, 0),
            null_transposed: DMatrix::zeros(0, columns),
            inertial: DVector::zeros(model.nv),
            reduced_mass: DMatrix::zeros(0, 0),
            reduced_factor: DMatrix::zeros(0, 0),
            reduced_force: DVector::zeros(0),
            accelerations: DVector::zeros(columns),
            multipliers: DVector::zeros(rows),
        }
    }

    /// Sizes the allowed motions' matrices for `free` coordinates (allocates only when their
    /// number changes, with the structure).
    fn size_for(&mut self, free: usize) {
        if self.null.ncols() != free {
            self.null = DMatrix::zeros(self.null.nrows(), free);
            self.mass_null = DMatrix::zeros(self.mass_null.nrows(), free);
            self.null_transposed = DMatrix::zeros(free, self.null.nrows());
            self.reduced_mass = DMatrix::zeros(free, free);
            self.reduced_factor = DMatrix::zeros(free, free);
            self.reduced_force = DVector::zeros(free);
        }
    }
}

#[derive(Clone, Debug, PartialEq)]
pub enum LoopError {
    /// An effort acts on a motion that moves no mass: its acceleration would be infinite. The
    /// state velocity that motion moves most.
    MasslessMotion { velocity: usize },
    /// The kept rows are dependent here: the mechanism is exactly at a singular configuration.
    /// The row (among the 6 per loop) that lost its independence.
    Singular { row: usize },
}

/// A force on a motion without mass stops the run above this fraction of the largest force on
/// the motions: it is a model that forgot a mass, not the residue (1e-6 relative seen on the
/// Delta's rod spins) of evaluating forces that balance exactly.
const MASSLESS_FORCE: f64 = 1e-3;

/// Solves `M v̇ = f + Gᵀλ`, `G v̇ + γ = 0` on the kept rows (γ with Baumgarte's terms when asked
/// for) at the constraints in `scratch`; `mass` is the tree's mass matrix, `force` has the
/// state's length. The accelerations and multipliers are left in `scratch`.
pub fn solve(
    mass: &DMatrix<f64>,
    force: &DVector<f64>,
    structure: &Structure,
    stabilisation: Stabilisation,
    scratch: &mut LoopScratch,
) -> Result<(), LoopError> {
    scratch.size_for(structure.free.len());
    let LoopScratch {
        constraints: c,
        factored,
        factor,
        kept,
        gamma,
        particular,
        applied,
        null,
        mass_null,
        null_transposed,
        inertial,
        reduced_mass,
        reduced_factor,
        reduced_force,
        accelerations,
        multipliers,
    } = scratch;
    gamma.copy_from(&c.bias);
    if let Stabilisation::Baumgarte(rate) = stabilisation {
        gamma.axpy(2.0 * rate, &c.velocity, 1.0);
        gamma.axpy(rate * rate, &c.residual, 1.0);
    }
    factored.refill(&c.jacobian, &structure.choice);
    let damped = factored
        .damped_in(DAMPING, std::mem::take(factor))
        .map_err(singular)?;
    factored.kept_into(gamma.as_slice(), kept);
    kept.iter_mut().for_each(|x| *x = -*x);
    damped.least_norm_into(kept, particular.as_mut_slice());
    damped.allowed_motions_into(&structure.free, kept, null);
    // The complementary links' own coordinates carry no inertia: only the tree's rows of the
    // motions meet the mass matrix.
    let nv = mass.nrows();
    let tree = null.rows(0, nv);
    mass.mul_to(&tree, mass_null);
    null.transpose_to(null_transposed);
    null_transposed
        .columns(0, nv)
        .mul_to(mass_null, reduced_mass);
    mass.mul_to(&particular.rows(0, nv), inertial);
    applied.copy_from(force);
    let mut top = applied.rows_mut(0, nv);
    top -= &*inertial;
    null_transposed.mul_to(applied, reduced_force);
    massive_solve(
        reduced_mass,
        reduced_factor,
        reduced_force,
        structure.massless,
    )
    .map_err(|k| LoopError::MasslessMotion {
        velocity: null.column(k).iamax(),
    })?;
    null.mul_to(reduced_force, accelerations);
    *accelerations += &*particular;
    // Ma − f, the constraint forces' share.
    mass.mul_to(&accelerations.rows(0, nv), inertial);
    applied.copy_from(force);
    applied.neg_mut();
    let mut top = applied.rows_mut(0, nv);
    top += &*inertial;
    damped.multipliers_into(applied.as_slice(), kept, multipliers.as_mut_slice());
    *factor = damped.into_storage();
    Ok(())
}

fn singular(lost: Singular) -> LoopError {
    LoopError::Singular { row: lost.row }
}

/// Solves the symmetric positive semi-definite system `a z = b` in the span of the eigenvectors
/// that carry mass, z into `b`: the `massless` smallest eigenvalues count as without mass (their
/// number is part of the structure, not decided here). A motion without mass stays at rest
/// unless a force acts on it (then its eigenvector index is the error). `work` is scratch of a's size.
fn massive_solve(
    a: &DMatrix<f64>,
    work: &mut DMatrix<f64>,
    b: &mut DVector<f64>,
    massless: usize,
) -> Result<(), usize> {
    if a.nrows() == 0 {
        return Ok(());
    }
    if massless == 0 {
        work.copy_from(a);
        // The factorisation takes the buffer and gives it back: no allocation.
        if let Some(cholesky) = Cholesky::new(std::mem::take(work)) {
            cholesky.solve_mut(b);
            *work = cholesky.unpack_dirty();
            return Ok(());
        }
        *work = a.clone();
    }
    let eigen = a.clone().symmetric_eigen();
    let mut order: Vec<usize> = (0..eigen.eigenvalues.len()).collect();
    order.sort_by(|&i, &j| eigen.eigenvalues[i].total_cmp(&eigen.eigenvalues[j]));
    let scale = b.amax().max(f64::MIN_POSITIVE);
    let mut z = DVector::zeros(b.len());
    for (rank, &k) in order.iter().enumerate() {
        let (value, vector) = (eigen.eigenvalues[k], eigen.eigenvectors.column(k));
        let component = vector.dot(b);
        if rank >= massless && value > 0.0 {
            z += vector * (component / value);
        } else if component.abs() > MASSLESS_FORCE * scale {
            return Err(k);
        }
    }
    b.copy_from(&z);
    Ok(())
}

/// Replaces v by the motion the kept rows allow that has the same momentum along every allowed
/// motion: v' = N(NᵀMN)⁻¹NᵀMv over the allowed motions N of the structure's free coordinates,
/// the velocity an impulsive reaction of the constraints leaves (it does no work on the allowed
/// motions, and removes only the kinetic energy of the motion across them). Used where the
/// constraints come back after a passage through a singular configuration: what the released
/// rows let the motion gain across them is taken away whole, and nothing along the branch.
/// Leaves v as it is when some allowed motion has no mass (the projection is then not defined).
pub fn project_momentum(
    model: &Model,
    data: &mut Data,
    structure: &Structure,
    q: &[f64],
    v: &mut [f64],
) -> Result<(), EvalError> {
    let rest = vec![0.0; v.len()];
    let c = constraints(model, data, q, &rest, false)?;
    let factored = Factored::new(&c.jacobian, &structure.choice);
    let Ok(damped) = factored.damped(DAMPING) else {
        return Ok(());
    };
    let allowed = damped.allowed_motions(&structure.free);
    let mass = crba(model, data, &q[..model.nq])?;
    let tree = allowed.rows(0, model.nv);
    let momentum = &mass * DVector::from_column_slice(&v[..model.nv]);
    let reduced = tree.transpose() * (&mass * tree);
    let Some(cholesky) = reduced.cholesky() else {
        return Ok(());
    };
    let moved = &allowed * cholesky.solve(&(tree.transpose() * momentum));
    v.copy_from_slice(moved.as_slice());
    Ok(())
}
