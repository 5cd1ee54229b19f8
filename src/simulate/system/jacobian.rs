//! The Jacobian of a tree's equations of motion, for the implicit integrator, from inverse
//! dynamics instead of the forward dynamics.
//!
//! With y = (q, v) and joints whose coordinates move with their rates (q̇ = v, no quaternion),
//! f(y) = (v, a(q, v)), so ∂q̇/∂q = 0 and ∂q̇/∂v = I exactly. The accelerations satisfy
//! r(q, v, a) = τ(q, v) − ID(q, v, a; f_ext(q, v)) = 0, with ID the inverse dynamics (RNEA) and
//! τ, f_ext the efforts; since ∂r/∂a = −M, differentiating at the solution a* gives
//!
//!   ∂a/∂x = M⁻¹ ∂r/∂x (q, v, a*),
//!
//! a derivative at fixed accelerations. Each column of ∂r/∂x is a forward difference of the
//! efforts and of RNEA, cheaper than the articulated-body algorithm that f needs, and M comes
//! from the composite rigid bodies once per Jacobian; the power of the non-conservative efforts
//! (the work's rate) is differenced along with the efforts.
//!
//! The same holds with the structure of the tree's other equations. Mimic couplings keep
//! a = S u̇ with Sᵀ r(q, v, a*) = 0, so ∂a/∂x = P ∂r/∂x with P = S (Sᵀ M S)⁻¹ Sᵀ (the tree
//! response, `Response::apply`). Coordinates held at rest (a resting stop, a sticking joint)
//! add the rows E a = 0 and their forces Eᵀμ, which depend on the state too: differentiating
//! Sᵀ(r + Eᵀμ) = 0 and E a = 0 gives ∂a/∂x = (P − P Eᵀ (E P Eᵀ)⁺ E P) ∂r/∂x, the held change
//! of the columns P ∂r/∂x (`subtract_held_change`). The slipping joints' friction,
//! −s F_c − c q̇ in a phase, is one more effort in r.

use nalgebra::{DMatrix, DVector};

use super::scratch::mass_storage;
use super::{MechanicalSystem, SystemError};
use crate::dynamics::algorithms::rnea_derivatives::RneaDerivatives;
use crate::dynamics::algorithms::{
    crba_after_kinematics, forward_kinematics, rnea_after_kinematics,
};
use crate::dynamics::dense::inverse_power_of_two;
use crate::dynamics::effort_derivatives::{self, EffortDerivatives};
use crate::dynamics::efforts::Declared;
use crate::dynamics::joint::JointType;
use crate::dynamics::rows::DEPENDENT_ROWS;
use std::ops::SubAssign;

/// The residual of the equations of motion at one state, and the power of the efforts there.
struct Residual {
    values: DVector<f64>,
    power: f64,
}

