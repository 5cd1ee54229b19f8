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
use super::evaluator::{Evaluator, Halt};
use super::events::{EventWatch, Located};
use super::hermite::HermiteSegment;
use super::march::{Marching, Problem};
use super::outcome::{Failure, Stats, StepError};
use super::output::Outputs;
use super::settings::Settings;
use super::stability::StabilityWatch;
use super::system::Observer;

/// A remainder below this fraction of a step joins the last full step instead of making a sliver.
const SLIVER: f64 = 1e-9;

/// How many times one step may be shortened (`OdeSystem::cut_step`): each cut takes a fraction
/// of the step, so that a few bring its end as close to what it must see as a step can come.
const MAX_CUTS: usize = 60;

/// |h λ| at the boundary of the method's stability region: 2.785 on the negative real axis,
/// 2√2 on the imaginary one.
pub const STABILITY_LIMIT: f64 = 2.8;

/// RK4's integration between steps: the current point and its grid, the watches over the
/// stability region and the system's events.
pub(super) struct Rk4March {
    rk4: Rk4,
    step: f64,
    /// The grid's origin, and the number of its points passed.
    t0: f64,
    k: usize,
    watch: Option<StabilityWatch>,
    events: Option<EventWatch>,
}

impl Rk4March {
    /// At (t0, y0), with steps of `step` on the grid t0 + k step, to be started
    /// (`Marching::start`).
    pub(super) fn new(t0: f64, y0: &[f64], step: f64, settings: &Settings) -> Rk4March {
        Rk4March {
            rk4: Rk4::new(t0, y0),
            step,
            t0,
            k: 0,
            watch: StabilityWatch::new(STABILITY_LIMIT, false, y0.len(), settings),
            events: None,
        }
    }
}

impl Marching for Rk4March {
    fn time(&self) -> f64 {
        self.rk4.t
    }

    fn state(&self) -> &[f64] {
        &self.rk4.y
    }

    fn state_mut(&mut self) -> &mut [f64] {
        &mut self.rk4.y
    }

    /// The events' values at the start.
    fn start(&mut self, eval: &mut Evaluator, _problem: &Problem) -> Result<(), Halt> {
        self.events = EventWatch::new(eval, self.rk4.t, &self.rk4.y)?;
        Ok(())
    }

    /// One step to the next grid point, or to the end when it comes first, or to the first
    /// event in between.
    fn step(
        &mut self,
        eval: &mut Evaluator,
        problem: &Problem,
        outputs: &mut Outputs,
        observer: &mut Observer,
    ) -> Result<(), Halt> {
        let rk4 = &mut self.rk4;
        if let Some(value) = problem.settings.interrupted() {
            return Err(Halt::fatal(rk4.t, Failure::Interrupted(value)));
        }
        if self.k >= problem.settings.max_steps {
            return Err(Halt::fatal(rk4.t, Failure::TooManySteps));
        }
        self.k += 1;
        // Grid points by multiplication, so that rounding does not accumulate over many steps.
        let grid_point = self.t0 + self.k as f64 * self.step;
        let t_new = match self.k as f64 >= step_count(problem.t_end - self.t0, self.step) {
            true => problem.t_end,
            false => grid_point,
        };
        rk4.step(eval, t_new)?;
        // A step the system wants shorter (`OdeSystem::cut_step`) is taken again so, off the
        // grid; the next step goes on to the grid point.
        let mut t_new = t_new;
        for _ in 0..MAX_CUTS {
            let Some(fraction) = eval.cut_step(t_new, &rk4.y_new)? else {
                break;
            };
            t_new = rk4.t + fraction * (t_new - rk4.t);
            rk4.derivative_known = true;
            rk4.step(eval, t_new)?;
        }
        // Before the end derivative is evaluated, so that what the next step reuses is taken at
        // the projected state and the interpolant joins the projected ends.
        eval.project(t_new, &mut rk4.y_new)?;
        rk4.end_slope(eval)?;
        let error = rk4.error_estimate(problem.settings);
        StepError::keep_largest(&mut eval.stats.largest_step_error, error, t_new);
        if outputs.wants_interior(rk4.t, t_new) || self.events.is_some() {
            rk4.prepare_interpolation();
        }
        if let Some(watch) = &mut self.events {
            let segment = &rk4.segment;
            let interpolate = |t: f64, out: &mut [f64]| segment.evaluate(t, out);
            if let Some(event) = watch.search(eval, (rk4.t, t_new), &rk4.y_new, &interpolate)? {
                rk4.act_on_event(eval, event, outputs, observer)?;
                watch.restart(eval, rk4.t, &rk4.y)?;
                // The step to the grid point is taken again, from the event.
                self.k -= 1;
                eval.stats.steps += 1;
                return Ok(());
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
        // A step the end cut short of its grid point leaves that point for the next step, when
        // the integration goes on to a later end (`Integration::step`).
        if t_new < grid_point {
            self.k -= 1;
        }
        if let Some(watch) = &mut self.watch {
            watch.after_step(eval, rk4.t, &rk4.y, h);
        }
        Ok(())
    }

    /// The next step's first stage evaluated again, and the events' values.
    fn restart(&mut self, eval: &mut Evaluator) -> Result<(), Halt> {
        self.rk4.derivative_known = false;
        if let Some(watch) = &mut self.events {
            watch.restart(eval, self.rk4.t, &self.rk4.y)?;
        }
        Ok(())
    }

    fn count(&self, stats: &mut Stats) {
        stats.stability_bound = self.watch.as_ref().and_then(StabilityWatch::finding);
    }
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
    fn error_estimate(&mut self, settings: &Settings) -> f64 {
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
