//! The velocities an impulse of the constraints leaves (`project_momentum`): after a projection
//! near a singular configuration, where the outputs' velocities and those of a run whose rows
//! come back after a passage must keep their momentum along the allowed motions. It works on the
//! rows and the factorisation the projection just ended with (`ProjectionScratch`), not on
//! rows evaluated again.

use nalgebra::{DMatrix, DVector};

use super::factored::Factored;
use super::orthonormal::orthonormal_allowed_motions;
use super::project::ProjectionScratch;
use super::structure::Structure;
use crate::dynamics::algorithms::{
    crba, crba_into, forward_kinematics, joint_transforms, mass_times, Data,
};
use crate::dynamics::model::Model;
use crate::kinematics::eval::EvalError;

/// Below this conditioning of the kept rows, `project_momentum` asked for `Basis::Orthonormal`
/// spans the allowed motions with an orthonormal basis corrected to round-off
/// (`orthonormal_allowed_motions`): the free coordinates' allowed motions alone, from solves on
/// the rows' normal matrix, cost ε/σ² of the velocity (on a row of ten four-bars at σ = 1e-4,
/// 8.7e-8 rad/s between the cranks, which should turn together).
const DENSE_MOMENTUM_BELOW: f64 = 1e-2;

/// Above this many velocities `project_momentum` multiplies by the mass matrix only over the
/// entries its joints' branches can fill (`mass_times`), in a matrix kept in the projection's
/// scratch: a fresh n × n matrix and dense products grow as n², and on the ladder of 1,000
/// loops (3,002 velocities, projected by impulse at every step since its kept rows' conditioning
/// falls below `NEAR_SINGULAR` from N = 300 on) they were most of a projection. Below, the
/// dense products as before, to the last bit (the row of two four-bars' flat passages are
/// sensitive to it).
const SPARSE_MASS_ABOVE: usize = 400;

/// How `project_momentum` spans the allowed motions near a singular configuration.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum MomentumBasis {
    /// The free coordinates' allowed motions, by sparse solves, as the equations of motion.
    Free,
    /// An orthonormal basis exact to round-off below a conditioning of 1e-2, when no motion is
    /// idle or without mass (`DENSE_MOMENTUM_BELOW`): for the outputs, whose velocities are
    /// compared with the motion's own. From the sparse factorisation
    /// (`orthonormal_allowed_motions`), or a dense QR factorisation of the rows where it cannot
    /// be taken (rows exactly dependent).
    Orthonormal,
}

/// Replaces v by the motion the kept rows allow that has the same momentum along every allowed
/// motion: v' = N(NᵀMN)⁻¹NᵀMv over the allowed motions N of the structure's free coordinates,
/// the velocity an impulsive reaction of the constraints leaves (it does no work on the allowed
/// motions, and removes only the kinetic energy of the motion across them). Used where the
/// constraints come back after a passage through a singular configuration: what the released
/// rows let the motion gain across them is taken away whole, and nothing along the branch.
/// Leaves v as it is when some allowed motion has no mass (the projection is then not defined).
/// q must be where `projection` last ended (`project_from`): its rows and their layout serve
/// here as they are, evaluated again only where it seated ball angles after them.
pub fn project_momentum(
    model: &Model,
    data: &mut Data,
    structure: &Structure,
    (q, v): (&[f64], &mut [f64]),
    basis: MomentumBasis,
    projection: &mut ProjectionScratch,
) -> Result<(), EvalError> {
    if model.loop_balls.iter().any(Option::is_some) {
        // The projection seated the complementary balls' angles after its last rows were
        // taken: the rows again at the seated positions.
        let rest = vec![0.0; v.len()];
        forward_kinematics(model, data, q, &rest)?;
        projection.constraints_at(model, data, q, &rest)?;
    }
    let allowed = projection.with_final_rows(&structure.choice, |factored, damped| {
        let dense = basis == MomentumBasis::Orthonormal
            && factored.conditioning_of(damped).0 < DENSE_MOMENTUM_BELOW
            && structure.idle.is_empty()
            && structure.massless == 0;
        match (dense, damped) {
            (true, Ok(damped)) if parametrised(factored, structure) => Some(
                orthonormal_allowed_motions(factored, damped, &structure.free),
            ),
            (true, _) => Some(factored.dense_null_space().clone()),
            (false, Ok(damped)) => Some(damped.allowed_motions(&structure.free)),
            (false, Err(_)) => None,
        }
    });
    let Some(allowed) = allowed else {
        return Ok(());
    };
    let tree = allowed.rows(0, model.nv);
    let (reduced, along) = if model.nv > SPARSE_MASS_ABOVE {
        large_mechanism_forms(model, data, q, v, &allowed, projection)?
    } else {
        let mass = crba(model, data, &q[..model.nq])?;
        let momentum = &mass * DVector::from_column_slice(&v[..model.nv]);
        (
            tree.transpose() * (&mass * tree),
            tree.transpose() * momentum,
        )
    };
    let Some(cholesky) = reduced.cholesky() else {
        return Ok(());
    };
    let moved = &allowed * cholesky.solve(&along);
    // The idle coordinates' unit motions are allowed as they are and carry no momentum: their
    // rates stay.
    for (k, value) in moved.iter().enumerate() {
        if !structure.idle.contains(&k) {
            v[k] = *value;
        }
    }
    Ok(())
}

