//! The joint-space mass matrix M(q) by composite rigid bodies (Featherstone, "Rigid Body
//! Dynamics Algorithms", 2008, §6.2), in the fixed frame: each body's inertia is moved to the
//! fixed frame once (10 numbers: mass, first moment, rotational inertia about the origin,
//! `RigidInertia`), composites are then plain sums, and every entry is a dot product of a
//! joint's motion column (in the fixed frame) with a composite momentum: no force is carried
//! from joint to joint.
//!
//! Measured against the local-frame form (Featherstone's Table 6.2, Pinocchio's
//! `Convention::LOCAL`: composites summed from the leaves, each moved to its parent's frame, and
//! the force set I_c S of a joint's subtree moved up once per ancestor) on UR5, Panda and Talos:
//! about the same instructions per call, but 1.07 to 1.14 times the CPU time, 1.24 to 1.28 times
//! with the unit axes of URDF joints read as one entry (BENCHMARKS.md, "Peers"). Here the bodies'
//! moves to the fixed frame depend only on their world transforms (a short chain of 3 × 3
//! products), so the processor overlaps them; in the local form each composite waits for all of
//! its children's.

use nalgebra::DMatrix;

use super::{slice, Data};
use crate::dynamics::model::Model;
use crate::kinematics::eval::EvalError;
use crate::spatial::{Motion, RigidInertia, Transform};

/// CRBA's scratch: per body its pose and composite inertia in the fixed frame, per velocity its
/// motion column in the fixed frame.
pub struct MassScratch {
    world_transform: Vec<Transform>,
    composite: Vec<RigidInertia>,
    world_columns: Vec<Motion>,
}

impl MassScratch {
    pub fn new(model: &Model) -> MassScratch {
        MassScratch {
            world_transform: vec![Transform::identity(); model.body_count() + 1],
            composite: vec![RigidInertia::zeros(); model.body_count() + 1],
            world_columns: vec![Motion::zeros(); model.nv],
        }
    }
}

/// The joint-space mass matrix M(q) (composite rigid bodies).
pub fn crba(model: &Model, data: &mut Data, q: &[f64]) -> Result<DMatrix<f64>, EvalError> {
    let mut mass = DMatrix::zeros(model.nv, model.nv);
    crba_into(model, data, q, &mut mass)?;
    Ok(mass)
}

/// The mass matrix written into `mass` (nv × nv). Only the entries between joints on one
/// branch (a joint and its ancestors) are written: the others are zero in every mass matrix,
/// so `mass` must be zero there (a zero matrix, or one this function filled before). Leaves the
/// joint transforms at q in `data` (not the velocities, nor the world poses).
pub fn crba_into(
    model: &Model,
    data: &mut Data,
    q: &[f64],
    mass: &mut DMatrix<f64>,
) -> Result<(), EvalError> {
    // The joints' transforms first: independent of one another, they overlap in the processor.
    for &k in &model.dynamic_joints {
        let joint = &model.joints[k];
        joint.update_transform(slice(q, joint.q_offset, joint.nq()), &mut data.states[k])?;
    }
    crba_after_kinematics(model, data, mass);
    Ok(())
}

/// `crba_into` when `data` already holds the joints' transforms at q (`forward_kinematics`).
pub fn crba_after_kinematics(model: &Model, data: &mut Data, mass: &mut DMatrix<f64>) {
    let MassScratch {
        world_transform,
        composite,
        world_columns,
    } = &mut data.mass_scratch;
    for &k in &model.dynamic_joints {
        let joint = &model.joints[k];
        let state = &data.states[k];
        let (i, parent) = (joint.child, joint.dynamic_parent);
        let world = world_transform[parent] * state.transform;
        world_transform[i] = world;
        let own = &model.dynamic_bodies[i - 1];
        composite[i] = if own.massless {
            RigidInertia::zeros()
        } else {
            own.rigid.to_parent(&world)
        };
        for (r, column) in state.subspace.columns().iter().enumerate() {
            world_columns[joint.v_offset + r] = world.motion_to_parent(column);
        }
    }
    for &k in model.dynamic_joints.iter().rev() {
        let joint = &model.joints[k];
        if joint.dynamic_parent != 0 {
            let child = composite[joint.child];
            composite[joint.dynamic_parent] += child;
        }
    }
    let nv = model.nv;
    let entries = mass.as_mut_slice();
    for &k in &model.dynamic_joints {
        let joint = &model.joints[k];
        let composite = &composite[joint.child];
        for column in joint.v_offset..joint.v_offset + joint.nv() {
            let force = composite.times(&world_columns[column]);
            // Column-major storage; the joint's branch lists its own and its ancestors' velocities.
            for &row in &model.branch_velocities[k] {
                let value = world_columns[row].dot(&force);
                entries[row + column * nv] = value;
                entries[column + row * nv] = value;
            }
        }
    }
    super::add_rotors_to_mass(model, data, mass);
}

/// The rows of each column of `model`'s mass matrix that the composite-rigid-body algorithm
/// writes (`crba_after_kinematics`): the others are zero whatever the state.
pub fn mass_rows(model: &Model) -> Vec<Vec<usize>> {
    let mut rows = vec![Vec::new(); model.nv];
    for &k in &model.dynamic_joints {
        let joint = &model.joints[k];
        for column in joint.v_offset..joint.v_offset + joint.nv() {
            for &row in &model.branch_velocities[k] {
                rows[column].push(row);
                if row != column {
                    rows[row].push(column);
                }
            }
        }
    }
    rows.iter_mut().for_each(|r| {
        r.sort_unstable();
        r.dedup();
    });
    rows
}

/// y = M x over the entries `rows` lists, column after column: the sums of a dense product
/// in the same order, without its products by zero.
pub fn mass_times(mass: &DMatrix<f64>, rows: &[Vec<usize>], x: &[f64], y: &mut [f64]) {
    y.fill(0.0);
    let nv = mass.nrows();
    let entries = mass.as_slice();
    for (column, (rows, &xj)) in rows.iter().zip(x).enumerate() {
        let entries = &entries[column * nv..(column + 1) * nv];
        for &row in rows {
            y[row] += entries[row] * xj;
        }
    }
}
