//! The steps shared by the adaptive methods: step-size selection, acceptance, output delivery and
//! failure detection. Each method supplies only how to attempt and interpolate one step.

use super::control::StepController;
use super::evaluator::{all_finite, Evaluator, Halt};
use super::events::{EventWatch, Located};
use super::march::{Marching, Problem};
use super::outcome::{Failure, Stats};
use super::output::Outputs;
use super::settings::Settings;
use super::stability::StabilityWatch;
use super::system::Observer;

/// One adaptive method, stepping from the current point of the solution.
pub(super) trait AdaptiveStepper {
    /// Order of the method (for the initial step estimate).
    fn order(&self) -> u32;
    /// |h λ| at the boundary of an explicit method's stability region (for its stiffness
    /// check); `None` for a method whose steps stability does not bound.
    fn stability_limit(&self) -> Option<f64> {
        None
    }
    /// The step-size controller suited to the method's error estimate.
    fn controller(&self) -> StepController;
    /// The longest step the method expects to complete from the current point, whatever its
    /// error estimate (an implicit method's iteration converges only on steps short enough).
    fn step_limit(&self) -> f64 {
        f64::INFINITY
    }
    /// The controller to use from the next attempt on, when the method changed at the last
    /// accepted step (a method that switches between two).
    fn switched_controller(&mut self) -> Option<StepController> {
        None
    }
    /// Prepares stepping from a point the last accepted step did not compute: the initial point,
    /// or a step end moved by [`OdeSystem::project`] (e.g. evaluates dy/dt there).
    fn start(&mut self, eval: &mut Evaluator, t: f64, y: &[f64]) -> Result<(), Halt>;
    /// dy/dt at the current point.
    fn derivative(&self) -> &[f64];
    /// Attempts a step of size `h` from (t, y): writes the new state into `y_new` and returns the
    /// norm of the local error estimate (at most 1 means acceptable).
    fn attempt(
        &mut self,
        eval: &mut Evaluator,
        t: f64,
        y: &[f64],
        h: f64,
        y_new: &mut [f64],
    ) -> Result<f64, Halt>;
    /// Takes what the dense output over the attempt about to be accepted needs beyond the
    /// attempt itself, when an output falls inside it or events are watched (the extra stages
    /// of a continuous extension); nothing for most methods. Only after this call is the
    /// accepted step interpolated: a method may leave its interpolant unformed otherwise.
    fn prepare_interpolation(
        &mut self,
        _eval: &mut Evaluator,
        _t: f64,
        _y: &[f64],
        _h: f64,
    ) -> Result<(), Halt> {
        Ok(())
    }
    /// Makes the last attempt the current step, preparing dense output over it.
    fn accept(&mut self, t: f64, y: &[f64], h: f64, y_new: &[f64]);
    /// The dense output of the last accepted step at `t`.
    fn interpolate(&self, t: f64, out: &mut [f64]);
    /// Looks at the accepted step of size `h` that ended at (t, y), after its end was projected
    /// and its outputs delivered: a method that switches between two may evaluate the system
    /// there to decide (and change [`AdaptiveStepper::switched_controller`]). Nothing for most.
    fn after_step(&mut self, _eval: &mut Evaluator, _t: f64, _y: &[f64], _h: f64) {}
    /// Adds to `stats` what the method counts itself (a method that switches between two).
    fn count(&self, _stats: &mut Stats) {}
}

/// An adaptive method's integration between steps: the method, the current point, the step
/// to try next, and the watches over the stability region and the system's events.
pub(super) struct AdaptiveMarch {
    stepper: Box<dyn AdaptiveStepper>,
    t: f64,
    y: Vec<f64>,
    y_new: Vec<f64>,
    /// The step to try next, and the last one accepted.
    h: f64,
    last_step: f64,
    attempts: usize,
    controller: StepController,
    /// The stiffness check of an explicit method, when the settings ask for it.
    watch: Option<StabilityWatch>,
    /// The system's event functions, when it has any.
    events: Option<EventWatch>,
}

