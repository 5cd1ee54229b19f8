//! The recursive algorithms in planar vectors, each the spatial one of `algorithms` with
//! three rows instead of six (Featherstone 2008, §2.16): the kinematics of the joints, inverse
//! dynamics (RNEA, its pass out and its pass back), the mass matrix (CRBA, in the fixed
//! plane's frame) and forward dynamics (ABA). Every joint has one velocity or none, so the
//! articulated-body algorithm divides by a number where the spatial one inverts a matrix.

use nalgebra::{DMatrix, DVector};

use super::algebra::{
    cross_force, cross_motion, PlanarArticulated, PlanarForce, PlanarInertia, PlanarMotion,
    PlanarTransform,
};
use super::model::PlanarModel;
use crate::dynamics::algorithms::DynamicsError;
use crate::dynamics::model::Model;
use crate::spatial::Force;

/// Scratch of the planar algorithms, per body (index = body number, 0 is earth) and per
/// velocity; made once for a model (`PlanarData::new`).
#[derive(Clone, Debug)]
pub struct PlanarData {
    /// Per joint of the model (its index), the child's planar frame in its parent's.
    pub transforms: Vec<PlanarTransform>,
    /// The bodies' planar frames in the fixed plane's.
    pub world: Vec<PlanarTransform>,
    pub velocity: Vec<PlanarMotion>,
    /// The velocity-product accelerations vᵢ × Sᵢq̇ᵢ.
    pub coriolis: Vec<PlanarMotion>,
    pub acceleration: Vec<PlanarMotion>,
    /// RNEA: each body's force beyond the external ones, then (pass back) with its subtree's.
    pub force: Vec<PlanarForce>,
    /// The external forces in the bodies' planar frames.
    pub external: Vec<PlanarForce>,
    /// CRBA: composite inertias and the velocities' motions, in the fixed plane's frame.
    composite: Vec<PlanarInertia>,
    pub world_columns: Vec<PlanarMotion>,
    /// ABA: articulated inertias and bias forces, U = I S, 1 / (Sᵀ U) and u = τ − Sᵀ p.
    articulated: Vec<PlanarArticulated>,
    bias: Vec<PlanarForce>,
    u: Vec<PlanarForce>,
    d_inverse: Vec<f64>,
    u_scalar: Vec<f64>,
    /// `mass_solve_after_aba`'s passes: the forces handed inward, u, and the accelerations.
    unit_bias: Vec<PlanarForce>,
    unit_u: Vec<f64>,
    unit_acceleration: Vec<PlanarMotion>,
}

impl PlanarData {
    pub fn new(model: &Model) -> PlanarData {
        let (bodies, joints) = (model.body_count() + 1, model.joints.len());
        PlanarData {
            transforms: vec![PlanarTransform::identity(); joints],
            world: vec![PlanarTransform::identity(); bodies],
            velocity: vec![PlanarMotion::zeros(); bodies],
            coriolis: vec![PlanarMotion::zeros(); bodies],
            acceleration: vec![PlanarMotion::zeros(); bodies],
            force: vec![PlanarForce::zeros(); bodies],
            external: vec![PlanarForce::zeros(); bodies],
            composite: vec![PlanarInertia::zeros(); bodies],
            world_columns: vec![PlanarMotion::zeros(); model.nv],
            articulated: vec![PlanarArticulated::zeros(); bodies],
            bias: vec![PlanarForce::zeros(); bodies],
            u: vec![PlanarForce::zeros(); bodies],
            d_inverse: vec![0.0; bodies],
            u_scalar: vec![0.0; bodies],
            unit_bias: vec![PlanarForce::zeros(); bodies],
            unit_u: vec![0.0; bodies],
            unit_acceleration: vec![PlanarMotion::zeros(); bodies],
        }
    }

    /// The external forces (spatial, in the bodies' frames) in the bodies' planar frames.
    pub fn set_external(&mut self, planar: &PlanarModel, external: &[Force]) {
        for joint in &planar.joints {
            let i = joint.child;
            self.external[i] = planar.planar_force(i, &external[i]);
        }
    }
}

