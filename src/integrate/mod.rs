//! Integrators for ordinary differential equations `dy/dt = f(t, y)`, independent of mechanics.
//!
//! Three methods share one entry point, [`integrate`]:
//! - [`Method::Rk4`]: the classic fixed-step Runge–Kutta method of order 4;
//! - [`Method::DormandPrince`]: the adaptive explicit Dormand–Prince 5(4) pair with dense output;
//! - [`Method::Rosenbrock`]: the adaptive linearly implicit RODAS3 method for stiff problems.
//!
//! Values at output times between steps come from each method's interpolant, so asking for many
//! outputs never shortens the steps.

mod control;
mod dopri5;
mod driver;
mod evaluator;
mod hermite;
mod output;
mod rk4;
mod rosenbrock;

use std::fmt;

/// A system of first-order ordinary differential equations.
pub trait OdeSystem {
    /// Length of the state vector.
    fn dimension(&self) -> usize;
    /// Writes dy/dt at (t, y) into `dydt`. An `Err` stops the integration with that message
    /// (e.g. a singular mass matrix).
    fn rhs(&mut self, t: f64, y: &[f64], dydt: &mut [f64]) -> Result<(), String>;
    /// Called after each accepted step with the new state: may move it back onto an invariant
    /// manifold (constraints of a closed-loop mechanism). Returns whether `y` changed.
    ///
    /// The integration continues from the projected state, and outputs at the step's end get it;
    /// outputs strictly inside a step still come from the step's interpolant. Not called on the
    /// initial state, which the caller makes consistent. An `Err` stops the integration like an
    /// `Err` from [`OdeSystem::rhs`].
    fn project(&mut self, _t: f64, _y: &mut [f64]) -> Result<bool, String> {
        Ok(false)
    }
}

/// Receives the state at each output time; an `Err` stops the integration with that message.
pub type Observer<'o> = dyn FnMut(f64, &[f64]) -> Result<(), String> + 'o;

/// Which integration method to use.
#[derive(Clone, Debug, PartialEq)]
pub enum Method {
    /// Classic Runge–Kutta of order 4 with this fixed step; the last step is shortened to land on
    /// the end time. Ignores the tolerances.
    Rk4 { step: f64 },
    /// Dormand–Prince 5(4), adaptive, for non-stiff problems.
    DormandPrince,
    /// RODAS3, a Rosenbrock method of order 3 with a finite-difference Jacobian, for stiff problems.
    Rosenbrock,
}

/// Tolerances and limits of the adaptive methods (only `max_steps` applies to RK4).
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
    /// Smallest step allowed before giving up with [`Failure::StepUnderflow`].
    pub min_step: f64,
    /// Most steps (accepted and rejected) before giving up with [`Failure::TooManySteps`].
    pub max_steps: usize,
    /// How many leading components the step control watches (all when `None`): the others are
    /// carried along, like a quadrature of the solution, without changing the steps.
    pub controlled: Option<usize>,
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

/// Work done by an integration.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Stats {
    /// Accepted steps.
    pub steps: usize,
    /// Rejected step attempts (error too large, or non-finite values in the attempt).
    pub rejected: usize,
    /// Calls of [`OdeSystem::rhs`], including those made for finite-difference Jacobians.
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