impl AdaptiveMarch {
    /// `stepper` at (t0, y0), to be started (`Marching::start`).
    pub(super) fn new(
        stepper: Box<dyn AdaptiveStepper>,
        t0: f64,
        y0: &[f64],
        settings: &Settings,
    ) -> AdaptiveMarch {
        let watch = stepper
            .stability_limit()
            .and_then(|limit| StabilityWatch::new(limit, true, y0.len(), settings));
        AdaptiveMarch {
            controller: stepper.controller(),
            stepper,
            t: t0,
            y: y0.to_vec(),
            y_new: vec![0.0; y0.len()],
            h: 0.0,
            last_step: 0.0,
            attempts: 0,
            watch,
            events: None,
        }
    }
}

impl Marching for AdaptiveMarch {
    fn time(&self) -> f64 {
        self.t
    }

    fn state(&self) -> &[f64] {
        &self.y
    }

    fn state_mut(&mut self) -> &mut [f64] {
        &mut self.y
    }

    /// dy/dt at the start (a non-finite one cannot be avoided by a shorter step), the first
    /// step's size, the events' values.
    fn start(&mut self, eval: &mut Evaluator, problem: &Problem) -> Result<(), Halt> {
        let (t0, y0) = (self.t, &self.y[..]);
        (self.stepper)
            .start(eval, t0, y0)
            .map_err(Halt::made_fatal)?;
        self.h = match problem.settings.initial_step {
            Some(h) => h,
            None => initial_step(&mut *self.stepper, eval, problem, y0)?,
        };
        self.last_step = self.h;
        self.events = EventWatch::new(eval, t0, y0)?;
        Ok(())
    }

    /// Attempts steps until one is accepted (the rejected ones shrink the step).
    fn step(
        &mut self,
        eval: &mut Evaluator,
        problem: &Problem,
        outputs: &mut Outputs,
        observer: &mut Observer,
    ) -> Result<(), Halt> {
        while !self.attempt(eval, problem, outputs, observer)? {}
        (self.stepper).after_step(eval, self.t, &self.y, self.last_step);
        if let Some(controller) = self.stepper.switched_controller() {
            self.controller = controller;
        }
        if let Some(watch) = &mut self.watch {
            watch.after_step(eval, self.t, &self.y, self.last_step);
        }
        Ok(())
    }

    /// dy/dt and the events' values again at the current point, the error's trend forgotten.
    fn restart(&mut self, eval: &mut Evaluator) -> Result<(), Halt> {
        (self.stepper)
            .start(eval, self.t, &self.y)
            .map_err(Halt::made_fatal)?;
        self.controller.forget_trend();
        if let Some(watch) = &mut self.events {
            watch.restart(eval, self.t, &self.y)?;
        }
        Ok(())
    }

    fn count(&self, stats: &mut Stats) {
        stats.stability_bound = self.watch.as_ref().and_then(StabilityWatch::finding);
        self.stepper.count(stats);
    }
}

