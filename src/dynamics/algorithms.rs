//! The recursive algorithms, each `algorithm(&model, &mut data, ...)`: forward kinematics and
//! velocities, inverse dynamics (RNEA: one pass out, one back), the mass matrix (CRBA) and
//! forward dynamics (ABA: three passes). Bodies without mass cost nothing.

use nalgebra::{DMatrix, DVector};

use super::joint::JointState;
use super::model::Model;
use super::spatial::{self, Force, Inertia, Motion, Pose};
use crate::kinematics::eval::EvalError;

/// Scratch space for the algorithms; `Data::new(&model)` once, reuse for every call.
pub struct Data {
    pub states: Vec<JointState>,
    /// World pose, velocity and acceleration of body i at index i (0 is earth), in body frame.
    pub world: Vec<Pose>,
    pub velocity: Vec<Motion>,
    pub acceleration: Vec<Motion>,
    pub force: Vec<Force>,
    composite: Vec<Inertia>,
    articulated: Vec<Inertia>,
    bias: Vec<Force>,
    coriolis: Vec<Motion>,
    u: Vec<DMatrix<f64>>,
    d_inverse: Vec<DMatrix<f64>>,
    u_vector: Vec<DVector<f64>>,
}

#[derive(Clone, Debug, PartialEq)]
pub enum DynamicsError {
    Evaluation(EvalError),
    /// The articulated inertia of a joint is singular: the bodies it carries have no inertia
    /// along some of its motions (joint index, body number).
    Singular { joint: usize, body: usize },
}

impl From<EvalError> for DynamicsError {
    fn from(e: EvalError) -> Self {
        DynamicsError::Evaluation(e)
    }
}

impl Data {
    pub fn new(model: &Model) -> Data {
        let n = model.body_count();
        Data {
            states: Vec::with_capacity(n),
            world: vec![Pose::identity(); n + 1],
            velocity: vec![Motion::zeros(); n + 1],
            acceleration: vec![Motion::zeros(); n + 1],
            force: vec![Force::zeros(); n + 1],
            composite: vec![Inertia::zeros(); n + 1],
            articulated: vec![Inertia::zeros(); n + 1],
            bias: vec![Force::zeros(); n + 1],
            coriolis: vec![Motion::zeros(); n + 1],
            u: vec![DMatrix::zeros(0, 0); n + 1],
            d_inverse: vec![DMatrix::zeros(0, 0); n + 1],
            u_vector: vec![DVector::zeros(0); n + 1],
        }
    }
}

fn slice(values: &[f64], offset: usize, count: usize) -> &[f64] {
    &values[offset..offset + count]
}

/// Joint states, world poses and body velocities at (q, v).
pub fn forward_kinematics(model: &Model, data: &mut Data, q: &[f64], v: &[f64]) -> Result<(), EvalError> {
    data.states.clear();
    for joint in &model.joints {
        let state = joint.state(slice(q, joint.q_offset, joint.nq()), slice(v, joint.v_offset, joint.nv()), &model.unknowns)?;
        let (i, parent) = (joint.child, joint.parent);
        data.world[i] = data.world[parent] * state.pose;
        data.velocity[i] = spatial::motion_to_child(&state.pose, &data.velocity[parent]) + state.velocity;
        data.coriolis[i] = state.bias + spatial::cross_motion(&data.velocity[i], &state.velocity);
        data.states.push(state);
    }
    Ok(())
}

/// Fills `data.acceleration` with the bodies' accelerations when every joint acceleration is
/// zero (the velocity-product terms alone); `data` must hold the forward kinematics of (q, v).
pub fn bias_accelerations(model: &Model, data: &mut Data) {
    for (k, joint) in model.joints.iter().enumerate() {
        let (i, parent) = (joint.child, joint.parent);
        data.acceleration[i] = spatial::motion_to_child(&data.states[k].pose, &data.acceleration[parent]) + data.coriolis[i];
    }
}

/// Inverse dynamics: the generalised forces that give accelerations `a` at (q, v) under the
/// external forces `external` (one per body, in its frame; index 0 unused).
pub fn rnea(model: &Model, data: &mut Data, q: &[f64], v: &[f64], a: &[f64], external: &[Force]) -> Result<DVector<f64>, EvalError> {
    forward_kinematics(model, data, q, v)?;
    for (k, joint) in model.joints.iter().enumerate() {
        let (i, parent) = (joint.child, joint.parent);
        let state = &data.states[k];
        let joint_acceleration = &state.subspace * DVector::from_column_slice(slice(a, joint.v_offset, joint.nv()));
        data.acceleration[i] = spatial::motion_to_child(&state.pose, &data.acceleration[parent])
            + Motion::from_column_slice(joint_acceleration.as_slice())
            + data.coriolis[i];
        let body = &model.bodies[i - 1];
        data.force[i] = if body.massless {
            -external[i]
        } else {
            let momentum = body.inertia * data.velocity[i];
            body.inertia * data.acceleration[i] + spatial::cross_force(&data.velocity[i], &momentum) - external[i]
        };
    }
    let mut tau = DVector::zeros(model.nv);
    for (k, joint) in model.joints.iter().enumerate().rev() {
        let (i, parent) = (joint.child, joint.parent);
        let state = &data.states[k];
        let generalised = state.subspace.transpose() * DVector::from_column_slice(data.force[i].as_slice());
        tau.rows_mut(joint.v_offset, joint.nv()).copy_from(&generalised);
        if parent != 0 {
            let transmitted = spatial::force_to_parent(&state.pose, &data.force[i]);
            data.force[parent] += transmitted;
        }
    }
    Ok(tau)
}

