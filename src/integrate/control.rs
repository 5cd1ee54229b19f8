//! Error norms and step-size control shared by the adaptive methods.

/// The smallest previous error the predictive limit extrapolates from (Hairer and Wanner's
/// RADAU5): from a step far more accurate than asked, the next error's growth says nothing of
/// the one after.
const PREDICTION_FLOOR: f64 = 1e-2;
/// Largest shrink of one step, so that a single bad estimate cannot collapse the step size.
const MIN_FACTOR: f64 = 0.2;

/// Root-mean-square of the local error estimate, each component measured against
/// `atol + rtol * max(|y_old|, |y_new|)`: a value at most 1 means the step meets the tolerances.
pub fn error_norm(error: &[f64], y_old: &[f64], y_new: &[f64], rtol: f64, atol: f64) -> f64 {
    let sum: f64 = (0..error.len())
        .map(|i| {
            let scale = atol + rtol * y_old[i].abs().max(y_new[i].abs());
            (error[i] / scale).powi(2)
        })
        .sum();
    (sum / error.len().max(1) as f64).sqrt()
}

/// How a method's step-size controller reacts: each method's values are measured on its own
/// (`docs/commands.md`, *Integrators*).
#[derive(Clone, Copy, Debug)]
pub(super) struct Gains {
    /// The integral gain: proportional-integral control when above 0, elementary at 0.
    pub(super) beta: f64,
    /// Fraction of the optimal step actually taken, so that the next step is likely accepted.
    pub(super) safety: f64,
    /// Largest growth of one step.
    pub(super) max_factor: f64,
    /// How far the predictive limit extrapolates the rise of the error constant err / h^(q+1)
    /// seen over the last step: 1 assumes the next step's constant rises by the same ratio
    /// (Gustafsson), more anticipates an acceleration.
    pub(super) rise_power: f64,
}

impl Gains {
    /// Elementary control (β = 0) with the safety factor 0.9 of Hairer's codes (DOP853,
    /// RADAU5, RODAS), steps growing at most by `max_factor`, and the predictive limit
    /// extrapolating the error constant's rise once (Gustafsson).
    pub(super) fn elementary(max_factor: f64) -> Gains {
        Gains {
            beta: 0.0,
            safety: 0.9,
            max_factor,
            rise_power: 1.0,
        }
    }
}

/// Step-size controller: proportional-integral when `beta > 0`, elementary when `beta == 0`.
/// The integral part remembers the previous error so that the step varies smoothly.
#[derive(Clone, Debug)]
pub(super) struct StepController {
    /// 1 / (order of the error estimate + 1): the local error behaves like h to that power's inverse.
    exponent: f64,
    gains: Gains,
    previous_error: f64,
    /// The last accepted step and its error (at least `PREDICTION_FLOOR`), for the predictive
    /// limit.
    previous_step: Option<(f64, f64)>,
    just_rejected: bool,
}

impl StepController {
    /// `estimate_order` is q when the local error estimate behaves like h^(q+1).
    pub(super) fn new(estimate_order: u32, gains: Gains) -> Self {
        StepController {
            exponent: 1.0 / (estimate_order as f64 + 1.0),
            gains,
            previous_error: 1e-4,
            previous_step: None,
            just_rejected: false,
        }
    }

    /// The step to try after accepting a step of size `h` with error norm `error` (<= 1).
    pub(super) fn after_accept(&mut self, h: f64, error: f64) -> f64 {
        let Gains { beta, safety, .. } = self.gains;
        let error = error.max(1e-10);
        let alpha = self.exponent - 0.75 * beta;
        let factor = safety * error.powf(-alpha) * self.previous_error.powf(beta);
        // Growing right after a rejection tends to be rejected again.
        let max_factor = if self.just_rejected {
            1.0
        } else {
            self.gains.max_factor
        };
        let mut factor = factor.clamp(MIN_FACTOR, max_factor);
        // Gustafsson's predictive limit (as in Hairer and Wanner's RADAU5): where the error
        // constant rises from step to step (as when a Bricard linkage speeds up), the
        // proportional-integral factor lags one step behind and the next step is rejected;
        // extrapolating the rise takes the smaller step at once.
        if let Some((previous, previous_error)) = self.previous_step {
            let rise = (error / previous_error) * (previous / h).powf(1.0 / self.exponent);
            let predicted = error * rise.powf(self.gains.rise_power);
            let limit = safety * predicted.powf(-self.exponent);
            factor = factor.min(limit.clamp(MIN_FACTOR, max_factor));
        }
        self.previous_error = error.max(1e-4);
        self.previous_step = Some((h, error.max(PREDICTION_FLOOR)));
        self.just_rejected = false;
        h * factor
    }

    /// Forgets the accepted steps' errors, after an event that changed the equations: their
    /// trend says nothing of the errors after it.
    pub(super) fn forget_trend(&mut self) {
        self.previous_step = None;
    }

    /// The step to retry with after rejecting a step of size `h` with error norm `error` (> 1).
    pub(super) fn after_reject(&mut self, h: f64, error: f64) -> f64 {
        self.just_rejected = true;
        let factor = if error.is_finite() {
            self.gains.safety * error.powf(-self.exponent)
        } else {
            MIN_FACTOR
        };
        h * factor.clamp(MIN_FACTOR, 1.0)
    }

    /// The step to retry with after an attempt produced non-finite values.
    pub(super) fn after_not_finite(&mut self, h: f64) -> f64 {
        self.just_rejected = true;
        h * 0.25
    }
}
