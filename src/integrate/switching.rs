//! Stiffness switching between the explicit Dormand–Prince pair and an implicit method (Radau IIA
//! of order 5 on trees, the Rosenbrock method ROS34PW2 on closed loops), as LSODA switches between Adams and BDF (Petzold, *SIAM J. Sci. Stat. Comput.* 4, 1983): the
//! explicit method steps while nothing stiff holds its steps at its stability boundary, the
//! implicit one while something does.
//!
//! - **To the implicit method**: Dormand–Prince's estimate h |λ| of the stiffest eigenvalue
//!   (`DormandPrince::stiffness`, Hairer and Wanner's test in DOPRI5) is above `NEAR_STIFF` on
//!   `PERSISTENCE` accepted steps in a row: the steps are within a factor of three of those
//!   its stability allows (`STIFF`), so they cannot grow much while a stiff component is there,
//!   whereas Radau IIA's are bounded by accuracy alone. Waiting for `STIFF` itself, as DOPRI5
//!   does to report stiffness, kept the governor at 1e-10 on Dormand–Prince's accuracy-bound
//!   steps (h |λ| between 1 and 3.25) until t = 0.56. Or, after an accepted step, the
//!   spectral radius of ∂f/∂y says that the steps are held by stability (`held_steps.rs`):
//!   the stage estimate measures ∂f/∂y only along what the last stages differ by, and a stiff
//!   mode the motion does not excite (a stiff spring released on its slow manifold) kept
//!   Dormand–Prince at its stability limit, or not, by accident.
//! - **Back to the explicit method**: the spectral radius ρ of the implicit method's Jacobian
//!   gives h ρ below `EXPLICIT_MARGIN` times the explicit method's boundary along the stiff
//!   mode (`STIFF` on the real axis, 0.997 for an undamped oscillation: `HeldSteps::boundary`)
//!   on `PERSISTENCE` accepted steps in a row: the explicit method would be stable at the
//!   steps the implicit one takes, and costs less per step at equal accuracy (order 5 against
//!   4, and no Jacobian).
//!
//! Where the implicit method was left for steps ρ allowed, it is taken again only where the
//! explicit steps fall below `RETURN_RATIO` of the longest step it took in its last stretch, so
//! that the two do not take turns on a mildly stiff stretch where neither gains. The longest, not
//! the last: after an impact the implicit method starts again with short steps, which ρ allows
//! the explicit method too, and a ratio to those kept the explicit method at its stability
//! limit for the rest of the run (a stiff pendulum on its stop: 96,761 steps instead of 1,907).
//!
//! Both comparisons weigh the steps by what a step of each method costs, in evaluations of f
//! per accepted step as measured on the run (`Cost`): a step of the implicit method forms a
//! Jacobian, one evaluation per direction, so on a mechanism with many states it costs several
//! explicit steps, and it gains only where its steps are longer by more than that. A controlled
//! Delta robot (21 states, a mode at 2.1e4 /s, tolerance 1e-8) showed why: the implicit steps,
//! held by accuracy at h ρ ≈ 3.2, were no longer than the explicit method's stable ones, at 31
//! evaluations each against 7, and the run took 9 times the explicit method's time. So the
//! explicit method is taken back where h ρ is below `EXPLICIT_MARGIN` times its boundary times
//! the ratio of the costs (the time the explicit method would take at its stable steps against
//! the implicit one's), and the implicit method again only where the explicit steps fall below
//! the implicit one's longest divided by that ratio.

use super::control::StepController;
use super::dopri5::DormandPrince;
use super::driver::AdaptiveStepper;
use super::evaluator::{Evaluator, Halt};
use super::held_steps::HeldSteps;
use super::outcome::Stats;
use super::radau::Radau5;
use super::rosenbrock::RosenbrockW;
use super::settings::Settings;

/// The implicit method of the pair.
pub(super) enum Stiff {
    /// A Rosenbrock method (ROS34PW2 on a system with tangent directions).
    Rosenbrock(RosenbrockW),
    /// Radau IIA of order 5.
    Radau(Radau5),
}

impl Stiff {
    fn stepper(&mut self) -> &mut dyn AdaptiveStepper {
        match self {
            Stiff::Rosenbrock(method) => method,
            Stiff::Radau(method) => method,
        }
    }

    fn spectral_radius_below(&self, limit: f64) -> bool {
        match self {
            Stiff::Rosenbrock(method) => method.spectral_radius_below(limit),
            Stiff::Radau(method) => method.spectral_radius_below(limit),
        }
    }

