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
///
/// The factors are formed from logarithms: each power of the errors and of the steps' ratio is
/// a multiple of a logarithm, so a step takes two logarithms (of its error and of its ratio to
/// the step before) and one exponential, where the powers took five `powf` (about a tenth of a
/// native run's time on a small mechanism, BENCHMARKS.md, "Sweeps: the simulator's framework
/// around native code cut"). The factors are the same up to rounding.
#[derive(Clone, Debug)]
pub(super) struct StepController {
    /// 1 / (order of the error estimate + 1): the local error behaves like h to that power's inverse.
    exponent: f64,
    gains: Gains,
    /// ln of the gains' safety factor, of the previous error's floor (1e-4) and of
    /// `PREDICTION_FLOOR`: formed once.
    log_safety: f64,
    log_error_floor: f64,
    log_prediction_floor: f64,
    /// ln of the previous error (at least 1e-4), for the integral part.
    log_previous_error: f64,
    /// The last accepted step and the logarithm of its error (at least `PREDICTION_FLOOR`),
    /// for the predictive limit.
    previous_step: Option<(f64, f64)>,
    just_rejected: bool,
}

impl StepController {
    /// `estimate_order` is q when the local error estimate behaves like h^(q+1).
    pub(super) fn new(estimate_order: u32, gains: Gains) -> Self {
        let log_error_floor = 1e-4f64.ln();
        StepController {
            exponent: 1.0 / (estimate_order as f64 + 1.0),
            log_safety: gains.safety.ln(),
            log_error_floor,
            log_prediction_floor: PREDICTION_FLOOR.ln(),
            gains,
            log_previous_error: log_error_floor,
            previous_step: None,
            just_rejected: false,
        }
    }

    /// The step to try after accepting a step of size `h` with error norm `error` (<= 1).
    pub(super) fn after_accept(&mut self, h: f64, error: f64) -> f64 {
        let beta = self.gains.beta;
        let log_error = error.max(1e-10).ln();
        let alpha = self.exponent - 0.75 * beta;
        // ln of the proportional-integral factor safety · error^(−α) · previous^β.
        let mut log_factor = self.log_safety - alpha * log_error + beta * self.log_previous_error;
        // Gustafsson's predictive limit (as in Hairer and Wanner's RADAU5): where the error
        // constant rises from step to step (as when a Bricard linkage speeds up), the
        // proportional-integral factor lags one step behind and the next step is rejected;
        // extrapolating the rise takes the smaller step at once. In logarithms,
        //   rise = (error / previous error) · (previous h / h)^(1/exponent),
        //   limit = safety · (error · rise^rise_power)^(−exponent).
        if let Some((previous, log_previous_error)) = self.previous_step {
            let log_rise = (log_error - log_previous_error) + (previous / h).ln() / self.exponent;
            let log_predicted = log_error + self.gains.rise_power * log_rise;
            let log_limit = self.log_safety - self.exponent * log_predicted;
            // Both are bounded alike below: the smaller of the bounded is the bounded smaller.
            log_factor = log_factor.min(log_limit);
        }
        // Growing right after a rejection tends to be rejected again.
        let max_factor = if self.just_rejected {
            1.0
        } else {
            self.gains.max_factor
        };
        let factor = log_factor.exp().clamp(MIN_FACTOR, max_factor);
        self.log_previous_error = log_error.max(self.log_error_floor);
        self.previous_step = Some((h, log_error.max(self.log_prediction_floor)));
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
