//! Which method integrates, and within which tolerances and limits.

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
    Rosenbrock,
    /// RODAS4, a Rosenbrock method of order 4 for stiff problems, with a Jacobian formed at
    /// every step: the system's own ([`OdeSystem::jacobian`](super::OdeSystem::jacobian)) when
    /// it gives one, finite differences otherwise (along the system's tangent directions when it
    /// gives them).
    Rodas4,
    /// Dormand–Prince where the problem is not stiff, RODAS4 where it is: the method changes
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
    /// Most steps (accepted and rejected) before giving up with [`Failure::TooManySteps`](super::outcome::Failure::TooManySteps).
    pub max_steps: usize,
    /// How many leading components the step control watches (all when `None`): the others are
    /// carried along, like a quadrature of the solution, without changing the steps.
    pub controlled: Option<usize>,
}

impl Settings {
    /// How many leading components of a state of `dimension` the error control watches.
    pub(super) fn controlled_len(&self, dimension: usize) -> usize {
        self.controlled.unwrap_or(dimension).min(dimension)
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
        }
    }
}