/// The joints' transforms and the bodies' planar poses in the fixed plane, velocities and
/// velocity-product accelerations vᵢ × Sᵢq̇ᵢ at (q, v). With `for_rows`, in the same pass,
/// what the loops' rows read (`loops::planar_rows`): the bodies' accelerations at zero joint
/// accelerations without gravity in `acceleration`, and each velocity's motion in the fixed
/// plane's frame in `world_columns`.
pub fn kinematics(
    planar: &PlanarModel,
    data: &mut PlanarData,
    (q, v): (&[f64], &[f64]),
    for_rows: bool,
) {
    for joint in &planar.joints {
        let (i, parent) = (joint.child, joint.parent);
        let x = joint.transform(q.get(joint.q_offset).copied().unwrap_or(0.0));
        data.transforms[joint.index] = x;
        data.world[i] = data.world[parent] * x;
        let own = match joint.nv() {
            0 => PlanarMotion::zeros(),
            _ => joint.column * v[joint.v_offset],
        };
        data.velocity[i] = x.motion_to_child(&data.velocity[parent]) + own;
        data.coriolis[i] = cross_motion(&data.velocity[i], &own);
        if for_rows {
            data.acceleration[i] = x.motion_to_child(&data.acceleration[parent]) + data.coriolis[i];
            if joint.nv() == 1 {
                data.world_columns[joint.v_offset] = data.world[i].motion_to_parent(&joint.column);
            }
        }
    }
}

/// RNEA's pass out after `kinematics`: each body's acceleration under the joint accelerations
/// `a` and gravity, and in `data.force` the force it needs beyond the external one,
/// I aᵢ + vᵢ × I vᵢ − fᵢ (`data.external`).
pub fn rnea_forward(planar: &PlanarModel, data: &mut PlanarData, a: &[f64]) {
    for joint in &planar.joints {
        let (i, parent) = (joint.child, joint.parent);
        let parent_acceleration = match parent {
            0 => planar.base_acceleration,
            _ => data.acceleration[parent],
        };
        let own = match joint.nv() {
            0 => PlanarMotion::zeros(),
            _ => joint.column * a[joint.v_offset],
        };
        data.acceleration[i] = data.transforms[joint.index].motion_to_child(&parent_acceleration)
            + own
            + data.coriolis[i];
        data.force[i] = if planar.massless[i - 1] {
            -data.external[i]
        } else {
            let inertia = &planar.bodies[i - 1];
            let momentum = inertia.times(&data.velocity[i]);
            inertia.times(&data.acceleration[i]) + cross_force(&data.velocity[i], &momentum)
                - data.external[i]
        };
    }
}

/// RNEA's pass back: the generalised forces `tau` (length nv) from the forces `rnea_forward`
/// left in `data.force`, which it accumulates from child to parent.
pub fn rnea_backward(planar: &PlanarModel, data: &mut PlanarData, tau: &mut DVector<f64>) {
    for joint in planar.joints.iter().rev() {
        let (i, parent) = (joint.child, joint.parent);
        if joint.nv() == 1 {
            tau[joint.v_offset] = joint.column.dot(&data.force[i]);
        }
        if parent != 0 {
            let transmitted = data.transforms[joint.index].force_to_parent(&data.force[i]);
            data.force[parent] += transmitted;
        }
    }
}

/// The mass matrix into `mass` (nv × nv) after `kinematics`, by composite rigid bodies in the
/// fixed plane's frame; only the entries between joints on one branch are written (as
/// `algorithms::crba_after_kinematics`).
pub fn crba(model: &Model, planar: &PlanarModel, data: &mut PlanarData, mass: &mut DMatrix<f64>) {
    for joint in &planar.joints {
        let i = joint.child;
        let world = data.world[i];
        data.composite[i] = match planar.massless[i - 1] {
            true => PlanarInertia::zeros(),
            false => planar.bodies[i - 1].to_parent(&world),
        };
        if joint.nv() == 1 {
            data.world_columns[joint.v_offset] = world.motion_to_parent(&joint.column);
        }
    }
    for joint in planar.joints.iter().rev() {
        if joint.parent != 0 {
            let child = data.composite[joint.child];
            data.composite[joint.parent] += child;
        }
    }
    let nv = model.nv;
    let entries = mass.as_mut_slice();
    for joint in planar.joints.iter().filter(|j| j.nv() == 1) {
        let column = joint.v_offset;
        let force = data.composite[joint.child].times(&data.world_columns[column]);
        for &row in model.branch_velocities(joint.index) {
            let value = data.world_columns[row].dot(&force);
            entries[row + column * nv] = value;
            entries[column + row * nv] = value;
        }
    }
}

/// The motion of every body (in its planar frame) when the joints move with velocities `x`
/// from the configuration whose transforms `data` holds (as `algorithms::body_motions`).
pub fn body_motions(
    planar: &PlanarModel,
    data: &PlanarData,
    x: &[f64],
    motions: &mut [PlanarMotion],
) {
    motions[0] = PlanarMotion::zeros();
    for joint in &planar.joints {
        let (i, parent) = (joint.child, joint.parent);
        let own = match joint.nv() {
            0 => PlanarMotion::zeros(),
            _ => joint.column * x[joint.v_offset],
        };
        motions[i] = data.transforms[joint.index].motion_to_child(&motions[parent]) + own;
    }
}

