//! The regressor of inverse dynamics: RNEA's generalised forces are linear in every body's ten
//! inertial parameters, τ = Y(q, v, a) π + τ₀ (Atkeson, An & Hollerbach, "Estimation of
//! Inertial Parameters of Manipulator Loads and Links", IJRR 5(3), 1986). A body's force
//! I a + v ×* I v is linear in its inertia about its frame's origin, (m, h = m c, J), so each
//! parameter's column is that force for a unit inertia holding only the parameter, carried
//! back to the root as RNEA's pass back carries forces: one pass out (RNEA's own), then per
//! body and parameter one walk to earth.
//!
//! τ₀ holds what does not depend on the bodies' inertias: external forces and the geared
//! rotors' efforts (their inertias are the rotors', not the bodies'). Welded bodies merged into
//! their anchor (`welds`) keep their own parameters, in their own frame: their unit inertias are
//! moved to the anchor's frame, which is linear in them.

use nalgebra::{DMatrix, Matrix3, Vector3};

use super::{rnea_into, Data};
use crate::dynamics::model::Model;
use crate::kinematics::eval::EvalError;
use crate::spatial::{self, Force, RigidInertia};

/// Parameters per body, in the order of [`INERTIAL_PARAMETERS`].
pub const PARAMETERS_PER_BODY: usize = 10;

/// The names of a body's inertial parameters, about the origin of its frame and in its axes:
/// the mass, the first moments m c (kg m), the rotational inertia J about the origin (kg m²;
/// `Ixy` is J's entry, −∫ x y dm).
pub const INERTIAL_PARAMETERS: [&str; PARAMETERS_PER_BODY] = [
    "mass", "mx", "my", "mz", "Ixx", "Ixy", "Ixz", "Iyy", "Iyz", "Izz",
];

/// The inertia holding parameter `p` (of [`INERTIAL_PARAMETERS`]) at 1 and the others at 0:
/// not a physical body, but the force of any inertia is the sum of these times its parameters.
pub fn unit_inertia(p: usize) -> RigidInertia {
    let mut inertia = RigidInertia::zeros();
    match p {
        0 => inertia.mass = 1.0,
        1..=3 => inertia.first[p - 1] = 1.0,
        _ => {
            let (i, j) = [(0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)][p - 4];
            inertia.rotational[(i, j)] = 1.0;
            inertia.rotational[(j, i)] = 1.0;
        }
    }
    inertia
}

/// A body's parameters in the order of [`INERTIAL_PARAMETERS`].
pub fn parameters_of(inertia: &RigidInertia) -> [f64; PARAMETERS_PER_BODY] {
    let (h, j) = (inertia.first, inertia.rotational);
    [
        inertia.mass,
        h.x,
        h.y,
        h.z,
        j[(0, 0)],
        j[(0, 1)],
        j[(0, 2)],
        j[(1, 1)],
        j[(1, 2)],
        j[(2, 2)],
    ]
}

/// The inertia of the parameters `p`, in the order of [`INERTIAL_PARAMETERS`].
pub fn inertia_of(p: &[f64; PARAMETERS_PER_BODY]) -> RigidInertia {
    RigidInertia {
        mass: p[0],
        first: Vector3::new(p[1], p[2], p[3]),
        rotational: Matrix3::new(p[4], p[5], p[6], p[5], p[7], p[8], p[6], p[8], p[9]),
    }
}

/// Every body's parameters (as the model holds them), body 1 first: the π of `Y π`.
pub fn model_parameters(model: &Model) -> Vec<f64> {
    (model.bodies.iter())
        .flat_map(|body| parameters_of(&body.rigid))
        .collect()
}

/// Y(q, v, a): nv rows, one column per body and parameter (column 10 (b − 1) + p for body b and
/// parameter p of [`INERTIAL_PARAMETERS`]), gravity included; `data` is left with RNEA's pass
/// out at (q, v, a) without external forces.
pub fn regressor(
    model: &Model,
    data: &mut Data,
    q: &[f64],
    v: &[f64],
    a: &[f64],
) -> Result<DMatrix<f64>, EvalError> {
    let n = model.body_count();
    let external = vec![Force::zeros(); n + 1];
    let mut tau = nalgebra::DVector::zeros(model.nv);
    rnea_into(model, data, q, v, a, &external, &mut tau)?;
    let mut moving = vec![false; model.joints.len()];
    for &k in &model.dynamic_joints {
        moving[k] = true;
    }
    let mut y = DMatrix::zeros(model.nv, PARAMETERS_PER_BODY * n);
    let mut projected = [0.0; 6];
    for body in 1..=n {
        let joint = &model.joints[body - 1];
        // A merged body moves with its anchor, the body its joint's transform is relative to.
        let anchor = if moving[body - 1] {
            body
        } else {
            joint.dynamic_parent
        };
        if anchor == 0 {
            continue;
        }
        let (velocity, acceleration) = (data.velocity[anchor], data.acceleration[anchor]);
        for p in 0..PARAMETERS_PER_BODY {
            let inertia = unit_inertia(p).to_parent(&model.anchor_offsets[body]);
            let momentum = inertia.times(&velocity);
            let mut force =
                inertia.times(&acceleration) + spatial::cross_force(&velocity, &momentum);
            let column = PARAMETERS_PER_BODY * (body - 1) + p;
            let mut child = anchor;
            while child != 0 {
                let k = child - 1;
                let (joint, state) = (&model.joints[k], &data.states[k]);
                let count = joint.nv();
                state.subspace.project(&force, &mut projected[..count]);
                for (r, value) in projected[..count].iter().enumerate() {
                    y[(joint.v_offset + r, column)] = *value;
                }
                force = state.transform.force_to_parent(&force);
                child = joint.dynamic_parent;
            }
        }
    }
    Ok(y)
}
