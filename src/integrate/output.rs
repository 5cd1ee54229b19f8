//! Hands the states at the requested output times to the observer as the integration passes them.

use super::evaluator::{Evaluator, Halt};
use super::outcome::Failure;
use super::system::Observer;

/// Fraction of a step within which an output time counts as the step's end, so that output times
/// computed with rounding (3 * 0.1 against 0.3) still get the step's own state.
const COINCIDENCE: f64 = 1e-9;

/// The output times and how many of them were delivered.
pub(super) struct Outputs {
    times: Vec<f64>,
    next: usize,
    value: Vec<f64>,
}

impl Outputs {
    pub(super) fn new(times: Vec<f64>, dimension: usize) -> Self {
        Outputs {
            times,
            next: 0,
            value: vec![0.0; dimension],
        }
    }

    /// Delivers the outputs at the start time.
    pub(super) fn deliver_start(
        &mut self,
        t0: f64,
        y0: &[f64],
        (eval, observer): (&mut Evaluator, &mut Observer),
    ) -> Result<(), Halt> {
        while let Some(&t) = self.times.get(self.next).filter(|&&t| t <= t0) {
            self.next += 1;
            observe((eval, observer), t, y0)?;
        }
        Ok(())
    }

    /// Whether an output falls strictly inside the step, i.e. needs the interpolant.
    pub(super) fn wants_interior(&self, t_start: f64, t_end: f64) -> bool {
        self.times
            .get(self.next)
            .is_some_and(|&t| t < t_end - COINCIDENCE * (t_end - t_start))
    }

    /// Delivers the outputs up to the end of the accepted step from `t_start` to `t_end`,
    /// interpolating those inside it.
    pub(super) fn deliver_step(
        &mut self,
        (t_start, t_end): (f64, f64),
        y_end: &[f64],
        interpolate: impl Fn(f64, &mut [f64]),
        (eval, observer): (&mut Evaluator, &mut Observer),
    ) -> Result<(), Halt> {
        let tolerance = COINCIDENCE * (t_end - t_start);
        while let Some(&t) = self
            .times
            .get(self.next)
            .filter(|&&t| t <= t_end + tolerance)
        {
            self.next += 1;
            if t < t_end - tolerance {
                interpolate(t, &mut self.value);
                observe((eval, observer), t, &self.value)?;
            } else {
                observe((eval, observer), t, y_end)?;
            }
        }
        Ok(())
    }

    /// Delivers whatever is left (times that rounding put a hair past the final step).
    pub(super) fn deliver_rest(
        &mut self,
        y_end: &[f64],
        (eval, observer): (&mut Evaluator, &mut Observer),
    ) -> Result<(), Halt> {
        while let Some(&t) = self.times.get(self.next) {
            self.next += 1;
            observe((eval, observer), t, y_end)?;
        }
        Ok(())
    }
}

/// The system's observation, then the observer's, of the output at (t, y).
fn observe(
    (eval, observer): (&mut Evaluator, &mut Observer),
    t: f64,
    y: &[f64],
) -> Result<(), Halt> {
    let observed = eval.observe(t, y).and_then(|()| observer(t, y));
    observed.map_err(|error| Halt::fatal(t, Failure::Observer(error.to_string())))
}
