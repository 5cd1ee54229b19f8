//! Whether an explicit method's steps are held by its stability region rather than by its
//! accuracy: the stiffness check of the explicit methods, during the run.
//!
//! Every `CHECK_EVERY` accepted steps the spectral radius ρ of the Jacobian ∂f/∂y at the step's
//! end is estimated by power iteration on J², its products with a vector taken by finite
//! differences of the right-hand side: three evaluations per check, O(n) for a tree. J² rather
//! than J because the fast modes of a mechanism are mostly conjugate pairs ±iω, on which
//! power iteration with J does not settle and ‖J v‖ / ‖v‖ swings between 1 and ω² with the
//! scales of positions and velocities, while J² v = −ω² v on their plane. The vector is kept
//! from check to check, so the iteration goes on converging along the run.
//!
//! On a system kept on a manifold after each step (a mechanism's closed loops, projected onto
//! their constraints), only the motions along the manifold are integrated: the directions off
//! it are removed by the projection, never stepped. So the iteration runs on the tangent space
//! ([`OdeSystem::tangent_basis`]), each product projected back onto it: P J P. Off it, near a
//! singular configuration of the loops (a parallelogram four-bar passing flat), ∂f/∂y grows
//! like the inverse of the constraints' conditioning (1.2e4 /s at a conditioning of 3e-4 on
//! `examples/hard/four_bar_row_1.lsd`), a rate no step ever sees: RK4 at 1 ms ran through such
//! passages with an energy drift of 4e-8 while the check said it diverged.
//!
//! Where h ρ reaches `HELD` of the method's stability limit on `PERSISTENCE` checks in a row
//! (taken at consecutive steps once one says so), the run's steps are those stability allows:
//! an adaptive method's controller has found the boundary (and h ρ stays below
//! `ADAPTIVE_CEILING` times it), a fixed step lies near or beyond it. A fixed step beyond it
//! is found at the first check that says so: the run diverges within a few steps.
//! The first such finding is kept ([`StabilityBound`]) and the checks stop. Nothing depends on
//! the output times. The implicit method's stiffness switching watches its steps with
//! Dormand–Prince's own stage estimate (`switching.rs`), which is free but measures
//! ‖J v‖ / ‖v‖ along the step's stage difference only, and with this power iteration
//! (`held_steps.rs`); a warning must not depend on what one step happened to excite.

use nalgebra::{DMatrix, DVector};

use super::evaluator::Evaluator;
use super::jacobian::orthonormal;
use super::outcome::{StabilityBound, Stats};
use super::settings::Settings;
use super::system::OdeSystem;

/// Accepted steps between two checks while nothing is found.
pub(super) const CHECK_EVERY: usize = 20;
/// Power iterations at the first check, from the starting vector (fewer when two in a row
/// agree within `SETTLED`); later checks take one.
const WARM_UP: usize = 12;
const SETTLED: f64 = 0.01;
/// The fraction of the stability limit from which h ρ says the step is held by stability:
/// Dormand–Prince's controller keeps a stiff run's steps between about half the limit and the
/// limit, and accuracy alone keeps them far below on the non-stiff examples.
pub(super) const HELD: f64 = 0.5;
/// Checks in a row that must agree.
pub(super) const PERSISTENCE: usize = 3;
/// The multiple of the stability limit above which an adaptive method's accepted steps cannot
/// be held by stability: its error estimate would have caught a mode that grows at every step.
/// There the fastest mode is one the solution itself follows (a motion running away), which
/// the step must resolve for accuracy; λ² cannot tell it from a decaying mode.
pub(super) const ADAPTIVE_CEILING: f64 = 2.0;
/// Relative size of the finite-difference perturbation (about √ε).
const PERTURBATION: f64 = 1.5e-8;

/// Power iteration on J² along a kept direction (see the module).
pub(super) struct PowerIteration {
    controlled: usize,
    direction: Vec<f64>,
    slope: Vec<f64>,
    probe: Vec<f64>,
    perturbed: Vec<f64>,
    /// The direction before the last iteration.
    previous: Vec<f64>,
    /// Whether `direction` has been iterated on at all (else it is the starting vector).
    warm: bool,
    /// Whether the last iteration turned the direction over (⟨v, J² v⟩ < 0): the fastest
    /// eigenvalues are an oscillation ±iω rather than real (λ² = −ω² against λ² > 0).
    oscillating: bool,
    /// An orthonormal basis of the system's tangent space at the point of the estimate (over
    /// the controlled components), `None` for a system that moves freely.
    tangent: Option<DMatrix<f64>>,
}

