//! The classic Runge–Kutta method of order 4 with a fixed step on the grid t0 + k * step, the last
//! step shortened to land on the end time. Outputs between grid points come from the cubic Hermite
//! interpolant through the step's ends, whose end slope is then reused as the next step's first
//! stage, so outputs cost at most one extra evaluation (at the very end). Each step's end is
//! projected before anything is derived from it, so a projection costs no evaluation here.
//!
//! Nothing controls a fixed step's error, so each step measures it: the slope at the step's end
//! (the next step's first stage, so it costs nothing but at the very end) makes with the four
//! stages an embedded solution of order 3, y + h (k1 + 2 k2 + 2 k3 + k5) / 6 (the weights
//! 1/6, 1/3, 1/3, 0, 1/6 satisfy the four order-3 conditions), whose difference from the
//! order-4 solution, h (k4 − k5) / 6, estimates the local error of the order-3 solution: an upper
//! bound, to leading order, of the order-4 step's. The run reports the largest estimate in the
//! norm of the tolerances, so that a step too long for the motion is not a silent wrong answer.

use super::control::error_norm;
use super::driver::Problem;
use super::evaluator::{all_finite, Evaluator, Halt};
use super::events::{EventWatch, Located};
use super::hermite::HermiteSegment;
use super::outcome::{Failure, IntegrationError, Stats, StepError};
use super::output::Outputs;
use super::stability::StabilityWatch;
use super::system::{Observer, OdeSystem};

/// A remainder below this fraction of a step joins the last full step instead of making a sliver.
const SLIVER: f64 = 1e-9;

/// |h λ| at the boundary of the method's stability region: 2.785 on the negative real axis,
/// 2√2 on the imaginary one.
pub const STABILITY_LIMIT: f64 = 2.8;

pub(super) fn integrate(
    system: &mut dyn OdeSystem,
    problem: &Problem,
    step: f64,
    observer: &mut Observer,
) -> Result<(Vec<f64>, Stats), IntegrationError> {
    let mut eval = Evaluator::new(system);
    let dimension = problem.y0.len();
    let mut watch = StabilityWatch::new(STABILITY_LIMIT, false, dimension, problem.settings);
    let result = run(&mut eval, problem, step, &mut watch, observer);
    eval.stats.stability_bound = watch.and_then(|mut watch| watch.finding());
    match result {
        Ok(y) => Ok((y, eval.stats)),
        Err(halt) => Err(halt.made_fatal().into_error(eval.stats)),
    }
}

fn run(
    eval: &mut Evaluator,
    problem: &Problem,
    step: f64,
    watch: &mut Option<StabilityWatch>,
    observer: &mut Observer,
) -> Result<Vec<f64>, Halt> {
    let Problem { t0, y0, t_end, .. } = *problem;
    let mut outputs = Outputs::new(problem.outputs, y0.len());
    if !all_finite(y0) {
        return Err(Halt::fatal(t0, Failure::NotFinite));
    }
    outputs.deliver_start(t0, y0, (eval, observer))?;
    let step_count = step_count(t_end - t0, step);
    let mut rk4 = Rk4::new(t0, y0);
    let mut events = EventWatch::new(eval, t0, y0)?;
    let mut k = 0usize;
    while (k as f64) < step_count {
        if let Some(value) = problem.settings.interrupted() {
            return Err(Halt::fatal(rk4.t, Failure::Interrupted(value)));
        }
        if k >= problem.settings.max_steps {
            return Err(Halt::fatal(rk4.t, Failure::TooManySteps));
        }
        k += 1;
        // Grid points by multiplication, so that rounding does not accumulate over many steps.
        let t_new = if k as f64 >= step_count {
            t_end
        } else {
            t0 + k as f64 * step
        };
        rk4.step(eval, t_new)?;
        // Before the end derivative is evaluated, so that what the next step reuses is taken at
        // the projected state and the interpolant joins the projected ends.
        eval.project(t_new, &mut rk4.y_new)?;
        rk4.end_slope(eval)?;
        let error = rk4.error_estimate(problem);
        StepError::keep_largest(&mut eval.stats.largest_step_error, error, t_new);
        if outputs.wants_interior(rk4.t, t_new) || events.is_some() {
            rk4.prepare_interpolation();
        }
        if let Some(watch) = &mut events {
            let segment = &rk4.segment;
            let interpolate = |t: f64, out: &mut [f64]| segment.evaluate(t, out);
            if let Some(event) = watch.search(eval, (rk4.t, t_new), &rk4.y_new, &interpolate)? {
                rk4.act_on_event(eval, event, &mut outputs, observer)?;
                watch.restart(eval, rk4.t, &rk4.y)?;
                // The step to the grid point is taken again, from the event.
                k -= 1;
                eval.stats.steps += 1;
                continue;
            }
        }
        let segment = &rk4.segment;
        outputs.deliver_step(
            (rk4.t, t_new),
            &rk4.y_new,
            |t, out| segment.evaluate(t, out),
            (eval, observer),
        )?;
        let h = rk4.h;
        rk4.advance(t_new);
        eval.stats.steps += 1;
        if let Some(watch) = watch {
            watch.after_step(eval, rk4.t, &rk4.y, h);
        }
    }
    outputs.deliver_rest(&rk4.y, (eval, observer))?;
    Ok(rk4.y)
}

