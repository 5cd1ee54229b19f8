//! Whether Dormand–Prince's steps are held by its stability region: the implicit integrator's
//! reason to leave it for the implicit method (`switching.rs`).
//!
//! Dormand–Prince's own estimate h ‖k₇ − k₆‖ / ‖y₇ − y₆‖ (Hairer and Wanner's, from its last two
//! stages) measures ∂f/∂y along whatever the last step's stages happened to differ by. Where the
//! motion does not excite the stiff mode (a stiff spring released on its slow manifold), it
//! swings from step to step between 0.01 and 30 and seldom stays above a threshold for many
//! steps in a row: whether the switch came depended on the tolerance and on the last digits of
//! the start (a bob on a spring of k/m = 1e8 took 147,621 steps at 1e-4, 798 at 1e-6). So the
//! decision is taken on the spectral radius ρ of ∂f/∂y itself, by power iteration on J²
//! ([`PowerIteration`], its products by differences of f, its direction kept from check to
//! check), against the stability region's boundary in the direction of the stiff eigenvalues:
//!
//! - on the negative real axis (λ² > 0: a damped mode, a stiff damper) at h|λ| = 3.3;
//! - on the imaginary axis (λ² < 0: an undamped oscillation, a stiff spring) at h|λ| = 0.997,
//!   where |R(iy)| of Dormand–Prince's stability function crosses 1 (it exceeds 1 by 0.3 % at
//!   y = 1.5, 3 % at 2): the stiff pendulum's steps there were at h ρ = 0.81 on average.
//!
//! The steps are held when h ρ is between `HELD` and `CEILING` times that boundary on
//! `PERSISTENCE` checks in a row (taken at consecutive steps once one says so). A check costs
//! three evaluations of f (ten more at the first), taken every `CHECK_EVERY` steps, and only
//! while Dormand–Prince's free estimate is above `WORTH_CHECKING`: a problem whose steps are far
//! from any stability boundary (an orbit at 1e-10: h|λ| about 0.03) pays nothing.

use super::evaluator::Evaluator;
use super::stability::PowerIteration;

/// |h λ| at the boundary of Dormand–Prince's stability region on the negative real axis, and
/// on the imaginary axis.
const REAL_LIMIT: f64 = super::dopri5::STABILITY_LIMIT;
const IMAGINARY_LIMIT: f64 = 0.997;
/// The fraction of the boundary from which h ρ says that the step is held by stability, the
/// multiple above which it cannot be (an accepted step beyond the boundary means that the
/// fastest mode is one the solution follows, a motion running away, whose λ² > 0 looks like a
/// damped mode's, its steps bound by accuracy), the checks in a row that must agree and the
/// accepted steps between two checks: the stiffness check's (`stability.rs`), one policy.
use super::stability::{ADAPTIVE_CEILING as CEILING, CHECK_EVERY, HELD, PERSISTENCE};
/// Power iterations at the first check (fewer once two agree); later checks take one, the
/// direction converging along the run.
const WARM_UP: usize = 6;
/// Dormand–Prince's stage estimate h |λ| below which no check is taken: ‖J v‖ / ‖v‖ along any
/// direction v, it is below h ρ, and on the stiff pendulum it was above 0.1 on 95 % of the
/// steps held by stability.
const WORTH_CHECKING: f64 = 0.1;

/// The watch over Dormand–Prince's steps (see the module).
pub(super) struct HeldSteps {
    iteration: PowerIteration,
    steps_since_check: usize,
    held_checks: usize,
}

impl HeldSteps {
    pub(super) fn new(dimension: usize, controlled: usize) -> Self {
        HeldSteps {
            iteration: PowerIteration::new(dimension, controlled),
            steps_since_check: CHECK_EVERY,
            held_checks: 0,
        }
    }

    /// The stability boundary h ρ of Dormand–Prince along the fastest mode that its last check
    /// found, or `real` (the caller's boundary on the negative real axis) before any check found
    /// an oscillation: the bound the implicit method's steps are compared with to go back.
    pub(super) fn boundary(&self, real: f64) -> f64 {
        match self.iteration.is_warm() && self.iteration.oscillating() {
            true => IMAGINARY_LIMIT,
            false => real,
        }
    }

    /// Forgets the checks in a row (the method changed), keeping the iteration's direction.
    pub(super) fn forget(&mut self) {
        self.steps_since_check = CHECK_EVERY;
        self.held_checks = 0;
    }

    /// Whether the accepted step of size `h` that ended at (t, y), with Dormand–Prince's stage
    /// estimate `stage_estimate`, completes the checks that say the steps are held.
    pub(super) fn held_after(
        &mut self,
        eval: &mut Evaluator,
        (t, y): (f64, &[f64]),
        h: f64,
        stage_estimate: f64,
    ) -> bool {
        self.steps_since_check += 1;
        let due = self.held_checks > 0 || self.steps_since_check >= CHECK_EVERY;
        if !due || stage_estimate < WORTH_CHECKING {
            return false;
        }
        self.steps_since_check = 0;
        let iterations = if self.iteration.is_warm() { 1 } else { WARM_UP };
        let Some(rate) = self.iteration.estimate(eval, t, y, iterations) else {
            self.held_checks = 0;
            return false;
        };
        let limit = match self.iteration.oscillating() {
            true => IMAGINARY_LIMIT,
            false => REAL_LIMIT,
        };
        self.held_checks = match (HELD * limit..=CEILING * limit).contains(&(h * rate)) {
            true => self.held_checks + 1,
            false => 0,
        };
        self.held_checks >= PERSISTENCE
    }
}