impl PowerIteration {
    pub(super) fn new(dimension: usize, controlled: usize) -> Self {
        let zeros = vec![0.0; dimension];
        PowerIteration {
            controlled,
            direction: starting_vector(dimension, controlled),
            slope: zeros.clone(),
            probe: zeros.clone(),
            perturbed: zeros.clone(),
            previous: zeros,
            warm: false,
            oscillating: false,
            tangent: None,
        }
    }

    /// Starts from `direction` instead of the default vector: its norm over the controlled
    /// components, `None` (and the default vector kept) when it is zero.
    fn start_from(&mut self, direction: &[f64]) -> Option<f64> {
        let n = self.controlled;
        self.direction[..n].copy_from_slice(&direction[..n]);
        let size = normalise(&mut self.direction[..n]);
        if size.is_none() {
            self.direction = starting_vector(self.direction.len(), n);
        }
        size
    }

    pub(super) fn direction(&self) -> &[f64] {
        &self.direction
    }

    /// Whether the direction has been iterated on (a first estimate needs more iterations).
    pub(super) fn is_warm(&self) -> bool {
        self.warm
    }

    /// Whether the fastest eigenvalues of the last estimate are an oscillation (see the field).
    pub(super) fn oscillating(&self) -> bool {
        self.oscillating
    }

    /// The estimate of ρ at (t, y) after `iterations` iterations at most (stopping early when
    /// two agree within `SETTLED`); `None` when an evaluation fails or J v vanishes.
    pub(super) fn estimate(
        &mut self,
        eval: &mut Evaluator,
        t: f64,
        y: &[f64],
        iterations: usize,
    ) -> Option<f64> {
        let n = self.controlled;
        let tangent = eval.tangent_basis(t, y).ok()?;
        self.tangent = tangent.map(|basis| {
            let rows = basis.nrows().min(n);
            orthonormal(basis.rows(0, rows).into_owned(), n)
        });
        self.onto_tangent();
        if normalise(&mut self.direction[..n]).is_none() {
            self.direction = starting_vector(self.direction.len(), n);
            self.onto_tangent();
            normalise(&mut self.direction[..n]);
        }
        eval.rhs(t, y, &mut self.slope).ok()?;
        let mut rate: Option<f64> = None;
        for _ in 0..iterations {
            self.previous[..n].copy_from_slice(&self.direction[..n]);
            let first = self.multiply(eval, t, y)?;
            let second = self.multiply(eval, t, y)?;
            let turned: f64 = (self.direction[..n].iter().zip(&self.previous[..n]))
                .map(|(a, b)| a * b)
                .sum();
            self.oscillating = turned < 0.0;
            let next = (first * second).sqrt();
            let settled = rate.is_some_and(|r| (next - r).abs() <= SETTLED * next);
            rate = Some(next);
            if settled {
                break;
            }
        }
        self.warm = true;
        rate
    }

    /// direction ← J direction / ‖J direction‖, by a forward difference from `slope` = f(t, y);
    /// returns ‖J direction‖ (the direction having unit norm).
    fn multiply(&mut self, eval: &mut Evaluator, t: f64, y: &[f64]) -> Option<f64> {
        let n = self.controlled;
        let size = y[..n].iter().map(|v| v * v).sum::<f64>().sqrt();
        let epsilon = PERTURBATION * (1.0 + size);
        self.probe.copy_from_slice(y);
        for (p, d) in self.probe[..n].iter_mut().zip(&self.direction) {
            *p += epsilon * d;
        }
        eval.rhs(t, &self.probe, &mut self.perturbed).ok()?;
        for i in 0..n {
            self.direction[i] = (self.perturbed[i] - self.slope[i]) / epsilon;
        }
        self.onto_tangent();
        let norm = normalise(&mut self.direction[..n]);
        if norm.is_none() {
            self.direction = starting_vector(self.direction.len(), n);
        }
        norm
    }
}