/// Whether the structure's free coordinates and the kept rows together number the coordinates
/// (so that the free coordinates' allowed motions span the allowed motions).
fn parametrised(factored: &Factored, structure: &Structure) -> bool {
    structure.free.len() + factored.len() == factored.columns()
}

/// NᵀMN and NᵀMv for the allowed motions N (`allowed`, over the state's velocities; only the
/// tree's meet M) above `SPARSE_MASS_ABOVE` velocities. With few allowed motions (up to
/// `passes_up_to`: the ladder's two), from one pass over the bodies per motion and one for v
/// (`BodyPasses`), in time linear in the bodies: the mass matrix's storage alone is n² (72 MB
/// on the ladder of 1,000 loops), and its entries between a rung and the beam, a column apart
/// in memory, cost a cache miss each. With many, from the mass matrix over the entries its
/// branches can fill (`mass_times`).
fn large_mechanism_forms(
    model: &Model,
    data: &mut Data,
    q: &[f64],
    v: &[f64],
    allowed: &DMatrix<f64>,
    projection: &mut ProjectionScratch,
) -> Result<(DMatrix<f64>, DVector<f64>), EvalError> {
    let (nv, count) = (model.nv, allowed.ncols());
    let (_, passes_up_to) = projection.mass_layout(model);
    if count < passes_up_to {
        // The allowed motions and v side by side: the last pass is v's.
        let mut columns = DMatrix::zeros(nv, count + 1);
        columns
            .columns_mut(0, count)
            .copy_from(&allowed.rows(0, nv));
        columns.column_mut(count).copy_from_slice(&v[..nv]);
        joint_transforms(model, data, &q[..model.nq])?;
        let passes = projection.passes();
        passes.take(model, data, &columns, count + 1);
        let mut reduced = DMatrix::zeros(count, count);
        for k in 0..count {
            for l in 0..=k {
                let value = passes.form(model, &columns, k, l);
                reduced[(k, l)] = value;
                reduced[(l, k)] = value;
            }
        }
        let along = DVector::from_fn(count, |k, _| passes.form(model, &columns, count, k));
        return Ok((reduced, along));
    }
    let tree = allowed.rows(0, nv);
    let (mass, rows) = projection.mass_storage(model);
    crba_into(model, data, &q[..model.nq], mass)?;
    let mut momentum = DVector::zeros(nv);
    mass_times(mass, rows, &v[..nv], momentum.as_mut_slice());
    let mut mass_tree = DMatrix::zeros(nv, count);
    let mut column = vec![0.0; nv];
    for j in 0..count {
        column
            .iter_mut()
            .zip(tree.column(j).iter())
            .for_each(|(c, t)| *c = *t);
        mass_times(mass, rows, &column, mass_tree.column_mut(j).as_mut_slice());
    }
    Ok((tree.transpose() * mass_tree, tree.transpose() * momentum))
}
