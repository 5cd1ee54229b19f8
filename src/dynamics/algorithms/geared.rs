//! Geared rotors (see `dynamics::rotors`) in the recursive algorithms, as methods of `Data`:
//! their J w wᵀ in the mass matrix (CRBA), their torques in inverse dynamics (RNEA) and their
//! terms in the articulated-body algorithm (ABA). Their spin and its energy are in `algorithms`.
//!
//! In ABA a rotor is a second body moved by its joint's coordinate: carried by a body F (the
//! joint's parent, or its child when the join's first frame is on the child), with velocity
//! v_R = v_F + n q̇ e (e = (ε, 0) its axis as a motion in F's frame) and, its mass being F's,
//! the inertia I_R = J e eᵀ. The joint then moves two bodies, its child C and the rotor R, and
//! the articulated-body recursion applies to the pair as to one body of stacked velocity
//! (Featherstone, Rigid Body Dynamics Algorithms, 2008, §7.3, with the joint's motion subspace
//! stacked over the two bodies; Jain, Robot and Multibody Dynamics, 2011, treats geared motors
//! the same way): with S_R the rotor's motion per unit q̇ in F's frame (n e when F is the
//! parent, S + n e when F is the child), U = (I_C S, I_R S_R), D = Sᵀ I_C S + S_Rᵀ I_R S_R,
//! u = τ − Sᵀ p_C − S_Rᵀ p_R, and the parent receives the pair's articulated inertia and bias
//! reduced by U D⁻¹ Uᵀ and U D⁻¹ u, both bodies' terms moved to its frame.

use nalgebra::{DMatrix, Vector3};

use super::{
    angular, body_motions, joint_rate, pure_moment, rotor_spin, spin, Data, DynamicsError,
};
use crate::dynamics::model::Model;
use crate::dynamics::rotors::Rotor;
use crate::spatial::{self, constant, Inertia, Motion, Real};

/// The rotor's axis as a motion of its carrier, e = (ε, 0).
fn axis_motion<T: Real>(rotor: &Rotor) -> Motion<T> {
    spatial::twist(rotor.axis.cast(), Vector3::zeros())
}

/// The rotor's inertia as a spatial inertia of its carrier, I_R = J e eᵀ: the moment of
/// inertia J about its axis alone (its mass and transverse inertia are the carrier's), the
/// same about any point of the carrier since it has no mass.
fn rotor_inertia<T: Real>(rotor: &Rotor) -> Inertia<T> {
    let e = axis_motion::<T>(rotor);
    e * e.transpose() * constant::<T>(rotor.inertia)
}

impl Data {
    /// Adds the rotors' J w wᵀ to the mass matrix, `data` holding the joint transforms at q; w is
    /// the rotor's spin rate per unit velocity, found by moving each velocity alone (in `data`'s
    /// rotor scratch: nothing is allocated).
    pub(super) fn add_rotor_inertias(&mut self, model: &Model, mass: &mut DMatrix<f64>) {
        let data = self;
        if model.rotors.is_empty() {
            return;
        }
        let mut motions = std::mem::take(&mut data.rotor_motions);
        for j in 0..model.nv {
            data.rotor_unit[j] = 1.0;
            body_motions(model, data, &data.rotor_unit, &mut motions);
            data.rotor_unit[j] = 0.0;
            for (r, rotor) in model.rotors.iter().enumerate() {
                let rate = if j == rotor.velocity { 1.0 } else { 0.0 };
                data.rotor_rows[(r, j)] = rotor_spin(rotor, &motions, rate);
            }
        }
        data.rotor_motions = motions;
        for (r, rotor) in model.rotors.iter().enumerate() {
            let row = data.rotor_rows.row(r);
            for i in 0..model.nv {
                for j in 0..model.nv {
                    mass[(i, j)] += rotor.inertia * row[i] * row[j];
                }
            }
        }
    }
}

impl<T: Real> Data<T> {
    /// Inverse dynamics of the rotors, at the end of RNEA's pass out: adds each rotor's torque τ_r
    /// to its carrier's force (so the pass back carries it to the joints that turn the carrier) and
    /// leaves, per rotor, n ε·τ_r for the pass back to add to its coordinate's effort in
    /// `data.rotor_own`.
    pub(super) fn add_rotor_torques(&mut self, model: &Model, a: &[T]) {
        let data = self;
        for (r, rotor) in model.rotors.iter().enumerate() {
            let omega = angular(&data.velocity[rotor.carrier]);
            let omega_dot = match rotor.carrier {
                0 => Vector3::zeros(),
                b => angular(&data.acceleration[b]),
            };
            let axis: Vector3<T> = rotor.axis.cast();
            let ratio: T = constant(rotor.ratio);
            let spin_rate = axis.dot(&omega_dot) + ratio * a[rotor.velocity];
            let torque = (axis * spin_rate + omega.cross(&axis) * spin(rotor, data))
                * constant::<T>(rotor.inertia);
            if rotor.carrier != 0 {
                data.force[rotor.carrier] += pure_moment(&torque);
            }
            data.rotor_own[r] = ratio * axis.dot(&torque);
            data.rotor_torques[r] = torque;
        }
    }

