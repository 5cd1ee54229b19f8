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

use nalgebra::{DMatrix, DVector};

use std::ops::{AddAssign, SubAssign};

use super::factored::{Factored, Singular, DAMPING};
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

pub struct Solution {
    /// Accelerations of every state velocity.
    pub accelerations: DVector<f64>,
    /// Constraint wrench of each loop on its second body, at the loop point in fixed axes:
    /// moment, then force (6 per loop).
    pub multipliers: DVector<f64>,
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
/// for); `mass` is the tree's mass matrix, `force` has the state's length.
pub fn solve(
    mass: &DMatrix<f64>,
    force: &DVector<f64>,
    c: &Constraints,
    structure: &Structure,
    stabilisation: Stabilisation,
) -> Result<Solution, LoopError> {
    let mut gamma = c.bias.clone();
    if let Stabilisation::Baumgarte(rate) = stabilisation {
        gamma += 2.0 * rate * &c.velocity + rate * rate * &c.residual;
    }
    let factored = Factored::new(&c.jacobian, &structure.choice);
    let damped = factored.damped(DAMPING).map_err(singular)?;
    let particular = damped.least_norm(&-factored.kept(&gamma));
    let null = damped.allowed_motions(&structure.free);
    // The complementary links' own coordinates carry no inertia: only the tree's rows of the
    // motions meet the mass matrix.
    let tree = null.rows(0, mass.nrows());
    let mass_times_null = mass * tree;
    let reduced_mass = tree.transpose() * &mass_times_null;
    let inertial = mass * particular.rows(0, mass.nrows());
    let mut applied = force.clone();
    applied.rows_mut(0, mass.nrows()).sub_assign(&inertial);
    let reduced_force = null.transpose() * applied;
    let z = massive_solve(reduced_mass, &reduced_force, structure.massless).map_err(|k| {
        LoopError::MasslessMotion {
            velocity: null.column(k).iamax(),
        }
    })?;
    let accelerations = particular + &null * z;
    let mut unbalanced = -force;
    let inertial = mass * accelerations.rows(0, mass.nrows());
    unbalanced.rows_mut(0, mass.nrows()).add_assign(&inertial);
    let multipliers = damped.multipliers(&unbalanced, c.residual.len());
    Ok(Solution {
        accelerations,
        multipliers,
    })
}

fn singular(lost: Singular) -> LoopError {
    LoopError::Singular { row: lost.row }
}

/// Solves the symmetric positive semi-definite system `a z = b` in the span of the eigenvectors
/// that carry mass: the `massless` smallest eigenvalues count as without mass (their number is
/// part of the structure, not decided here). A motion without mass stays at rest unless a force
/// acts on it (then its eigenvector index is the error).
fn massive_solve(
    a: DMatrix<f64>,
    b: &DVector<f64>,
    massless: usize,
) -> Result<DVector<f64>, usize> {
    if a.nrows() == 0 {
        return Ok(DVector::zeros(0));
    }
    if massless == 0 {
        if let Some(cholesky) = a.clone().cholesky() {
            return Ok(cholesky.solve(b));
        }
    }
    let eigen = a.symmetric_eigen();
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
    Ok(z)
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