    fn adopt(&mut self, derivative: &[f64]) {
        match self {
            Stiff::Rosenbrock(method) => method.adopt(derivative),
            Stiff::Radau(method) => method.adopt(derivative),
        }
    }

    fn derivative(&self) -> &[f64] {
        match self {
            Stiff::Rosenbrock(method) => method.derivative(),
            Stiff::Radau(method) => method.derivative(),
        }
    }

    fn interpolate(&self, t: f64, out: &mut [f64]) {
        match self {
            Stiff::Rosenbrock(method) => method.interpolate(t, out),
            Stiff::Radau(method) => method.interpolate(t, out),
        }
    }
}

/// h |λ| above which a Dormand–Prince step is taken as held by stability: its stability region
/// reaches about 3.3 along the negative real axis.
const STIFF: f64 = 3.25;
/// h |λ| above which Dormand–Prince's steps are near enough that limit for the implicit method
/// to be taken. None of the non-stiff examples reaches it on 15 steps in a row, at its own
/// tolerance or at 1e-6 (the double pendulum, the heavy top and the four-bar not even 0.3).
const NEAR_STIFF: f64 = 1.0;
/// Accepted steps in a row that must agree before the method changes.
const PERSISTENCE: usize = 15;
/// The fraction of `STIFF` below which h ρ of the implicit steps says the explicit method
/// would be stable at them with room to spare.
const EXPLICIT_MARGIN: f64 = 0.5;
/// How much shorter than the implicit method's last steps the explicit ones must be for the
/// implicit method to be taken again.
const RETURN_RATIO: f64 = 0.67;
/// Evaluations of f per accepted step of Dormand–Prince before any is measured: six stages, the
/// seventh being the next step's first.
const EXPLICIT_EVALUATIONS: f64 = 6.0;

/// The evaluations of f a method spent (rejected attempts, Jacobians and stiffness checks
/// included) and the steps it took.
#[derive(Clone, Copy, Default)]
struct Cost {
    evaluations: usize,
    steps: usize,
}

impl Cost {
    fn per_step(&self) -> Option<f64> {
        (self.steps > 0).then(|| self.evaluations as f64 / self.steps as f64)
    }
}

pub(super) struct Switching {
    explicit: DormandPrince,
    implicit: Stiff,
    /// Whether the explicit method's steps are held by its stability region, from the spectral
    /// radius of ∂f/∂y (`held_steps.rs`).
    held: HeldSteps,
    /// Which method takes the next attempt.
    stiff: bool,
    /// Which method took the last accepted step (whose interpolant serves the outputs).
    last_stiff: bool,
    /// Accepted steps in a row that called for the other method.
    agreeing: usize,
    /// The longest step of the implicit method in its current stretch, or in its last one while
    /// the explicit method steps; infinite before it is first taken.
    longest_implicit: f64,
    /// The controller of the method just taken, for the driver.
    switched: Option<StepController>,
    /// What the explicit and the implicit method's steps cost, and the evaluations counted when
    /// the last step ended.
    explicit_cost: Cost,
    implicit_cost: Cost,
    evaluations_counted: usize,
    /// Steps taken by the implicit method, and changes of method.
    pub(super) implicit_steps: usize,
    pub(super) switches: usize,
    /// When the implicit method first took over.
    pub(super) stiff_from: Option<f64>,
}

impl Switching {
    pub(super) fn new(implicit: Stiff, dimension: usize, settings: &Settings) -> Self {
        Switching {
            explicit: DormandPrince::new(dimension, settings),
            implicit,
            held: HeldSteps::new(dimension, settings.controlled_len(dimension)),
            stiff: false,
            last_stiff: false,
            agreeing: 0,
            longest_implicit: f64::INFINITY,
            switched: None,
            explicit_cost: Cost::default(),
            implicit_cost: Cost::default(),
            evaluations_counted: 0,
            implicit_steps: 0,
            switches: 0,
            stiff_from: None,
        }
    }

    fn current(&mut self) -> &mut dyn AdaptiveStepper {
        match self.stiff {
            true => self.implicit.stepper(),
            false => &mut self.explicit,
        }
    }

    /// How many explicit steps one implicit step costs, as measured on the run (1 before the
    /// implicit method has taken a step).
    fn cost_ratio(&self) -> f64 {
        let explicit = self
            .explicit_cost
            .per_step()
            .unwrap_or(EXPLICIT_EVALUATIONS);
        match self.implicit_cost.per_step() {
            Some(implicit) => (implicit / explicit).max(1.0),
            None => 1.0,
        }
    }