    /// ABA's backward pass at joint `k` (one coordinate) driving the rotor `r`: U_C = I_C S, D⁻¹
    /// and u of the pair (child, rotor) as the module's documentation gives them, U_R and the
    /// rotor's velocity-product acceleration relative to its carrier's, v_F × n q̇ e, kept for
    /// the pass out (`rotor_acceleration_term`), then the pair's articulated inertia and bias handed
    /// to the parent.
    pub(super) fn aba_rotor_step(
        &mut self,
        model: &Model,
        k: usize,
        r: usize,
        tau: T,
    ) -> Result<(), DynamicsError> {
        let data = self;
        let joint = &model.joints[k];
        let rotor = &model.rotors[r];
        let (i, parent) = (joint.child, joint.dynamic_parent);
        let carried_by_child = rotor.carrier == i;
        let state = &data.states[k];
        let s = *state.subspace.column(0);
        let (inertia, bias, coriolis) = (data.articulated[i], data.bias[i], data.coriolis[i]);
        let u_child = inertia * s;

        let e = axis_motion::<T>(rotor);
        let rotor_inertia = rotor_inertia::<T>(rotor);
        let ratio: T = constant(rotor.ratio);
        let geared_rate = ratio * joint_rate(data, k);
        let (carrier_velocity, rotor_subspace) = match carried_by_child {
            true => (data.velocity[i], s + e * ratio),
            false => (data.velocity[parent], e * ratio),
        };
        let rotor_velocity = carrier_velocity + e * geared_rate;
        let rotor_bias = spatial::cross_force(&rotor_velocity, &(rotor_inertia * rotor_velocity));
        let rotor_coriolis = spatial::cross_motion(&carrier_velocity, &(e * geared_rate));
        let u_rotor = rotor_inertia * rotor_subspace;

        let d = s.dot(&u_child) + rotor_subspace.dot(&u_rotor);
        if !(d.abs() > constant(1e-300) && d.is_finite()) {
            return Err(DynamicsError::Singular { joint: k, body: i });
        }
        let u = tau - s.dot(&bias) - rotor_subspace.dot(&rotor_bias);
        data.u[i][0] = u_child;
        data.d_inverse[i][(0, 0)] = d.recip();
        data.u_vector[i][0] = u;
        data.rotor_u[r] = u_rotor;
        data.rotor_coriolis[r] = rotor_coriolis;
        if parent == 0 {
            return Ok(());
        }
        // The pair's bias acceleration, as it enters U D⁻¹ (u − Uᵀ c): the child's is c_C, the
        // rotor's its carrier's (c_C when the child carries it, none for the parent) plus v_F × n q̇ e.
        let rotor_shift = u_rotor.dot(&rotor_coriolis);
        let state = &data.states[k];
        if carried_by_child {
            // Both bodies in the child's frame, moved to the parent's together.
            let u_pair = u_child + u_rotor;
            let reduced = inertia + rotor_inertia - u_pair * u_pair.transpose() / d;
            let handed = bias
                + rotor_bias
                + (inertia + rotor_inertia) * coriolis
                + rotor_inertia * rotor_coriolis
                + u_pair * ((u - u_pair.dot(&coriolis) - rotor_shift) / d);
            data.articulated[parent] += state.transform.inertia_to_parent(&reduced);
            data.bias[parent] += state.transform.force_to_parent(&handed);
        } else {
            // The child's terms moved to the parent's frame, where the rotor's already are.
            let u_pair = state.transform.force_to_parent(&u_child) + u_rotor;
            let reduced = state.transform.inertia_to_parent(&inertia) + rotor_inertia
                - u_pair * u_pair.transpose() / d;
            let handed = state
                .transform
                .force_to_parent(&(bias + inertia * coriolis))
                + rotor_bias
                + rotor_inertia * rotor_coriolis
                + u_pair * ((u - u_child.dot(&coriolis) - rotor_shift) / d);
            data.articulated[parent] += reduced;
            data.bias[parent] += handed;
        }
        Ok(())
    }

    /// U_Rᵀ (a_F + v_F × n q̇ e): what the rotor `r` of joint `k` takes from u in ABA's pass out,
    /// a_F its carrier's acceleration before the joint's own (the parent's `parent_acceleration`,
    /// or the child's `child_acceleration` = X a_P + c_C when the child carries it).
    pub(super) fn rotor_acceleration_term(
        &self,
        model: &Model,
        k: usize,
        r: usize,
        parent_acceleration: &Motion<T>,
        child_acceleration: &Motion<T>,
    ) -> T {
        let data = self;
        let carrier_acceleration = match model.rotors[r].carrier == model.joints[k].child {
            true => child_acceleration,
            false => parent_acceleration,
        };
        data.rotor_u[r].dot(&(carrier_acceleration + data.rotor_coriolis[r]))
    }
}
