//! Stiffness: how fast the fastest mode of a mechanism decays or turns, from the eigenvalues of
//! the Jacobian of its equations at the start, and which force element makes it so. An explicit
//! integrator's step is bounded by that rate for stability alone, however smooth the motion of
//! interest; when the bound forces far more steps than the outputs ask for, the run is better
//! served by the implicit integrator, and `lsdc simulate` says so (W0901).

use std::cell::RefCell;
use std::rc::Rc;

use nalgebra::{DMatrix, Schur};

use super::prepare::{Integrator, Prepared};
use super::system::MechanicalSystem;
use crate::diag::Diagnostic;
use crate::dynamics::model::Model;
use crate::source::Span;

/// The stability bound of an explicit method: |λ| h below this (about 3.3 for Dormand–Prince,
/// about 6 for DOP853, 2.8 for the classical Runge–Kutta method); `None` for the other integrators.
fn stability_limit(integrator: &Integrator) -> Option<f64> {
    match integrator {
        Integrator::DormandPrince => Some(3.3),
        Integrator::Dop853 => Some(6.0),
        Integrator::Rk4 => Some(2.8),
        Integrator::Implicit | Integrator::Symplectic => None,
    }
}

/// The warning for an explicit run that stiffness makes inefficient, or `None`.
pub fn warning(prepared: &Prepared) -> Option<Diagnostic> {
    let settings = &prepared.settings;
    let limit = stability_limit(&settings.integrator)?;
    let rate = fastest_rate(&prepared.model, prepared)?;
    let stability_steps = settings.duration * rate / limit;
    let outputs = (settings.duration / settings.output).ceil().max(1.0);
    if stability_steps < 1000.0 || stability_steps < 100.0 * outputs {
        return None;
    }
    let name = super::run::integrator_name(&settings.integrator);
    let message = format!(
        "the mechanism is stiff for `{name}`: its fastest mode decays or turns at {:.1e} /s, so every step must stay below {:.1e} s, about {:.0} steps for this run",
        rate,
        limit / rate,
        stability_steps
    );
    let warning = Diagnostic::warning("W0901", message).help("use the implicit integrator: `--integrator implicit`, or `simulate integrator = implicit end`");
    // Only now, when there is something to say, look for the element to blame: it costs one
    // estimate per force element.
    Some(match stiffest_element(prepared, rate) {
        Some(span) => warning.primary(span, "the stiffest element"),
        None => warning,
    })
}

/// The force element whose removal lowers the fastest rate most, when it lowers it by half or
/// more.
fn stiffest_element(prepared: &Prepared, rate: f64) -> Option<Span> {
    let model = &prepared.model;
    let mut element = None;
    let mut lowest = 0.5 * rate;
    for k in 0..model.applied.len() {
        let mut without = model.clone();
        let removed = without.applied.remove(k);
        without.compile_efforts();
        if let Some(r) = fastest_rate(&without, prepared).filter(|&r| r < lowest) {
            (lowest, element) = (r, Some(removed.span));
        }
    }
    for k in 0..model.link_efforts.len() {
        let mut without = model.clone();
        let removed = without.link_efforts.remove(k);
        without.compile_efforts();
        if let Some(r) = fastest_rate(&without, prepared).filter(|&r| r < lowest) {
            (lowest, element) = (r, Some(removed.span));
        }
    }
    element
}

/// Sweeps of the eigenvalue iteration allowed per state before the estimate gives up (and no
/// warning is given): a few per eigenvalue is typical; without a bound a matrix on which the
/// iteration does not converge would hang the run before its first step.
const EIGENVALUE_SWEEPS_PER_STATE: usize = 30;

/// The largest |λ| of the Jacobian of y' = f(t, y) at the initial state, by forward differences.
fn fastest_rate(model: &Model, prepared: &Prepared) -> Option<f64> {
    let (q0, v0) = model
        .state_from_declared(&prepared.coordinates, &prepared.rates)
        .ok()?;
    let mut y0 = q0;
    y0.extend_from_slice(&v0);
    let reference = Rc::new(RefCell::new(prepared.coordinates.clone()));
    let mut system = MechanicalSystem::new(model, reference, prepared.settings.stabilisation);
    system.start_loops(&mut y0).ok()?;
    let n = y0.len();
    if n == 0 {
        // Nothing moves: no mode, no bound on the step.
        return None;
    }
    let mut f0 = vec![0.0; n];
    system.derivative(0.0, &y0, &mut f0).ok()?;
    let mut jacobian = DMatrix::zeros(n, n);
    let mut f = vec![0.0; n];
    for j in 0..n {
        let mut y = y0.clone();
        let h = 1e-7 * y0[j].abs().max(1.0);
        y[j] += h;
        system.derivative(0.0, &y, &mut f).ok()?;
        for i in 0..n {
            jacobian[(i, j)] = (f[i] - f0[i]) / h;
        }
    }
    if !jacobian.iter().all(|x| x.is_finite()) {
        return None;
    }
    let n = jacobian.nrows();
    Schur::try_new(
        jacobian,
        f64::EPSILON,
        EIGENVALUE_SWEEPS_PER_STATE * n.max(1),
    )?
    .complex_eigenvalues()
    .iter()
    .map(|l| l.norm())
    .fold(None, |m: Option<f64>, r| Some(m.map_or(r, |m| m.max(r))))
}