impl MechanicalSystem<'_> {
    /// Whether [`MechanicalSystem::jacobian`] applies: a tree whose joints' coordinates move
    /// with their rates, evaluated in the library (not native code), without contacts or
    /// position drives.
    pub fn has_tree_jacobian(&self) -> bool {
        let model = self.model;
        !model.has_loops()
            && !model.has_contacts()
            && self.native.is_none()
            && model.positions() == model.velocities()
            && model.joints.iter().all(|j| j.kind == JointType::Chain)
            // A position drive's rows are not among the held coordinates it differentiates.
            && model.position_drives.is_empty()
    }

    /// ∂f/∂y at (t, y), where `dydt` = f(t, y), into `jacobian` (a square of the state's
    /// dimension), and the gradient of the efforts' power into `power_gradient`. `Ok(false)`
    /// where it does not apply ([`MechanicalSystem::has_tree_jacobian`]) or where the mass
    /// matrix is singular (a massless motion): the caller differences f instead.
    pub fn jacobian(
        &mut self,
        t: f64,
        y: &[f64],
        dydt: &[f64],
        jacobian: &mut DMatrix<f64>,
        power_gradient: &mut [f64],
    ) -> Result<bool, SystemError> {
        if !self.has_tree_jacobian() {
            return Ok(false);
        }
        let model = self.model;
        let nv = model.nv;
        let accelerations = &dydt[nv..];
        let mut differences = DMatrix::zeros(nv, 2 * nv);
        if !self.exact_residual_derivatives(
            t,
            y,
            accelerations,
            &mut differences,
            power_gradient,
        )? {
            self.differenced_residual(t, y, accelerations, &mut differences, power_gradient)?;
        }
        let mass = mass_storage(&mut self.scratch.mass, nv);
        crba_after_kinematics(model, &mut self.scratch.data, mass);
        // X = M⁻¹, or S (SᵀMS)⁻¹Sᵀ with the mimic couplings; formed at y for this Jacobian only.
        let formed = self.form_tree_response().is_ok();
        self.scratch.response_here = false;
        if !formed {
            return Ok(false);
        }
        let mut response = DMatrix::zeros(nv, 2 * nv);
        self.scratch.response.apply(&differences, &mut response);
        // The coordinates held keep their accelerations (zero at rest, d̈(t) when driven),
        // whatever the state.
        self.gather_held(t);
        if !self.scratch.held.is_empty() {
            self.subtract_held_change(&mut response);
        }
        jacobian.fill(0.0);
        jacobian.view_mut((0, nv), (nv, nv)).fill_with_identity();
        jacobian
            .view_mut((nv, 0), (nv, 2 * nv))
            .copy_from(&response);
        Ok(true)
    }

    /// Whether the analytical derivatives cover the residual's: the efforts' through their
    /// tape (`effort_derivatives::covers`), no input and no friction, and RNEA's.
    fn has_exact_residual_derivatives(&self) -> bool {
        let model = self.model;
        effort_derivatives::covers(model).is_ok()
            && !self.state.inputs.any()
            && !model.has_contacts()
    }

    /// The derivatives of the efforts' generalised forces at (t, q, v),
    /// D = ∂τ_links/∂(q, v) + Σ_b J_bᵀ ∂f_b/∂(q, v) with the bodies' Jacobians held (nv × 2nv,
    /// along q then v), and
    /// the gradient of their power, through the efforts' tape (`effort_derivatives`); the
    /// forward kinematics of (q, v) left in `data`. `None` where they do not cover the model
    /// or an input is set.
    pub(crate) fn effort_derivatives(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
    ) -> Result<Option<&EffortDerivatives>, SystemError> {
        if !self.has_exact_residual_derivatives() {
            return Ok(None);
        }
        let model = self.model;
        self.evaluate_efforts(t, q, v)?;
        let scratch = &mut *self.scratch;
        let exact = scratch.exact_jacobian.get_or_insert_with(|| {
            Box::new((RneaDerivatives::new(model), EffortDerivatives::new(model)))
        });
        let declared = Declared {
            model,
            coordinates: &scratch.declared.coordinates,
            rates: &scratch.declared.rates,
            states: &self.state.states,
        };
        exact.1.compute(model, &mut scratch.data, &declared, t)?;
        Ok(Some(&exact.1))
    }

    /// ∂r/∂(q, v) at (y, a*) exactly, D − ∂RNEA/∂(q, v) with D the efforts' derivatives
    /// ([`MechanicalSystem::effort_derivatives`]), and the gradient of the efforts' power; the
    /// forward kinematics of y left in `data`. `Ok(false)` where they do not cover the model.
    fn exact_residual_derivatives(
        &mut self,
        t: f64,
        y: &[f64],
        a: &[f64],
        columns: &mut DMatrix<f64>,
        power_gradient: &mut [f64],
    ) -> Result<bool, SystemError> {
        let model = self.model;
        let nv = model.nv;
        let (q, v) = y.split_at(model.nq);
        if self.effort_derivatives(t, q, v)?.is_none() {
            return Ok(false);
        }
        let scratch = &mut *self.scratch;
        let (inverse, efforts) = &mut **scratch.exact_jacobian.as_mut().expect("made above");
        let external = &scratch.efforts.external;
        if inverse
            .compute(model, &mut scratch.data, q, v, a, external)
            .is_err()
        {
            return Ok(false);
        }
        columns.copy_from(&efforts.efforts);
        columns.columns_mut(0, nv).sub_assign(&inverse.dtau_dq);
        columns.columns_mut(nv, nv).sub_assign(&inverse.dtau_dv);
        power_gradient[..2 * nv].copy_from_slice(&efforts.power);
        Ok(true)
    }

    /// ∂r/∂(q, v) by forward differences of the residual (efforts and RNEA), and the gradient
    /// of the efforts' power; the forward kinematics of y left in `data`.
    fn differenced_residual(
        &mut self,
        t: f64,
        y: &[f64],
        accelerations: &[f64],
        differences: &mut DMatrix<f64>,
        power_gradient: &mut [f64],
    ) -> Result<(), SystemError> {
        let columns = 2 * self.model.nv;
        let mut perturbed = y.to_vec();
        let mut deltas = Vec::with_capacity(columns);
        for j in 0..columns {
            perturbed[j] = y[j] + (f64::EPSILON * y[j].abs().max(1e-5)).sqrt();
            // The increment actually represented, so that rounding of y + δ does not bias the
            // quotient.
            deltas.push(perturbed[j] - y[j]);
            let moved = self.residual(t, &perturbed, accelerations)?;
            perturbed[j] = y[j];
            differences.set_column(j, &moved.values);
            power_gradient[j] = moved.power;
        }
        // The state's own residual last, so that the kinematics left in `data` are y's.
        let at_state = self.residual(t, y, accelerations)?;
        for (j, delta) in deltas.into_iter().enumerate() {
            let mut column = differences.column_mut(j);
            column -= &at_state.values;
            column /= delta;
            power_gradient[j] = (power_gradient[j] - at_state.power) / delta;
        }
        Ok(())
    }

    /// The held change of the columns Y = X ∂r/∂x (`held`): Y − X Eᵀ (E X Eᵀ)⁺ E Y, with E the
    /// unit rows of the held velocities; X formed. Dependent rows (a coordinate held by its stop
    /// and its friction) are set aside as the run's solve sets them aside (`rows`).
    fn subtract_held_change(&mut self, columns: &mut DMatrix<f64>) {
        let nv = self.model.nv;
        let held: Vec<usize> = self.scratch.held.iter().map(|h| h.velocity).collect();
        let mut units = DMatrix::zeros(nv, held.len());
        for (i, &k) in held.iter().enumerate() {
            units[(k, i)] = 1.0;
        }
        let mut moved = DMatrix::zeros(nv, held.len());
        self.scratch.response.apply(&units, &mut moved);
        // Scaled symmetrically, D (E X Eᵀ) D with D of powers of two, for the reason `Pivoted`
        // scales the run's rows: a held angle of a light rotor beside a heavy slider's.
        let scales: Vec<f64> = (held.iter().enumerate())
            .map(|(i, &k)| inverse_power_of_two(moved[(k, i)].abs().sqrt()))
            .collect();
        let mut coupling = moved.select_rows(&held);
        let mut held_rows = columns.select_rows(&held);
        for (i, &scale) in scales.iter().enumerate() {
            coupling.row_mut(i).scale_mut(scale);
            coupling.column_mut(i).scale_mut(scale);
            held_rows.row_mut(i).scale_mut(scale);
        }
        // A non-finite coupling has no decomposition: the columns say so rather than hang.
        let Some(svd) = crate::linalg::svd(coupling, true, true) else {
            columns.fill(f64::NAN);
            return;
        };
        let cutoff = DEPENDENT_ROWS * svd.singular_values.max();
        if let Ok(mut solved) = svd.solve(&held_rows, cutoff) {
            for (i, &scale) in scales.iter().enumerate() {
                solved.row_mut(i).scale_mut(scale);
            }
            *columns -= moved * solved;
        }
    }

    /// r = τ − RNEA(q, v, a; f_ext) at y = (q, v), the efforts and the slipping joints'
    /// friction evaluated there, and their power; leaves the forward kinematics of y in `data`.
    fn residual(&mut self, t: f64, y: &[f64], a: &[f64]) -> Result<Residual, SystemError> {
        let model = self.model;
        let (q, v) = y.split_at(model.nq);
        let efforts = if self.reads_efforts() {
            self.evaluate_efforts(t, q, v)?;
            &self.scratch.efforts
        } else {
            forward_kinematics(model, &mut self.scratch.data, q, v)?;
            &self.scratch.no_efforts
        };
        let mut values = DVector::zeros(model.nv);
        rnea_after_kinematics(
            model,
            &mut self.scratch.data,
            a,
            &efforts.external,
            &mut values,
        );
        values -= &efforts.tau;
        values.neg_mut();
        let power = efforts.power + self.add_friction(v, &mut values);
        Ok(Residual { values, power })
    }
}
