//! What an integration did, and why one stopped early.

use std::fmt;

/// Work done by an integration.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
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
    /// The system's `rhs` or `project` returned this error.
    System(String),
    /// The observer returned this error.
    Observer(String),
    /// The arguments were inconsistent (wrong state length, unsorted outputs, bad settings...).
    InvalidInput(String),
}

/// An integration that stopped early: when, why, and the work done until then.
#[derive(Clone, Debug, PartialEq)]
pub struct IntegrationError {
    /// Time at which the failure appeared (for `NotFinite`, the time of the offending evaluation).
    pub time: f64,
    pub failure: Failure,
    pub stats: Stats,
}

impl fmt::Display for Failure {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Failure::NotFinite => write!(f, "the state or its derivative is not finite"),
            Failure::StepUnderflow { step } => write!(f, "the step size fell to {step:e}"),
            Failure::TooManySteps => write!(f, "too many steps"),
            Failure::System(message) => write!(f, "{message}"),
            Failure::Observer(message) => write!(f, "{message}"),
            Failure::InvalidInput(message) => write!(f, "invalid integration input: {message}"),
        }
    }
}

impl fmt::Display for IntegrationError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "integration stopped at t = {}: {}",
            self.time, self.failure
        )
    }
}

impl std::error::Error for IntegrationError {}