    /// Counts the accepted step of size `h`, ending at `t`, towards a change of method, and
    /// changes when enough agree.
    fn watch(&mut self, t: f64, h: f64) {
        let calls_for_other = if self.stiff {
            let limit = EXPLICIT_MARGIN * self.held.boundary(STIFF) * self.cost_ratio() / h;
            self.implicit.spectral_radius_below(limit)
        } else {
            self.returning(h) && self.explicit.stiffness() > NEAR_STIFF
        };
        self.agreeing = if calls_for_other {
            self.agreeing + 1
        } else {
            0
        };
        if self.agreeing >= PERSISTENCE {
            self.change(t);
        }
    }

    /// Whether a step `h` of the explicit method is short enough against the implicit method's
    /// last stretch, at their costs, for the implicit method to be taken again
    /// (`RETURN_RATIO`).
    fn returning(&self, h: f64) -> bool {
        h < RETURN_RATIO * self.longest_implicit / self.cost_ratio()
    }

    /// Takes the other method from the point reached at `t`.
    fn change(&mut self, t: f64) {
        self.agreeing = 0;
        self.switches += 1;
        if self.stiff {
            self.explicit.adopt(self.implicit.derivative());
            self.switched = Some(self.explicit.controller());
            self.held.forget();
        } else {
            self.stiff_from.get_or_insert(t);
            self.longest_implicit = 0.0;
            self.implicit.adopt(self.explicit.derivative());
            self.switched = Some(self.implicit.stepper().controller());
        }
        self.stiff = !self.stiff;
    }
}

impl AdaptiveStepper for Switching {
    fn order(&self) -> u32 {
        self.explicit.order()
    }

    fn controller(&self) -> StepController {
        self.explicit.controller()
    }

    fn step_limit(&self) -> f64 {
        match (self.stiff, &self.implicit) {
            (true, Stiff::Radau(method)) => method.step_limit(),
            _ => f64::INFINITY,
        }
    }

    fn switched_controller(&mut self) -> Option<StepController> {
        self.switched.take()
    }

    fn start(&mut self, eval: &mut Evaluator, t: f64, y: &[f64]) -> Result<(), Halt> {
        self.current().start(eval, t, y)
    }

    fn derivative(&self) -> &[f64] {
        match self.stiff {
            true => self.implicit.derivative(),
            false => self.explicit.derivative(),
        }
    }

    fn attempt(
        &mut self,
        eval: &mut Evaluator,
        t: f64,
        y: &[f64],
        h: f64,
        y_new: &mut [f64],
    ) -> Result<f64, Halt> {
        self.current().attempt(eval, t, y, h, y_new)
    }

    fn prepare_interpolation(
        &mut self,
        eval: &mut Evaluator,
        t: f64,
        y: &[f64],
        h: f64,
    ) -> Result<(), Halt> {
        self.current().prepare_interpolation(eval, t, y, h)
    }

    fn accept(&mut self, t: f64, y: &[f64], h: f64, y_new: &[f64]) {
        self.current().accept(t, y, h, y_new);
        self.last_stiff = self.stiff;
        if self.stiff {
            self.implicit_steps += 1;
            self.longest_implicit = self.longest_implicit.max(h);
        }
        self.watch(t + h, h);
    }

    fn interpolate(&self, t: f64, out: &mut [f64]) {
        match self.last_stiff {
            true => self.implicit.interpolate(t, out),
            false => self.explicit.interpolate(t, out),
        }
    }

    fn after_step(&mut self, eval: &mut Evaluator, t: f64, y: &[f64], h: f64) {
        let spent = eval.stats.rhs_evaluations - self.evaluations_counted;
        let cost = match self.last_stiff {
            true => &mut self.implicit_cost,
            false => &mut self.explicit_cost,
        };
        cost.evaluations += spent;
        cost.steps += 1;
        // A stiffness check's evaluations, below, count towards the next step.
        self.evaluations_counted = eval.stats.rhs_evaluations;
        if self.stiff || !self.returning(h) {
            return;
        }
        if (self.held).held_after(eval, (t, y), h, self.explicit.stiffness()) {
            self.change(t);
        }
    }

    fn count(&self, stats: &mut Stats) {
        stats.stiff_steps = self.implicit_steps;
        stats.method_switches = self.switches;
        stats.stiff_from = self.stiff_from;
    }
}
