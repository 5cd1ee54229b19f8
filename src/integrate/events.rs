//! Events on the solution: where an event function of the system crosses from non-negative to
//! negative within a step, located on the step's interpolant by bisection, to a time resolution
//! of [`TIME_RESOLUTION`] (relative to the time's size, at least that absolute).

use super::evaluator::{Evaluator, Halt};

/// The width, relative to max(1, |t|), of the bracket the bisection stops at: well below the
/// 1e-10 an event time is asked for, and above the rounding of t.
pub(super) const TIME_RESOLUTION: f64 = 1e-13;

/// The event functions at the start of the current step, and scratch for the search.
pub(super) struct EventWatch {
    before: Vec<f64>,
    after: Vec<f64>,
    probe: Vec<f64>,
    state: Vec<f64>,
}

/// The first event within a step: which function, when, and the interpolated state there.
pub(super) struct Located {
    pub(super) index: usize,
    pub(super) time: f64,
    pub(super) state: Vec<f64>,
}

impl EventWatch {
    /// A watch over the system's events, or `None` when it has none.
    pub(super) fn new(
        eval: &mut Evaluator,
        t0: f64,
        y0: &[f64],
    ) -> Result<Option<EventWatch>, Halt> {
        let count = eval.event_count();
        if count == 0 {
            return Ok(None);
        }
        let mut watch = EventWatch {
            before: vec![0.0; count],
            after: vec![0.0; count],
            probe: vec![0.0; count],
            state: vec![0.0; y0.len()],
        };
        watch.restart(eval, t0, y0)?;
        Ok(Some(watch))
    }

    /// Takes (t, y) as the start of the next step (after a step, or an event acted on).
    pub(super) fn restart(&mut self, eval: &mut Evaluator, t: f64, y: &[f64]) -> Result<(), Halt> {
        eval.events(t, y, &mut self.before)
    }

    /// The first event in the step (t0, t1] that ends at y1, searched on `interpolate`; `None`
    /// when no event function went from non-negative to negative (the step's end then becomes
    /// the start of the next).
    pub(super) fn search(
        &mut self,
        eval: &mut Evaluator,
        (t0, t1): (f64, f64),
        y1: &[f64],
        interpolate: &dyn Fn(f64, &mut [f64]),
    ) -> Result<Option<Located>, Halt> {
        eval.events(t1, y1, &mut self.after)?;
        let mut first: Option<(usize, f64)> = None;
        for index in 0..self.before.len() {
            if !(self.before[index] >= 0.0 && self.after[index] < 0.0) {
                continue;
            }
            let time = self.bisect(eval, index, (t0, t1), interpolate)?;
            if first.is_none_or(|(_, earliest)| time < earliest) {
                first = Some((index, time));
            }
        }
        let Some((index, time)) = first else {
            std::mem::swap(&mut self.before, &mut self.after);
            return Ok(None);
        };
        let mut state = vec![0.0; y1.len()];
        if time >= t1 {
            state.copy_from_slice(y1);
        } else {
            interpolate(time, &mut state);
        }
        Ok(Some(Located { index, time, state }))
    }

    /// The end of the smallest bracket [a, b] with g(a) ≥ 0 > g(b) that bisection reaches: the
    /// event function is past its zero there, by at most the bracket's width in time.
    fn bisect(
        &mut self,
        eval: &mut Evaluator,
        index: usize,
        (mut a, mut b): (f64, f64),
        interpolate: &dyn Fn(f64, &mut [f64]),
    ) -> Result<f64, Halt> {
        let resolution = TIME_RESOLUTION * b.abs().max(1.0);
        while b - a > resolution {
            let middle = 0.5 * (a + b);
            if middle <= a || middle >= b {
                break;
            }
            interpolate(middle, &mut self.state);
            eval.events(middle, &self.state, &mut self.probe)?;
            if self.probe[index] >= 0.0 {
                a = middle;
            } else {
                b = middle;
            }
        }
        Ok(b)
    }
}
