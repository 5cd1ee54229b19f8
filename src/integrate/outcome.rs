//! What an integration did, and why one stopped early.

use std::fmt;

/// Work done by an integration.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Stats {
    /// Accepted steps.
    pub steps: usize,
    /// Rejected step attempts (error too large, or non-finite values in the attempt).
    pub rejected: usize,
    /// Calls of [`OdeSystem::rhs`], including those made for finite-difference Jacobians.
    ///
    /// [`OdeSystem::rhs`]: super::system::OdeSystem::rhs
    pub rhs_evaluations: usize,
    /// Jacobians formed (Rosenbrock only).
    pub jacobian_evaluations: usize,
    /// LU decompositions of the iteration matrix (Rosenbrock only).
    pub lu_decompositions: usize,
    /// Accepted steps the Rosenbrock method (RODAS4, or ROS34PW2 on a manifold) took, and changes between it and Dormand–Prince
    /// ([`Method::Automatic`](super::settings::Method::Automatic) only).
    pub stiff_steps: usize,
    pub method_switches: usize,
    /// When the implicit method first took over from Dormand–Prince
    /// ([`Method::Automatic`](super::settings::Method::Automatic) only).
    pub stiff_from: Option<f64>,
    /// Events located and acted on ([`OdeSystem::handle_event`]).
    ///
    /// [`OdeSystem::handle_event`]: super::system::OdeSystem::handle_event
    pub events: usize,
    /// The largest local error estimate of a fixed-step method's steps (RK4, the variational
    /// integrator), which nothing controls: where it exceeds the tolerances, the step is too
    /// long for them.
    pub largest_step_error: Option<StepError>,
    /// Where an explicit method's steps were first found held by its stability region, when
    /// [`Settings::stiffness_check`](super::settings::Settings::stiffness_check) asks.
    pub stability_bound: Option<StabilityBound>,
}

/// Steps found held by an explicit method's stability region.
#[derive(Clone, Debug, PartialEq)]
pub struct StabilityBound {
    /// When it was found (the end of the step checked last).
    pub time: f64,
    /// The estimate of the spectral radius of ∂f/∂y there, in 1/s.
    pub rate: f64,
    /// The step taken there.
    pub step: f64,
    /// |h λ| at the method's stability boundary (2.8 for RK4, 3.3 for Dormand–Prince).
    pub limit: f64,
    /// The state there, and the fast mode's direction in it (unit norm over the controlled
    /// components, zero elsewhere): what a caller needs to find what makes the mode fast.
    pub state: Vec<f64>,
    pub direction: Vec<f64>,
}

impl StabilityBound {
    /// The largest stable step: limit / rate.
    pub fn stable_step(&self) -> f64 {
        self.limit / self.rate
    }
}

/// A local error estimate of one step, in the norm the adaptive methods control (at most 1 meets
/// the tolerances), and where the step ended.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepError {
    pub norm: f64,
    pub time: f64,
}

impl StepError {
    /// Keeps the larger of the estimate so far and `norm` at `time` (a non-finite estimate
    /// counts as the largest).
    pub fn keep_largest(largest: &mut Option<StepError>, norm: f64, time: f64) {
        let norm = if norm.is_nan() { f64::INFINITY } else { norm };
        if largest.is_none_or(|e| norm > e.norm) {
            *largest = Some(StepError { norm, time });
        }
    }
}

/// Why an integration stopped early.
#[derive(Clone, Debug, PartialEq)]
pub enum Failure {
    /// A NaN or infinity appeared in the state or its derivative and shrinking the step did not
    /// avoid it.
    NotFinite,
    /// The step size needed for the tolerances fell below `min_step` (or below what the
    /// resolution of `f64` allows at that time).
    StepUnderflow { step: f64 },
    /// `max_steps` were taken before reaching the end time.
    TooManySteps,
    /// The system's `rhs` or `project` returned an error with this message.
    System(String),
    /// The observer returned an error with this message.
    Observer(String),
    /// [`Settings::interrupt`](super::settings::Settings::interrupt) was set to this value.
    Interrupted(usize),
    /// The arguments were inconsistent (wrong state length, unsorted outputs, bad settings...).
    InvalidInput(InputError),
}

/// Arguments of an integration that do not make a problem the method can solve.
#[derive(Clone, Debug, PartialEq)]
pub enum InputError {
    /// The initial state's length differs from the system's dimension.
    StateLength {
        given: usize,
        dimension: usize,
    },
    /// The time span is not finite or runs backwards.
    TimeSpan {
        t0: f64,
        t_end: f64,
    },
    /// An output time lies outside the time span.
    OutputOutsideSpan {
        t0: f64,
        t_end: f64,
    },
    UnsortedOutputs,
    /// The fixed step of RK4 is not a positive number.
    Rk4Step {
        step: f64,
    },
    /// The tolerances are negative, not finite, or both zero.
    Tolerances {
        rtol: f64,
        atol: f64,
    },
    /// The step limits do not make an interval of positive steps.
    StepLimits {
        min_step: f64,
        max_step: f64,
    },
    /// The initial step is not a positive number.
    InitialStep,
}

/// An integration that stopped early: when, why, and the work done until then.
#[derive(Clone, Debug, PartialEq)]
pub struct IntegrationError {
    /// Time at which the failure appeared (for `NotFinite`, the time of the offending evaluation).
    pub time: f64,
    pub failure: Failure,
    /// Boxed, so that a failed integration's `Result` stays small.
    pub stats: Box<Stats>,
}

impl fmt::Display for Failure {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Failure::NotFinite => write!(f, "the state or its derivative is not finite"),
            Failure::StepUnderflow { step } => write!(f, "the step size fell to {step:e}"),
            Failure::TooManySteps => write!(f, "too many steps"),
            Failure::System(message) => write!(f, "{message}"),
            Failure::Observer(message) => write!(f, "{message}"),
            Failure::Interrupted(value) => write!(f, "interrupted ({value})"),
            Failure::InvalidInput(error) => write!(f, "invalid integration input: {error}"),
        }
    }
}

impl fmt::Display for InputError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            InputError::StateLength { given, dimension } => write!(
                f,
                "the initial state has {given} values, the system {dimension}"
            ),
            InputError::TimeSpan { t0, t_end } => write!(
                f,
                "the time span [{t0}, {t_end}] is not a finite forward interval"
            ),
            InputError::OutputOutsideSpan { t0, t_end } => {
                write!(f, "an output time lies outside [{t0}, {t_end}]")
            }
            InputError::UnsortedOutputs => write!(f, "the output times are not sorted"),
            InputError::Rk4Step { step } => {
                write!(f, "the RK4 step {step} is not a positive number")
            }
            InputError::Tolerances { rtol, atol } => write!(
                f,
                "the tolerances rtol = {rtol}, atol = {atol} must be non-negative, not both zero"
            ),
            InputError::StepLimits { min_step, max_step } => write!(
                f,
                "the step limits [{min_step}, {max_step}] are not an interval of positive steps"
            ),
            InputError::InitialStep => write!(f, "the initial step must be a positive number"),
        }
    }
}

impl std::error::Error for InputError {}

impl fmt::Display for IntegrationError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "integration stopped at t = {}: {}",
            self.time, self.failure
        )
    }
}

impl std::error::Error for IntegrationError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match &self.failure {
            Failure::InvalidInput(error) => Some(error),
            _ => None,
        }
    }
}
