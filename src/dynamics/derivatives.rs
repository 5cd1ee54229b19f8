//! ∂T/∂q, the derivative of the kinetic energy with respect to the positions at fixed
//! velocities, for the variational integrator. One pass gathers each subtree's momentum h_c; the
//! derivative along coordinate k of joint J (child c) is h_c · ∂v_c/∂q_k, where moving q_k turns
//! the parent's velocity as seen from c (−S_k × Xv_λ) and changes the joint's own velocity.
//! For a spherical or free joint the derivative is left-trivialised: along the motion
//! q · exp(ε e_k) of its group (see `simulate::lie_group`), at fixed body velocity.

use nalgebra::DVector;

use super::algorithms::{forward_kinematics, Data};
use super::joint::JointType;
use super::model::Model;
use crate::kinematics::eval::EvalError;
use crate::spatial::{self, Force, Motion};

pub fn kinetic_energy_gradient(
    model: &Model,
    data: &mut Data,
    q: &[f64],
    v: &[f64],
) -> Result<DVector<f64>, EvalError> {
    forward_kinematics(model, data, q, v)?;
    let n = model.body_count();
    let mut momentum = vec![Force::zeros(); n + 1];
    for (k, joint) in model.joints.iter().enumerate().rev() {
        let body = &model.bodies[joint.child - 1];
        if !body.massless {
            momentum[joint.child] += body.inertia * data.velocity[joint.child];
        }
        if joint.dynamic_parent != 0 {
            let moved = spatial::force_to_parent(&data.states[k].pose, &momentum[joint.child]);
            momentum[joint.dynamic_parent] += moved;
        }
    }
    let mut gradient = DVector::zeros(model.nv);
    for (k, joint) in model.joints.iter().enumerate() {
        let state = &data.states[k];
        let n_joint = joint.nv();
        let parent_seen =
            spatial::motion_to_child(&state.pose, &data.velocity[joint.dynamic_parent]);
        if joint.kind != JointType::Chain {
            // Moving the joint by exp(ε e_c) turns the child by the column S_c in its own frame;
            // its velocity S v stays (S is constant in the child's frame), only the parent's
            // velocity seen from the child turns.
            for c in 0..n_joint {
                let column = state.subspace.column(c);
                let change = -spatial::cross_motion(column, &parent_seen);
                gradient[joint.v_offset + c] = momentum[joint.child].dot(&change);
            }
            continue;
        }
        let rates = &v[joint.v_offset..joint.v_offset + n_joint];
        let coordinates = &q[joint.q_offset..joint.q_offset + n_joint];
        let d = joint.chain.chain_motion(coordinates, None)?.pose;
        for c in 0..n_joint {
            let mut direction = vec![0.0; n_joint];
            direction[c] = 1.0;
            let column = Motion::from_column_slice(state.subspace.column(c).as_slice());
            let base = joint
                .chain
                .velocity_derivative(coordinates, rates, &direction)?;
            let own = if joint.first_on_parent {
                spatial::motion_to_parent(&(joint.on_child * d.inverse()), &base)
                    - spatial::cross_motion(&column, &state.velocity)
            } else {
                -spatial::motion_to_parent(&joint.on_child, &base)
            };
            let change = -spatial::cross_motion(&column, &parent_seen) + own;
            gradient[joint.v_offset + c] = momentum[joint.child].dot(&change);
        }
    }
    Ok(gradient)
}
