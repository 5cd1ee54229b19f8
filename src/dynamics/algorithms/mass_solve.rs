//! x = M⁻¹τ for generalised forces τ after the articulated-body algorithm at the same
//! configuration, on the articulated inertias it left: its pass back and pass out again without
//! velocities, gravity or external forces (Featherstone, *Rigid Body Dynamics Algorithms*,
//! 2008, §7.3; the responses to constraint forces by ABA, §8.5). Each solve costs two passes
//! over the joints, not a factorisation of M: the range-space method of the loops
//! (`loops::range_space`) takes one per kept row.

use nalgebra::Vector6;

use super::Data;
use crate::dynamics::model::Model;
use crate::spatial::{Force, Motion};

/// The passes' storage per body: the forces handed inward, u = τ − Sᵀp per joint, and the
/// accelerations.
#[derive(Clone, Debug, Default)]
pub struct MassSolveScratch {
    handed: Vec<Force>,
    u: Vec<Vector6<f64>>,
    acceleration: Vec<Motion>,
}

/// x = M⁻¹τ into `x` (the tree's velocities) after `aba_after_kinematics` (or `aba_into`) at
/// this configuration, whose U = I S and D⁻¹ per joint `data` holds. Not for a model with
/// geared rotors, whose joints ABA takes by other steps.
pub fn mass_solve_after_aba(
    model: &Model,
    data: &Data,
    tau: &[f64],
    x: &mut [f64],
    scratch: &mut MassSolveScratch,
) {
    debug_assert!(
        model.rotors.is_empty(),
        "ABA's rotor steps are not taken here"
    );
    let bodies = data.velocity.len();
    scratch.handed.resize(bodies, Force::zeros());
    scratch.u.resize(bodies, Vector6::zeros());
    scratch.acceleration.resize(bodies, Motion::zeros());
    for &k in &model.dynamic_joints {
        scratch.handed[model.joints[k].child] = Force::zeros();
    }
    for &k in model.dynamic_joints.iter().rev() {
        let joint = &model.joints[k];
        let (i, parent) = (joint.child, joint.dynamic_parent);
        let state = &data.states[k];
        let n = joint.nv();
        let mut handed = scratch.handed[i];
        for c in 0..n {
            scratch.u[i][c] = tau[joint.v_offset + c] - state.subspace.column(c).dot(&handed);
        }
        // p + U D⁻¹ u, with p the forces handed to this body by its children.
        for c in 0..n {
            let w: Force = (0..n).fold(Force::zeros(), |sum, r| {
                sum + data.u[i][r] * data.d_inverse[i][(r, c)]
            });
            handed += w * scratch.u[i][c];
        }
        if parent != 0 {
            let transmitted = state.transform.force_to_parent(&handed);
            scratch.handed[parent] += transmitted;
        }
    }
    for &k in &model.dynamic_joints {
        let joint = &model.joints[k];
        let (i, parent) = (joint.child, joint.dynamic_parent);
        let state = &data.states[k];
        let n = joint.nv();
        let a = match parent {
            0 => Motion::zeros(),
            _ => state
                .transform
                .motion_to_child(&scratch.acceleration[parent]),
        };
        let mut rhs = Vector6::zeros();
        for c in 0..n {
            rhs[c] = scratch.u[i][c] - data.u[i][c].dot(&a);
        }
        let out = &mut x[joint.v_offset..joint.v_offset + n];
        for (r, o) in out.iter_mut().enumerate() {
            *o = (0..n).map(|c| data.d_inverse[i][(r, c)] * rhs[c]).sum();
        }
        scratch.acceleration[i] = a + state.subspace.apply(out);
    }
}