/// Forward dynamics after `kinematics` and `PlanarData::set_external`: the accelerations under
/// the generalised forces `tau` (three passes; Featherstone 2008, Table 7.1).
pub fn aba(
    planar: &PlanarModel,
    data: &mut PlanarData,
    tau: &[f64],
    accelerations: &mut DVector<f64>,
) -> Result<(), DynamicsError> {
    for joint in &planar.joints {
        let i = joint.child;
        let inertia = &planar.bodies[i - 1];
        data.articulated[i] = inertia.matrix();
        data.bias[i] = if planar.massless[i - 1] {
            -data.external[i]
        } else {
            cross_force(&data.velocity[i], &inertia.times(&data.velocity[i])) - data.external[i]
        };
    }
    for joint in planar.joints.iter().rev() {
        let (i, parent) = (joint.child, joint.parent);
        let inertia = data.articulated[i];
        // Ia − U D⁻¹ Uᵀ and pa + Ia c + U D⁻¹ u handed to the parent.
        let mut reduced = inertia;
        let mut correction = PlanarForce::zeros();
        if joint.nv() == 1 {
            let s = joint.column;
            let u = inertia * s;
            let d = s.dot(&u);
            if !(d.abs() > 1e-300 && d.is_finite()) {
                return Err(DynamicsError::Singular {
                    joint: joint.index,
                    body: i,
                });
            }
            let (d_inverse, u_scalar) = (1.0 / d, tau[joint.v_offset] - s.dot(&data.bias[i]));
            reduced -= u * u.transpose() * d_inverse;
            correction = u * (d_inverse * u_scalar);
            data.u[i] = u;
            data.d_inverse[i] = d_inverse;
            data.u_scalar[i] = u_scalar;
        }
        if parent != 0 {
            let handed = data.bias[i] + reduced * data.coriolis[i] + correction;
            let x = &data.transforms[joint.index];
            data.articulated[parent] += x.inertia_to_parent(&reduced);
            data.bias[parent] += x.force_to_parent(&handed);
        }
    }
    for joint in &planar.joints {
        let (i, parent) = (joint.child, joint.parent);
        let parent_acceleration = match parent {
            0 => planar.base_acceleration,
            _ => data.acceleration[parent],
        };
        let a =
            data.transforms[joint.index].motion_to_child(&parent_acceleration) + data.coriolis[i];
        data.acceleration[i] = if joint.nv() == 1 {
            let q_dd = data.d_inverse[i] * (data.u_scalar[i] - data.u[i].dot(&a));
            accelerations[joint.v_offset] = q_dd;
            a + joint.column * q_dd
        } else {
            a
        };
    }
    Ok(())
}

/// x = M⁻¹ τ for the generalised forces `tau` (length nv) after `aba` at the same
/// configuration, into `x`: ABA's passes back and out again on the articulated inertias `aba`
/// left (its U = I S and D⁻¹), without velocities, gravity or external forces, so that each
/// solve costs two passes over the joints, not a factorisation of M (Featherstone 2008, §7.3
/// and §8.x, the constraint forces' responses by ABA).
pub fn mass_solve_after_aba(
    planar: &PlanarModel,
    data: &mut PlanarData,
    tau: &[f64],
    x: &mut [f64],
) {
    for joint in &planar.joints {
        data.unit_bias[joint.child] = PlanarForce::zeros();
    }
    for joint in planar.joints.iter().rev() {
        let (i, parent) = (joint.child, joint.parent);
        let mut handed = data.unit_bias[i];
        if joint.nv() == 1 {
            let u = tau[joint.v_offset] - joint.column.dot(&data.unit_bias[i]);
            data.unit_u[i] = u;
            handed += data.u[i] * (data.d_inverse[i] * u);
        }
        if parent != 0 {
            let transmitted = data.transforms[joint.index].force_to_parent(&handed);
            data.unit_bias[parent] += transmitted;
        }
    }
    for joint in &planar.joints {
        let (i, parent) = (joint.child, joint.parent);
        let a = match parent {
            0 => PlanarMotion::zeros(),
            _ => data.transforms[joint.index].motion_to_child(&data.unit_acceleration[parent]),
        };
        data.unit_acceleration[i] = if joint.nv() == 1 {
            let q_dd = data.d_inverse[i] * (data.unit_u[i] - data.u[i].dot(&a));
            x[joint.v_offset] = q_dd;
            a + joint.column * q_dd
        } else {
            a
        };
    }
}
