//! Stiffness as a run finds it: an explicit integrator checks during the run whether its steps
//! are held by its stability region (`integrate::stability`, power iteration on the Jacobian of
//! the equations, a few evaluations every 20 steps). When they are, the run is better served by
//! the implicit integrator, and `lsdc simulate` says so (W0901), naming the coordinates that
//! move in the fast mode and the force element that makes it fast.

use serde::Serialize;

use super::system::MechanicalSystem;
use crate::diag::Diagnostic;
use crate::dynamics::angles::AngleReference;
use crate::dynamics::model::Model;
use crate::integrate::{jacobian_product, StabilityBound};
use crate::prepare::{Integrator, Prepared};
use crate::source::Span;

/// The share of ∂f/∂y along the fast mode an element must give to be named.
const NAMED_SHARE: f64 = 0.25;
/// A coordinate is named when it moves in the fast mode at least this fraction of the one that
/// moves most.
const NAMED_FRACTION: f64 = 0.3;

/// Where a run's steps were found held by stability, and what makes them so.
#[derive(Clone, Debug, Serialize)]
pub struct StiffnessReport {
    /// When it was found.
    pub time: f64,
    /// The fastest mode's rate (spectral radius of the Jacobian of the equations), in 1/s.
    pub rate: f64,
    /// The step taken then, and the largest step stability allows.
    pub step: f64,
    pub stable_step: f64,
    /// Whether the step is a fixed one beyond the stable step: then the run diverges.
    pub diverges: bool,
    /// The declared coordinates that move most in the fast mode, the first moving most.
    pub coordinates: Vec<String>,
    /// The force element that contributes most to the fast mode, when it gives a quarter of
    /// its rate or more: how the report names it (for the warning, its place in the program).
    pub element: Option<String>,
    #[serde(skip)]
    pub element_span: Option<Span>,
}

/// The report of a stability bound an explicit run found, or `None` if its state cannot be
/// evaluated again.
pub fn describe(prepared: &Prepared, bound: &StabilityBound) -> Option<StiffnessReport> {
    let model = &prepared.model;
    let fixed_step = prepared.settings.integrator == Integrator::Rk4;
    let motion = model.positions() + model.velocities();
    let state = bound.state.get(..motion)?;
    let direction = bound.direction.get(..motion)?;
    let coordinates = moving_coordinates(prepared, state, direction, bound.rate);
    let element = stiffest_element(prepared, bound.time, state, direction);
    Some(StiffnessReport {
        time: bound.time,
        rate: bound.rate,
        step: bound.step,
        stable_step: bound.stable_step(),
        diverges: fixed_step && bound.step > bound.stable_step(),
        coordinates,
        element: element.as_ref().map(|(name, _)| name.clone()),
        element_span: element.map(|(_, span)| span),
    })
}

/// The warning for an explicit run whose steps were held by stability (W0901), from what the run
/// found and the integrator's name.
pub fn warning(found: &StiffnessReport, integrator: &str) -> Option<Diagnostic> {
    let moving = match found.coordinates.as_slice() {
        [] => String::new(),
        [one] => format!(" (mostly `{one}`)"),
        [first, second, ..] => format!(
            " (mostly `{first}`, `{second}`{})",
            if found.coordinates.len() > 2 {
                ", …"
            } else {
                ""
            }
        ),
    };
    let held = match found.diverges {
        true => "is beyond the largest step stability allows",
        false => "is held by stability, not accuracy,",
    };
    let message = format!(
        "the mechanism is stiff for `{integrator}`: at t = {}, its fastest mode{moving} decays or turns at {:.1e} /s, and the step {:.1e} s {held} at {:.1e} s",
        found.time, found.rate, found.step, found.stable_step
    );
    let mut warning = Diagnostic::warning("W0901", message)
        .help("use the implicit integrator: `--integrator implicit`, or `simulate integrator = implicit end`");
    if found.diverges {
        warning = warning.note(
            "a fixed step beyond the stable step makes the fast mode grow at every step: the run diverges",
        );
    }
    Some(match found.element_span {
        Some(span) => warning.primary(span, "the stiffest element"),
        None => warning,
    })
}