impl AdaptiveMarch {
    /// One attempt: either advances the solution (and says so) or shrinks the step.
    fn attempt(
        &mut self,
        eval: &mut Evaluator,
        problem: &Problem,
        outputs: &mut Outputs,
        observer: &mut Observer,
    ) -> Result<bool, Halt> {
        let h = self.next_step_size(problem, self.stepper.step_limit())?;
        let attempt = (self.stepper).attempt(eval, self.t, &self.y, h, &mut self.y_new);
        let attempt = attempt.and_then(|error| match all_finite(&self.y_new) {
            true => Ok(error),
            false => Err(Halt::NotFinite { time: self.t + h }),
        });
        // A step the system wants shorter (`OdeSystem::cut_adaptive_step`) is taken again so.
        let attempt = attempt.and_then(|error| match error <= 1.0 {
            true => Ok((error, eval.cut_adaptive_step(self.t + h, &self.y_new)?)),
            false => Ok((error, None)),
        });
        match attempt {
            Ok((_, Some(fraction))) => {
                eval.stats.rejected += 1;
                self.h = fraction * h;
            }
            Ok((error, None)) if error <= 1.0 => {
                self.advance(eval, problem, h, outputs, observer)?;
                eval.stats.steps += 1;
                self.last_step = h;
                self.h = self.controller.after_accept(h, error);
                if let Some(controller) = self.stepper.switched_controller() {
                    self.controller = controller;
                }
                if eval.breaks_error_trend() {
                    self.controller.forget_trend();
                }
                return Ok(true);
            }
            Ok((error, None)) => {
                eval.stats.rejected += 1;
                self.h = self.controller.after_reject(h, error);
            }
            Err(Halt::NotFinite { time }) => {
                eval.stats.rejected += 1;
                self.h = self.controller.after_not_finite(h);
                if self.h < smallest_step(problem, self.t) {
                    return Err(Halt::fatal(time, Failure::NotFinite));
                }
            }
            Err(fatal) => return Err(fatal),
        }
        Ok(false)
    }

    /// Moves to the end of the accepted step of size `h`, projected onto the system's manifold,
    /// delivering the outputs it passes.
    fn advance(
        &mut self,
        eval: &mut Evaluator,
        problem: &Problem,
        h: f64,
        outputs: &mut Outputs,
        observer: &mut Observer,
    ) -> Result<(), Halt> {
        let stepper = &mut self.stepper;
        let lands_on_end = h >= problem.t_end - self.t || self.t + h >= problem.t_end;
        let t_new = if lands_on_end {
            problem.t_end
        } else {
            self.t + h
        };
        if outputs.wants_interior(self.t, t_new) || self.events.is_some() {
            // A failure here is past the step's acceptance: a shorter step would not avoid it.
            (stepper.prepare_interpolation(eval, self.t, &self.y, h)).map_err(Halt::made_fatal)?;
        }
        // The interpolant is built from the unprojected end, consistent with the step's stages.
        stepper.accept(self.t, &self.y, h, &self.y_new);
        if let Some(watch) = &mut self.events {
            let interpolate = |t: f64, out: &mut [f64]| stepper.interpolate(t, out);
            if let Some(event) = watch.search(eval, (self.t, t_new), &self.y_new, &interpolate)? {
                return self.act_on_event(eval, event, outputs, observer);
            }
        }
        if eval.project(t_new, &mut self.y_new)? {
            // What the stepper cached at the step's end (dy/dt) belongs to the unprojected state.
            stepper
                .start(eval, t_new, &self.y_new)
                .map_err(Halt::made_fatal)?;
        }
        let interpolate = |t: f64, out: &mut [f64]| stepper.interpolate(t, out);
        outputs.deliver_step((self.t, t_new), &self.y_new, interpolate, (eval, observer))?;
        std::mem::swap(&mut self.y, &mut self.y_new);
        self.t = t_new;
        Ok(())
    }

    /// Ends the step at the event located in it: delivers the outputs up to the event (from the
    /// interpolant), lets the system act, and restarts the method from the changed state, the
    /// error's trend forgotten (the motion after an impact owes nothing to the one before).
    fn act_on_event(
        &mut self,
        eval: &mut Evaluator,
        event: Located,
        outputs: &mut Outputs,
        observer: &mut Observer,
    ) -> Result<(), Halt> {
        let stepper = &mut self.stepper;
        let Located {
            index,
            time,
            mut state,
        } = event;
        let interpolate = |t: f64, out: &mut [f64]| stepper.interpolate(t, out);
        outputs.deliver_step((self.t, time), &state, interpolate, (eval, observer))?;
        eval.handle_event(time, &mut state, index)?;
        eval.project(time, &mut state)?;
        stepper
            .start(eval, time, &state)
            .map_err(Halt::made_fatal)?;
        self.controller.forget_trend();
        if let Some(watch) = &mut self.events {
            watch.restart(eval, time, &state)?;
        }
        self.y = state;
        self.t = time;
        Ok(())
    }