/// Integrates from `t0` to `t_end`, calling `observer(t, y)` at every time in `outputs` (sorted,
/// within `[t0, t_end]`) as soon as the integration has passed it, and returns the state at
/// `t_end` with the work done.
///
/// Values at output times between steps come from dense output (cubic Hermite for RK4 and
/// Rosenbrock, the order-4 interpolant for Dormand–Prince); an output time that coincides with a
/// step end gets that step's state exactly, after [`OdeSystem::project`]. Outputs delivered before
/// a failure stay delivered.
///
/// ```
/// use lsdc::integrate::{integrate, Method, OdeSystem, Settings};
///
/// struct Decay;
/// impl OdeSystem for Decay {
///     fn dimension(&self) -> usize {
///         1
///     }
///     fn rhs(&mut self, _t: f64, y: &[f64], dydt: &mut [f64]) -> Result<(), String> {
///         dydt[0] = -y[0];
///         Ok(())
///     }
/// }
///
/// let mut samples = Vec::new();
/// let mut observer = |t: f64, y: &[f64]| {
///     samples.push((t, y[0]));
///     Ok(())
/// };
/// let settings = Settings { rtol: 1e-8, atol: 1e-10, ..Settings::default() };
/// let (y, stats) =
///     integrate(&Method::DormandPrince, &mut Decay, 0.0, &[1.0], 2.0, &[0.5, 1.0], &settings, &mut observer).unwrap();
/// assert!((y[0] - (-2.0f64).exp()).abs() < 1e-8);
/// assert_eq!(samples.len(), 2);
/// assert!(stats.steps > 0);
/// ```
#[allow(clippy::too_many_arguments)]
pub fn integrate(
    method: &Method,
    system: &mut dyn OdeSystem,
    t0: f64,
    y0: &[f64],
    t_end: f64,
    outputs: &[f64],
    settings: &Settings,
    observer: &mut Observer,
) -> Result<(Vec<f64>, Stats), IntegrationError> {
    let invalid = |message: String| IntegrationError {
        time: t0,
        failure: Failure::InvalidInput(message),
        stats: Stats::default(),
    };
    check_problem(system.dimension(), t0, y0, t_end, outputs).map_err(invalid)?;
    check_settings(method, settings).map_err(invalid)?;
    let problem = driver::Problem {
        t0,
        y0,
        t_end,
        outputs,
        settings,
    };
    match method {
        Method::Rk4 { step } => rk4::integrate(system, &problem, *step, observer),
        Method::DormandPrince => driver::integrate_adaptive(
            &mut dopri5::DormandPrince::new(y0.len(), settings),
            system,
            &problem,
            observer,
        ),
        Method::Rosenbrock => driver::integrate_adaptive(
            &mut rosenbrock::Rodas3::new(y0.len(), settings),
            system,
            &problem,
            observer,
        ),
    }
}

fn check_problem(
    dimension: usize,
    t0: f64,
    y0: &[f64],
    t_end: f64,
    outputs: &[f64],
) -> Result<(), String> {
    if y0.len() != dimension {
        return Err(format!(
            "the initial state has {} values, the system {dimension}",
            y0.len()
        ));
    }
    if !(t0.is_finite() && t_end.is_finite() && t0 <= t_end) {
        return Err(format!(
            "the time span [{t0}, {t_end}] is not a finite forward interval"
        ));
    }
    if outputs.iter().any(|&t| !(t0..=t_end).contains(&t)) {
        return Err(format!("an output time lies outside [{t0}, {t_end}]"));
    }
    if outputs.windows(2).any(|pair| pair[0] > pair[1]) {
        return Err("the output times are not sorted".to_string());
    }
    Ok(())
}

fn check_settings(method: &Method, settings: &Settings) -> Result<(), String> {
    if let Method::Rk4 { step } = method {
        if !(step.is_finite() && *step > 0.0) {
            return Err(format!("the RK4 step {step} is not a positive number"));
        }
        return Ok(());
    }
    let Settings {
        rtol,
        atol,
        initial_step,
        max_step,
        min_step,
        ..
    } = settings;
    if !(*rtol >= 0.0 && *atol >= 0.0 && rtol + atol > 0.0 && rtol.is_finite() && atol.is_finite())
    {
        return Err(format!(
            "the tolerances rtol = {rtol}, atol = {atol} must be non-negative, not both zero"
        ));
    }
    if !(*max_step > 0.0 && *min_step >= 0.0 && min_step <= max_step) {
        return Err(format!(
            "the step limits [{min_step}, {max_step}] are not an interval of positive steps"
        ));
    }
    if initial_step.is_some_and(|h| !(h.is_finite() && h > 0.0)) {
        return Err("the initial step must be a positive number".to_string());
    }
    Ok(())
}
