//! A variational integrator for long conservative runs: the discrete Euler–Lagrange equations of
//! the midpoint discrete Lagrangian L_d(q0, q1) = h L((q0 + q1)/2, (q1 − q0)/h), with the
//! efforts entering as discrete Lagrange–d'Alembert forces. It is symplectic and
//! momentum-preserving, so the energy error stays bounded instead of drifting. Each step solves
//!   p_k = M(q̄) v̄ − h/2 (∂T/∂q(q̄, v̄) + Q(q̄, v̄))   for q_{k+1},
//! then p_{k+1} = M(q̄) v̄ + h/2 (∂T/∂q(q̄, v̄) + Q(q̄, v̄)), with q̄, v̄ the midpoint and mean
//! velocity of the step and Q the generalised efforts. Needs chain joints (no quaternions).

use nalgebra::{DMatrix, DVector};

use super::system::MechanicalSystem;
use crate::dynamics::algorithms::{crba, forward_kinematics, rnea};
use crate::dynamics::derivatives::kinetic_energy_gradient;
use crate::dynamics::efforts::{evaluate, Declared};
use crate::integrate::{Failure, IntegrationError, Observer, Stats};

const MAX_ITERATIONS: usize = 50;

impl MechanicalSystem<'_> {
    /// The generalised efforts at (q, v, t): link efforts plus the applied efforts seen through
    /// the Jacobians (computed as −RNEA with no motion).
    fn generalised_efforts(&mut self, q: &[f64], v: &[f64], t: f64) -> Result<DVector<f64>, String> {
        let model = self.model;
        forward_kinematics(model, &mut self.data, q, v).map_err(|e| format!("{e:?}"))?;
        let declared = Declared { model, coordinates: q, rates: v };
        let efforts = evaluate(model, &self.data, &declared, t).map_err(|e| format!("{e:?}"))?;
        let zero = vec![0.0; model.nv];
        let applied = rnea(model, &mut self.data, q, &zero, &zero, &efforts.external).map_err(|e| format!("{e:?}"))?;
        Ok(efforts.tau - applied)
    }

    /// ∂T/∂q + Q at the step's midpoint, and the mass matrix there.
    fn midpoint_terms(&mut self, q: &[f64], v: &[f64], t: f64) -> Result<(DMatrix<f64>, DVector<f64>), String> {
        let model = self.model;
        let gradient = kinetic_energy_gradient(model, &mut self.data, q, v).map_err(|e| format!("{e:?}"))?;
        let forcing = self.generalised_efforts(q, v, t)?;
        let mass = crba(model, &mut self.data, q).map_err(|e| format!("{e:?}"))?;
        Ok((mass, gradient + forcing))
    }
}

fn solve(mass: &DMatrix<f64>, rhs: &DVector<f64>) -> Result<DVector<f64>, String> {
    mass.clone().cholesky().map(|c| c.solve(rhs)).ok_or_else(|| "the mass matrix is singular".to_string())
}

/// Integrates with fixed step `h`, reporting the state (positions, velocities) at each output.
pub fn integrate(
    system: &mut MechanicalSystem<'_>,
    t0: f64,
    y0: &[f64],
    t_end: f64,
    h: f64,
    outputs: &[f64],
    observer: &mut Observer,
) -> Result<(Vec<f64>, Stats), IntegrationError> {
    let n = system.model.nv;
    let mut stats = Stats::default();
    let fail = |time: f64, failure: Failure, stats: &Stats| IntegrationError { time, failure, stats: stats.clone() };
    let (mut q, mut v) = (DVector::from_column_slice(&y0[..n]), DVector::from_column_slice(&y0[n..]));
    let mut t = t0;
    let mass = crba(system.model, &mut system.data, q.as_slice()).map_err(|e| fail(t, Failure::System(format!("{e:?}")), &stats))?;
    let mut p = &mass * &v;
    let mut next_output = 0;
    while next_output < outputs.len() && outputs[next_output] <= t0 {
        observer(t0, y0).map_err(|m| fail(t0, Failure::Observer(m), &stats))?;
        next_output += 1;
    }
    while t < t_end {
        let step = h.min(t_end - t);
        let mut q1 = &q + &v * step;
        let mut converged = false;
        let (mut mass_mid, mut terms) = (DMatrix::zeros(n, n), DVector::zeros(n));
        for _ in 0..MAX_ITERATIONS {
            let (mid, mean) = ((&q + &q1) * 0.5, (&q1 - &q) / step);
            (mass_mid, terms) = system.midpoint_terms(mid.as_slice(), mean.as_slice(), t + 0.5 * step).map_err(|m| fail(t, Failure::System(m), &stats))?;
            stats.rhs_evaluations += 1;
            let residual = &mass_mid * &mean - &terms * (0.5 * step) - &p;
            // Newton with the leading part of the Jacobian, M/h: converges quickly for small h.
            let correction = solve(&mass_mid, &(-residual * step)).map_err(|m| fail(t, Failure::System(m), &stats))?;
            q1 += &correction;
            if correction.amax() <= 1e-15 * (1.0 + q1.amax()) {
                converged = true;
                break;
            }
        }
        if q1.iter().any(|x| !x.is_finite()) {
            return Err(fail(t, Failure::NotFinite, &stats));
        }
        if !converged {
            let message = format!("the implicit equations of the step from t = {t} did not converge: use a smaller `step` than {step}");
            return Err(fail(t, Failure::System(message), &stats));
        }
        let mean = (&q1 - &q) / step;
        p = &mass_mid * &mean + &terms * (0.5 * step);
        let mass_end = crba(system.model, &mut system.data, q1.as_slice()).map_err(|e| fail(t, Failure::System(format!("{e:?}")), &stats))?;
        let v1 = solve(&mass_end, &p).map_err(|m| fail(t + step, Failure::System(m), &stats))?;
        stats.steps += 1;
        while next_output < outputs.len() && outputs[next_output] <= t + step {
            let s = (outputs[next_output] - t) / step;
            let y = hermite(&q, &v, &q1, &v1, s, step);
            observer(outputs[next_output], &y).map_err(|m| fail(outputs[next_output], Failure::Observer(m), &stats))?;
            next_output += 1;
        }
        (q, v, t) = (q1, v1, t + step);
    }
    let mut y = q.as_slice().to_vec();
    y.extend_from_slice(v.as_slice());
    Ok((y, stats))
}

/// Cubic Hermite interpolation of positions (and its derivative for velocities) at fraction s.
fn hermite(q0: &DVector<f64>, v0: &DVector<f64>, q1: &DVector<f64>, v1: &DVector<f64>, s: f64, h: f64) -> Vec<f64> {
    let (h00, h10, h01, h11) = (2.0 * s * s * s - 3.0 * s * s + 1.0, s * s * s - 2.0 * s * s + s, -2.0 * s * s * s + 3.0 * s * s, s * s * s - s * s);
    let (d00, d10, d01, d11) = (6.0 * s * s - 6.0 * s, 3.0 * s * s - 4.0 * s + 1.0, -6.0 * s * s + 6.0 * s, 3.0 * s * s - 2.0 * s);
    let q = q0 * h00 + v0 * (h10 * h) + q1 * h01 + v1 * (h11 * h);
    let v = (q0 * d00 + q1 * d01) / h + v0 * d10 + v1 * d11;
    let mut y = q.as_slice().to_vec();
    y.extend_from_slice(v.as_slice());
    y
}