impl PowerIteration {
    /// Projects the direction onto the tangent space, when the system has one.
    fn onto_tangent(&mut self) {
        let Some(basis) = &self.tangent else { return };
        let n = self.controlled;
        let direction = DVector::from_column_slice(&self.direction[..n]);
        let projected = basis * basis.tr_mul(&direction);
        self.direction[..n].copy_from_slice(projected.as_slice());
    }
}

/// ∂f/∂y · `direction` at (t, y) of `system`, by a forward difference over its leading
/// `controlled` components (the others of `direction` are ignored, those of the product zero);
/// `None` when an evaluation fails or the product vanishes.
pub fn jacobian_product(
    system: &mut dyn OdeSystem,
    (t, y): (f64, &[f64]),
    controlled: usize,
    direction: &[f64],
) -> Option<Vec<f64>> {
    let mut iteration = PowerIteration::new(y.len(), controlled.min(y.len()));
    let size = iteration.start_from(direction)?;
    let mut stats = Stats::default();
    let mut eval = Evaluator::resume(system, &mut stats);
    eval.rhs(t, y, &mut iteration.slope).ok()?;
    let norm = iteration.multiply(&mut eval, t, y)?;
    Some(
        iteration
            .direction
            .iter()
            .map(|d| d * norm * size)
            .collect(),
    )
}

/// Scales `values` to unit norm; `None` (and unchanged) when their norm is zero or not finite.
fn normalise(values: &mut [f64]) -> Option<f64> {
    let norm = values.iter().map(|v| v * v).sum::<f64>().sqrt();
    if !(norm.is_finite() && norm > 0.0) {
        return None;
    }
    values.iter_mut().for_each(|v| *v /= norm);
    Some(norm)
}

/// A fixed vector with no structure a mechanism's modes could be orthogonal to (a hash of the
/// index), unit norm over the controlled components.
fn starting_vector(dimension: usize, controlled: usize) -> Vec<f64> {
    let mut v: Vec<f64> = (0..dimension)
        .map(|i| match i < controlled {
            true => ((i as u64 + 1).wrapping_mul(2_654_435_761) % 1000) as f64 / 1000.0 - 0.5,
            false => 0.0,
        })
        .collect();
    normalise(&mut v[..controlled]);
    v
}

/// The stiffness check of an explicit run (see the module).
pub(super) struct StabilityWatch {
    limit: f64,
    adaptive: bool,
    iteration: PowerIteration,
    steps_since_check: usize,
    held_checks: usize,
    found: Option<StabilityBound>,
}

impl StabilityWatch {
    /// The watch for a method whose stability region reaches |h λ| = `limit`, adaptive or with
    /// a fixed step, or `None` when the settings turn the check off.
    pub(super) fn new(
        limit: f64,
        adaptive: bool,
        dimension: usize,
        settings: &Settings,
    ) -> Option<Self> {
        settings.stiffness_check.then(|| StabilityWatch {
            limit,
            adaptive,
            iteration: PowerIteration::new(dimension, settings.controlled_len(dimension)),
            steps_since_check: CHECK_EVERY,
            held_checks: 0,
            found: None,
        })
    }

    /// Called at the end (t, y) of each accepted step of size `h`.
    pub(super) fn after_step(&mut self, eval: &mut Evaluator, t: f64, y: &[f64], h: f64) {
        if self.found.is_some() {
            return;
        }
        self.steps_since_check += 1;
        if self.held_checks == 0 && self.steps_since_check < CHECK_EVERY {
            return;
        }
        self.steps_since_check = 0;
        let iterations = if self.iteration.warm { 1 } else { WARM_UP };
        let Some(rate) = self.iteration.estimate(eval, t, y, iterations) else {
            self.held_checks = 0;
            return;
        };
        let ratio = h * rate / self.limit;
        let ceiling = match self.adaptive {
            true => ADAPTIVE_CEILING,
            false => f64::INFINITY,
        };
        self.held_checks = match (HELD..=ceiling).contains(&ratio) {
            true => self.held_checks + 1,
            false => 0,
        };
        let diverging = !self.adaptive && ratio > 1.0;
        if self.held_checks >= PERSISTENCE || diverging {
            self.found = Some(StabilityBound {
                time: t,
                rate,
                step: h,
                limit: self.limit,
                state: y.to_vec(),
                direction: self.iteration.direction().to_vec(),
            });
        }
    }

    pub(super) fn finding(&self) -> Option<StabilityBound> {
        self.found.clone()
    }
}
