//! Which method integrates, and within which tolerances and limits.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;

/// Which integration method to use.
#[derive(Clone, Debug, PartialEq)]
pub enum Method {
    /// Classic Runge–Kutta of order 4 with this fixed step; the last step is shortened to land on
    /// the end time. The tolerances do not change its steps; they measure its error estimate.
    Rk4 { step: f64 },
    /// Dormand–Prince 5(4), adaptive, for non-stiff problems.
    DormandPrince,
    /// DOP853, the 8(5,3) pair of Dormand and Prince, adaptive, for non-stiff problems at tight
    /// tolerances.
    Dop853,
    /// ROS34PW2, a Rosenbrock-W method of order 3 for stiff problems, with a finite-difference
    /// Jacobian kept across steps (along the system's tangent directions when it gives them).
    /// (A run reaches the three stiff methods through `Automatic`; the tests name each.)
    #[cfg_attr(not(lsdc_internals), allow(dead_code))]
    Rosenbrock,
    /// RODAS4, a Rosenbrock method of order 4 for stiff problems, with a Jacobian formed at
    /// every step: the system's own ([`OdeSystem::jacobian`](super::OdeSystem::jacobian)) when
    /// it gives one, finite differences otherwise (along the system's tangent directions when it
    /// gives them).
    #[cfg_attr(not(lsdc_internals), allow(dead_code))]
    Rodas4,
    /// Radau IIA of order 5 (RADAU5's method) for stiff problems, its Jacobian (the system's own
    /// or by finite differences) kept across steps while its Newton iteration converges fast.
    #[cfg_attr(not(lsdc_internals), allow(dead_code))]
    Radau5,
    /// Dormand–Prince where the problem is not stiff, Radau IIA (ROS34PW2 on a system with
    /// tangent directions) where it is: the method changes
    /// between steps when the steps' stability says so (`switching.rs`).
    Automatic,
}

/// Tolerances and limits of the adaptive methods (RK4 takes `max_steps`, and measures its error
/// estimate with the tolerances).
#[derive(Clone, Debug, PartialEq)]
pub struct Settings {
    /// Relative tolerance on each component of the local error.
    pub rtol: f64,
    /// Absolute tolerance on each component of the local error.
    pub atol: f64,
    /// First step to try; estimated from the problem when `None`.
    pub initial_step: Option<f64>,
    /// Largest step allowed.
    pub max_step: f64,
    /// Smallest step allowed before giving up with [`Failure::StepUnderflow`](super::outcome::Failure::StepUnderflow).
    pub min_step: f64,
    /// Most steps (accepted and rejected; RK4's and the others' alike) before giving up with
    /// [`Failure::TooManySteps`](super::outcome::Failure::TooManySteps); 1,000,000 by default.
    pub max_steps: usize,
    /// How many leading components the step control watches (all when `None`): the others are
    /// carried along, like a quadrature of the solution, without changing the steps.
    pub controlled: Option<usize>,
    /// Whether the explicit methods (RK4, Dormand–Prince) check during the run whether their
    /// steps are held by their stability region ([`Stats::stability_bound`]): a few evaluations
    /// every 20 steps.
    ///
    /// [`Stats::stability_bound`]: super::outcome::Stats::stability_bound
    pub stiffness_check: bool,
    /// A flag read between steps: once it is set, the integration stops with
    /// [`Failure::Interrupted`](super::outcome::Failure::Interrupted), outputs delivered so far
    /// kept (a signal handler sets it).
    pub interrupt: Option<Interrupt>,
}

/// A request to stop an integration between two steps: any value but 0, set from anywhere
/// (another thread, a signal handler), which the integration reports back.
#[derive(Clone, Debug, Default)]
pub struct Interrupt(pub Arc<AtomicUsize>);

impl Interrupt {
    /// The value set, if any.
    pub fn requested(&self) -> Option<usize> {
        match self.0.load(Ordering::Relaxed) {
            0 => None,
            value => Some(value),
        }
    }
}

/// Two interrupts are the same when they share their flag.
impl PartialEq for Interrupt {
    fn eq(&self, other: &Self) -> bool {
        Arc::ptr_eq(&self.0, &other.0)
    }
}

impl Settings {
    /// How many leading components of a state of `dimension` the error control watches.
    pub(super) fn controlled_len(&self, dimension: usize) -> usize {
        self.controlled.unwrap_or(dimension).min(dimension)
    }

    /// The value of the interrupt, when one was requested.
    pub(super) fn interrupted(&self) -> Option<usize> {
        self.interrupt.as_ref().and_then(Interrupt::requested)
    }
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            rtol: 1e-6,
            atol: 1e-9,
            initial_step: None,
            max_step: f64::INFINITY,
            min_step: 0.0,
            max_steps: 1_000_000,
            controlled: None,
            stiffness_check: false,
            interrupt: None,
        }
    }
}