/// The declared coordinates that move most along the fast mode `direction` at `state`:
/// their displacement scaled by the rate, plus their rate's change, along it.
fn moving_coordinates(
    prepared: &Prepared,
    state: &[f64],
    direction: &[f64],
    rate: f64,
) -> Vec<String> {
    let model = &prepared.model;
    // Both states against the same reference: their angles differ by the mode's motion.
    let reference = AngleReference::at_rest(prepared.coordinates.clone());
    let declared = |y: &[f64]| {
        let (q, v) = model.split_state(y);
        model.declared((0.0, &q, v), &reference).ok()
    };
    let size = state.iter().map(|v| v * v).sum::<f64>().sqrt();
    let epsilon = 1e-7 * (1.0 + size);
    let moved: Vec<f64> = state
        .iter()
        .zip(direction)
        .map(|(y, d)| y + epsilon * d)
        .collect();
    let (Some((q0, v0)), Some((q1, v1))) = (declared(state), declared(&moved)) else {
        return Vec::new();
    };
    let motion: Vec<f64> = (0..q0.len())
        .map(|i| rate * (q1[i] - q0[i]).abs() + (v1[i] - v0[i]).abs())
        .collect();
    let largest = motion.iter().copied().fold(0.0, f64::max);
    let mut named: Vec<(f64, &String)> = motion
        .iter()
        .zip(&prepared.coordinate_names)
        .filter(|(m, _)| largest > 0.0 && **m >= NAMED_FRACTION * largest)
        .map(|(m, name)| (*m, name))
        .collect();
    named.sort_by(|a, b| b.0.total_cmp(&a.0));
    named.into_iter().map(|(_, name)| name.clone()).collect()
}

/// The force element that contributes most to ∂f/∂y along the fast mode `direction` (its
/// contribution: the product with the element, less the product without it), when it gives at
/// least `NAMED_SHARE` of the product, with how the report names it. Each element costs a copy
/// of the model and two evaluations of the equations: done once, when a run found stiffness.
fn stiffest_element(
    prepared: &Prepared,
    time: f64,
    state: &[f64],
    direction: &[f64],
) -> Option<(String, Span)> {
    let model = &prepared.model;
    let product = |model: &Model| product_along(prepared, model, (time, state), direction);
    let whole = product(model)?;
    let contribution = |without: &Model| {
        let rest = product(without)?;
        Some(distance(&whole, &rest))
    };
    let mut largest = NAMED_SHARE * distance(&whole, &vec![0.0; whole.len()]);
    let mut element = None;
    for k in 0..model.applied.len() {
        let mut without = model.clone();
        let removed = without.applied.remove(k);
        without.compile_efforts();
        if let Some(size) = contribution(&without).filter(|&c| c > largest) {
            let body = model.body_names.get(removed.body.wrapping_sub(1));
            let name = match body {
                Some(body) => format!("an effort applied on `{body}`"),
                None => "an applied effort".to_string(),
            };
            (largest, element) = (size, Some((name, removed.span)));
        }
    }
    for k in 0..model.link_efforts.len() {
        let mut without = model.clone();
        let removed = without.link_efforts.remove(k);
        without.compile_efforts();
        if let Some(size) = contribution(&without).filter(|&c| c > largest) {
            let name = link_name(model, removed.joint).map_or("a link's effort".to_string(), |n| {
                format!("the effort of `{n}`")
            });
            (largest, element) = (size, Some((name, removed.span)));
        }
    }
    element
}

fn distance(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).powi(2))
        .sum::<f64>()
        .sqrt()
}

/// The join a link effort belongs to: a tree joint, then a complementary link.
fn link_name(model: &Model, joint: usize) -> Option<&str> {
    match model.joints.get(joint) {
        Some(j) => Some(&j.chain.name),
        None => model
            .loops
            .get(joint - model.joints.len())
            .map(|l| l.name.as_str()),
    }
}

/// ∂f/∂y · `direction` for `model`'s equations at (t, y).
fn product_along(
    prepared: &Prepared,
    model: &Model,
    (time, state): (f64, &[f64]),
    direction: &[f64],
) -> Option<Vec<f64>> {
    let reference = prepared.coordinates.clone();
    let mut system = MechanicalSystem::new(model, reference, prepared.settings.stabilisation);
    let mut y = state.to_vec();
    system.start_loops(&mut y).ok()?;
    let n = y.len();
    jacobian_product(&mut system, (time, &y), n, direction)
}
