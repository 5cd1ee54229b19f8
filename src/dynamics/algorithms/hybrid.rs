//! Hybrid dynamics: the articulated-body algorithm with some joints' accelerations known
//! (Featherstone, *Rigid Body Dynamics Algorithms*, 2008, §9.2). A joint whose acceleration is
//! known (`known[k]`, here the joints of fully driven subtrees, `driven_subtrees`) has no
//! unknown to solve: the pass in hands its whole articulated inertia Iᴬ and the bias of its
//! known motion pᴬ + Iᴬ (c + S q̈) to its parent, the pass out gives its body the acceleration
//! X a_parent + c + S q̈, and its generalised force is then Sᵀ (Iᴬ a + pᴬ): for a subtree whose
//! joints are all known, Iᴬ is its rigid composite inertia and this is its inverse dynamics.
//! The other joints are the articulated-body algorithm's, which sees the known subtrees through
//! the inertia and force they hand it.

use nalgebra::DVector;

use super::{
    aba_backward_step, aba_body_terms, aba_forward_step, base_acceleration, joint_motions, slice,
    Data, DynamicsError, JointAcceleration,
};
use crate::dynamics::model::Model;
use crate::spatial::{Force, Motion};

/// Accelerations with the known ones given: `accelerations` holds the known joints' on entry
/// (the other entries are written), under the generalised forces `tau` and the bodies' external
/// forces, `data` holding the forward kinematics of the state. `efforts` receives, at each
/// known velocity, the generalised force that imposes its acceleration beyond `tau` (a drive's
/// effort); its other entries are left as they were.
pub fn hybrid_after_kinematics(
    model: &Model,
    data: &mut Data,
    known: &[bool],
    (tau, external): (&[f64], &[Force]),
    accelerations: &mut DVector<f64>,
    efforts: &mut [f64],
) -> Result<(), DynamicsError> {
    let base = base_acceleration(model);
    hybrid(model, data, known, (tau, external), base, accelerations)?;
    known_efforts(model, data, known, tau, efforts);
    Ok(())
}

/// The least change of the velocities, in the kinetic metric, that changes each known one by
/// its entry of `change` (the others are written): the free velocities' change −M_ff⁻¹ M_fk Δ_k,
/// which is the hybrid dynamics at q at rest, with no force and no gravity, whose known
/// accelerations are the change. Minimising Δᵀ M Δ with the known entries fixed gives
/// M_ff Δ_f + M_fk Δ_k = 0: the free rows of M Δ vanish, as the free joints' equations do
/// under no force. `rest` is a zero velocity per state velocity and `no_external` a zero
/// force per body; the forward kinematics in `data` are left at rest.
pub fn least_change(
    model: &Model,
    data: &mut Data,
    known: &[bool],
    (q, rest, no_external): (&[f64], &[f64], &[Force]),
    change: &mut DVector<f64>,
) -> Result<(), DynamicsError> {
    joint_motions(model, data, q, rest)?;
    hybrid(
        model,
        data,
        known,
        (rest, no_external),
        Motion::zeros(),
        change,
    )
}

/// The three passes, the base given the acceleration `base`.
fn hybrid(
    model: &Model,
    data: &mut Data,
    known: &[bool],
    (tau, external): (&[f64], &[Force]),
    base: Motion,
    accelerations: &mut DVector<f64>,
) -> Result<(), DynamicsError> {
    aba_body_terms(model, data, external);
    for &k in model.dynamic_joints.iter().rev() {
        let joint = &model.joints[k];
        if !known[k] {
            aba_backward_step(model, data, k, slice(tau, joint.v_offset, joint.nv()))?;
            continue;
        }
        let (i, parent) = (joint.child, joint.dynamic_parent);
        if parent != 0 {
            let state = &data.states[k];
            let known_motion = data.coriolis[i]
                + state
                    .subspace
                    .apply(slice(accelerations.as_slice(), joint.v_offset, joint.nv()));
            let inertia = data.articulated[i];
            let handed = data.bias[i] + inertia * known_motion;
            data.articulated[parent] += state.transform.inertia_to_parent(&inertia);
            data.bias[parent] += state.transform.force_to_parent(&handed);
        }
    }
    for &k in &model.dynamic_joints {
        let joint_acceleration = if known[k] {
            JointAcceleration::Known
        } else {
            JointAcceleration::Solved
        };
        aba_forward_step(model, data, k, &base, accelerations, joint_acceleration);
    }
    Ok(())
}

/// At each known velocity, Sᵀ (Iᴬ a + pᴬ) less its applied generalised force, from the passes
/// `hybrid` left in `data`.
fn known_efforts(model: &Model, data: &Data, known: &[bool], tau: &[f64], efforts: &mut [f64]) {
    for &k in &model.dynamic_joints {
        if !known[k] {
            continue;
        }
        let joint = &model.joints[k];
        let i = joint.child;
        let force = data.articulated[i] * data.acceleration[i] + data.bias[i];
        let range = joint.v_offset..joint.v_offset + joint.nv();
        data.states[k]
            .subspace
            .project(&force, &mut efforts[range.clone()]);
        for velocity in range {
            efforts[velocity] -= tau[velocity];
        }
    }
}