    /// The proposed step limited by the settings and stretched to land exactly on the end time.
    fn next_step_size(&mut self, problem: &Problem, limit: f64) -> Result<f64, Halt> {
        let settings = problem.settings;
        if let Some(value) = settings.interrupted() {
            return Err(Halt::fatal(self.t, Failure::Interrupted(value)));
        }
        if self.attempts >= settings.max_steps {
            return Err(Halt::fatal(self.t, Failure::TooManySteps));
        }
        self.attempts += 1;
        let remaining = problem.t_end - self.t;
        let h = self.h.min(settings.max_step).min(limit);
        if h < smallest_step(problem, self.t) && h < remaining {
            return Err(Halt::fatal(self.t, Failure::StepUnderflow { step: h }));
        }
        // Stretching a step that nearly reaches the end avoids a sliver of a last step.
        let stretch = self.t + 1.01 * h >= problem.t_end && remaining <= settings.max_step;
        Ok(if stretch { remaining } else { h })
    }
}

/// Below this a step is either forbidden by the settings or lost in the rounding of t.
fn smallest_step(problem: &Problem, t: f64) -> f64 {
    let resolution = 8.0 * f64::EPSILON * t.abs().max(problem.t0.abs()).max(problem.t_end.abs());
    problem
        .settings
        .min_step
        .max(resolution)
        .max(f64::MIN_POSITIVE)
}

/// A first step from the sizes of y and dy/dt and an estimate of the second derivative, after
/// Hairer, Nørsett and Wanner (Solving ODEs I, II.4): such that the first step's error is modest.
fn initial_step(
    stepper: &mut dyn AdaptiveStepper,
    eval: &mut Evaluator,
    problem: &Problem,
    y0: &[f64],
) -> Result<f64, Halt> {
    let Problem {
        t0,
        t_end,
        settings,
    } = *problem;
    let f0 = stepper.derivative().to_vec();
    let controlled = settings.controlled_len(y0.len());
    let scale: Vec<f64> = y0[..controlled]
        .iter()
        .map(|y| settings.atol + settings.rtol * y.abs())
        .collect();
    let size_y = scaled_rms(&y0[..controlled], &scale);
    let size_f = scaled_rms(&f0[..controlled], &scale);
    let guess = if size_y < 1e-5 || size_f < 1e-5 {
        1e-6
    } else {
        0.01 * size_y / size_f
    };
    let guess = if guess.is_normal() { guess } else { 1e-6 };
    let guess = guess.min(settings.max_step).min(t_end - t0);
    let y1: Vec<f64> = (0..y0.len()).map(|i| y0[i] + guess * f0[i]).collect();
    let mut f1 = vec![0.0; y0.len()];
    match eval.rhs(t0 + guess, &y1, &mut f1) {
        Ok(()) => {}
        // Whatever lies ahead is not finite: start small and let the step control find out more.
        Err(Halt::NotFinite { .. }) => return Ok(guess * 1e-3),
        Err(fatal) => return Err(fatal),
    }
    let change: Vec<f64> = (0..y0.len()).map(|i| (f1[i] - f0[i]) / guess).collect();
    let size_change = scaled_rms(&change[..controlled], &scale);
    let largest = size_f.max(size_change);
    let from_curvature = match largest <= 1e-15 {
        true => (guess * 1e-3).max(1e-6),
        false => (0.01 / largest).powf(1.0 / (stepper.order() as f64 + 1.0)),
    };
    // A curvature too large to represent would suggest a zero step: fall back to the guess.
    let from_curvature = if from_curvature.is_normal() {
        from_curvature
    } else {
        guess
    };
    Ok((100.0 * guess).min(from_curvature).min(settings.max_step))
}

fn scaled_rms(values: &[f64], scale: &[f64]) -> f64 {
    let sum: f64 = values.iter().zip(scale).map(|(v, s)| (v / s).powi(2)).sum();
    (sum / values.len().max(1) as f64).sqrt()
}