/// The joint-space mass matrix M(q) (composite rigid bodies).
pub fn crba(model: &Model, data: &mut Data, q: &[f64]) -> Result<DMatrix<f64>, EvalError> {
    let zero_v = vec![0.0; model.nv];
    forward_kinematics(model, data, q, &zero_v)?;
    for (i, body) in model.bodies.iter().enumerate() {
        data.composite[i + 1] = body.inertia;
    }
    for (k, joint) in model.joints.iter().enumerate().rev() {
        if joint.parent != 0 && data.composite[joint.child] != Inertia::zeros() {
            let moved = spatial::inertia_to_parent(&data.states[k].pose, &data.composite[joint.child]);
            data.composite[joint.parent] += moved;
        }
    }
    let mut mass = DMatrix::zeros(model.nv, model.nv);
    for (k, joint) in model.joints.iter().enumerate() {
        let subspace = &data.states[k].subspace;
        let mut forces = DMatrix::from_fn(6, joint.nv(), |r, c| (data.composite[joint.child] * subspace.column(c))[r]);
        let block = subspace.transpose() * &forces;
        mass.view_mut((joint.v_offset, joint.v_offset), (joint.nv(), joint.nv())).copy_from(&block);
        let mut j = k;
        while model.joints[j].parent != 0 {
            for c in 0..forces.ncols() {
                let f = Force::from_column_slice(forces.column(c).as_slice());
                forces.set_column(c, &spatial::force_to_parent(&data.states[j].pose, &f));
            }
            j = model.joints[j].parent - 1;
            let ancestor = &model.joints[j];
            let block = data.states[j].subspace.transpose() * &forces;
            mass.view_mut((ancestor.v_offset, joint.v_offset), (ancestor.nv(), joint.nv())).copy_from(&block);
            mass.view_mut((joint.v_offset, ancestor.v_offset), (joint.nv(), ancestor.nv())).copy_from(&block.transpose());
        }
    }
    Ok(mass)
}

/// Forward dynamics: the accelerations under generalised forces `tau` and external forces.
pub fn aba(model: &Model, data: &mut Data, q: &[f64], v: &[f64], tau: &[f64], external: &[Force]) -> Result<DVector<f64>, DynamicsError> {
    forward_kinematics(model, data, q, v)?;
    for (i, body) in model.bodies.iter().enumerate() {
        let i = i + 1;
        data.articulated[i] = body.inertia;
        data.bias[i] = if body.massless {
            -external[i]
        } else {
            spatial::cross_force(&data.velocity[i], &(body.inertia * data.velocity[i])) - external[i]
        };
    }
    for (k, joint) in model.joints.iter().enumerate().rev() {
        let (i, parent) = (joint.child, joint.parent);
        let subspace = &data.states[k].subspace;
        let inertia = data.articulated[i];
        let u = DMatrix::from_fn(6, joint.nv(), |r, c| (inertia * subspace.column(c))[r]);
        let d = subspace.transpose() * &u;
        let d_inverse = d.clone().try_inverse().filter(|inv| inv.iter().all(|x| x.is_finite()) && d.determinant().abs() > 1e-300);
        let Some(d_inverse) = d_inverse else { return Err(DynamicsError::Singular { joint: k, body: i }) };
        let u_vector = DVector::from_column_slice(slice(tau, joint.v_offset, joint.nv()))
            - subspace.transpose() * DVector::from_column_slice(data.bias[i].as_slice());
        if parent != 0 {
            let ud = &u * &d_inverse;
            let reduced = inertia - Inertia::from_fn(|r, c| (&ud * u.transpose())[(r, c)]);
            let correction = &ud * &u_vector;
            let bias = data.bias[i] + reduced * data.coriolis[i] + Force::from_column_slice(correction.as_slice());
            let pose = data.states[k].pose;
            data.articulated[parent] += spatial::inertia_to_parent(&pose, &reduced);
            data.bias[parent] += spatial::force_to_parent(&pose, &bias);
        }
        data.u[i] = u;
        data.d_inverse[i] = d_inverse;
        data.u_vector[i] = u_vector;
    }
    let mut accelerations = DVector::zeros(model.nv);
    for (k, joint) in model.joints.iter().enumerate() {
        let (i, parent) = (joint.child, joint.parent);
        let state = &data.states[k];
        let a = spatial::motion_to_child(&state.pose, &data.acceleration[parent]) + data.coriolis[i];
        let qdd = &data.d_inverse[i] * (&data.u_vector[i] - data.u[i].transpose() * DVector::from_column_slice(a.as_slice()));
        data.acceleration[i] = a + Motion::from_column_slice((&state.subspace * &qdd).as_slice());
        accelerations.rows_mut(joint.v_offset, joint.nv()).copy_from(&qdd);
    }
    Ok(accelerations)
}