/// The number of steps of the grid over a run of length `span`: a remainder under `SLIVER` of a
/// step joins the last full step, and a run shorter than one step is one shortened step (not
/// none, which would report the start as the end).
fn step_count(span: f64, step: f64) -> f64 {
    if span > 0.0 {
        (span / step - SLIVER).ceil().max(1.0)
    } else {
        0.0
    }
}

/// The current point, the step just taken from it, and the stage buffers.
struct Rk4 {
    t: f64,
    y: Vec<f64>,
    y_new: Vec<f64>,
    h: f64,
    /// dy/dt at the current point when already known (the previous step's end slope).
    derivative_known: bool,
    stages: [Vec<f64>; 4],
    end_derivative: Vec<f64>,
    stage_state: Vec<f64>,
    segment: HermiteSegment,
}

impl Rk4 {
    fn new(t0: f64, y0: &[f64]) -> Self {
        let zeros = vec![0.0; y0.len()];
        Rk4 {
            t: t0,
            y: y0.to_vec(),
            y_new: zeros.clone(),
            h: 0.0,
            derivative_known: false,
            stages: std::array::from_fn(|_| zeros.clone()),
            end_derivative: zeros.clone(),
            stage_state: zeros,
            segment: HermiteSegment::new(y0.len()),
        }
    }

    /// Computes y_new at `t_new` from the current point.
    fn step(&mut self, eval: &mut Evaluator, t_new: f64) -> Result<(), Halt> {
        let (t, h) = (self.t, t_new - self.t);
        self.h = h;
        if !self.derivative_known {
            eval.rhs(t, &self.y, &mut self.stages[0])?;
        }
        self.derivative_known = false;
        for (stage, fraction) in [(1, 0.5), (2, 0.5), (3, 1.0)] {
            for i in 0..self.y.len() {
                self.stage_state[i] = self.y[i] + fraction * h * self.stages[stage - 1][i];
            }
            eval.rhs(t + fraction * h, &self.stage_state, &mut self.stages[stage])?;
        }
        let [k1, k2, k3, k4] = &self.stages;
        for i in 0..self.y.len() {
            self.y_new[i] = self.y[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
        }
        Ok(())
    }

    /// Evaluates dy/dt at the step's (projected) end: the next step's first stage.
    fn end_slope(&mut self, eval: &mut Evaluator) -> Result<(), Halt> {
        eval.rhs(self.t + self.h, &self.y_new, &mut self.end_derivative)?;
        self.derivative_known = true;
        Ok(())
    }

    /// The norm of h (k4 − k5) / 6 over the components the tolerances control: the embedded
    /// order-3 solution's distance from the step's end (see the module's documentation).
    fn error_estimate(&mut self, problem: &Problem) -> f64 {
        let settings = problem.settings;
        let controlled = settings.controlled_len(self.y.len());
        let difference = &mut self.stage_state;
        for (i, d) in difference.iter_mut().enumerate() {
            *d = self.h / 6.0 * (self.stages[3][i] - self.end_derivative[i]);
        }
        error_norm(
            &difference[..controlled],
            &self.y[..controlled],
            &self.y_new[..controlled],
            settings.rtol,
            settings.atol,
        )
    }

    /// Sets up the Hermite interpolant over the step from its ends and their slopes.
    fn prepare_interpolation(&mut self) {
        let ends = [
            &self.y[..],
            &self.stages[0],
            &self.y_new,
            &self.end_derivative,
        ];
        self.segment.set(self.t, self.h, ends);
    }

    /// Ends the step at the event located in it: the outputs up to it from the interpolant, then
    /// the system acts and the next step starts from the changed state (its slope unknown).
    fn act_on_event(
        &mut self,
        eval: &mut Evaluator,
        event: Located,
        outputs: &mut Outputs,
        observer: &mut Observer,
    ) -> Result<(), Halt> {
        let Located {
            index,
            time,
            mut state,
        } = event;
        let segment = &self.segment;
        outputs.deliver_step(
            (self.t, time),
            &state,
            |t, out| segment.evaluate(t, out),
            (eval, observer),
        )?;
        eval.handle_event(time, &mut state, index)?;
        eval.project(time, &mut state)?;
        self.y = state;
        self.t = time;
        self.derivative_known = false;
        Ok(())
    }

    /// Moves the current point to the end of the step just taken.
    fn advance(&mut self, t_new: f64) {
        if self.derivative_known {
            std::mem::swap(&mut self.stages[0], &mut self.end_derivative);
        }
        std::mem::swap(&mut self.y, &mut self.y_new);
        self.t = t_new;
    }
}
