//! Integrators for ordinary differential equations `dy/dt = f(t, y)`, independent of mechanics.
//!
//! The methods share one entry point, [`integrate`], which takes the steps of an
//! [`Integration`] to the end (a caller may take them one by one):
//! - [`Method::Rk4`]: the classic fixed-step Runge–Kutta method of order 4;
//! - [`Method::DormandPrince`]: the adaptive explicit Dormand–Prince 5(4) pair with dense output;
//! - [`Method::Dop853`]: the adaptive explicit 8(5,3) pair DOP853 with its dense output of
//!   order 7, for tight tolerances;
//! - [`Method::Rosenbrock`]: the adaptive linearly implicit Rosenbrock-W method ROS34PW2 for stiff
//!   problems, its Jacobian kept across steps;
//! - [`Method::Rodas4`]: the adaptive Rosenbrock method RODAS4 of order 4 for stiff problems, its
//!   Jacobian formed at every step;
//! - [`Method::Radau5`]: the adaptive implicit Runge–Kutta method Radau IIA of order 5 for stiff
//!   problems, its Jacobian kept across steps while its Newton iteration converges fast;
//! - [`Method::Automatic`]: Dormand–Prince, and Radau IIA where the problem is stiff (ROS34PW2
//!   on a system with tangent directions).
//!
//! Values at output times between steps come from each method's interpolant, so asking for many
//! outputs never shortens the steps.

mod control;
mod dop853;
pub mod dopri5;
mod driver;
mod evaluator;
mod events;
mod held_steps;
mod hermite;
mod jacobian;
mod march;
mod outcome;
mod output;
pub mod radau;
mod rk4;
pub mod rosenbrock;
mod settings;
pub mod stability;
mod stepping;
mod switching;
mod system;

pub use control::error_norm;
pub use hermite::HermiteSegment;
pub use outcome::InputError;
pub use outcome::{Failure, IntegrationError, StabilityBound, Stats, StepError};
pub use settings::{Interrupt, Method, Settings};
pub use stability::jacobian_product;
pub use stepping::Integration;
pub use system::Observer;
pub use system::{CallbackError, OdeSystem};

/// Integrates from `t0` to `t_end`, calling `observer(t, y)` at every time in `outputs` (sorted,
/// within `[t0, t_end]`) as soon as the integration has passed it, and returns the state at
/// `t_end` with the work done.
///
/// Values at output times between steps come from dense output (cubic Hermite for RK4 and
/// Rosenbrock, the order-4 interpolant for Dormand–Prince, order 7 for DOP853); an output time that coincides with a
/// step end gets that step's state exactly, after [`OdeSystem::project`]. Outputs delivered before
/// a failure stay delivered.
///
/// ```
/// use lsdc::integrate::{integrate, CallbackError, Method, OdeSystem, Settings};
///
/// struct Decay;
/// impl OdeSystem for Decay {
///     fn dimension(&self) -> usize {
///         1
///     }
///     fn rhs(&mut self, _t: f64, y: &[f64], dydt: &mut [f64]) -> Result<(), CallbackError> {
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
    let invalid = |error: InputError| IntegrationError {
        time: t0,
        failure: Failure::InvalidInput(error),
        stats: Box::default(),
    };
    check_problem(system.dimension(), t0, y0, t_end, outputs).map_err(invalid)?;
    let mut integration = Integration::new(method, system, t0, y0, outputs.to_vec(), settings)?;
    while integration.time() < t_end {
        integration.step(system, t_end, observer)?;
    }
    integration.deliver_rest(system, observer)?;
    Ok((integration.state().to_vec(), integration.stats()))
}

fn check_problem(
    dimension: usize,
    t0: f64,
    y0: &[f64],
    t_end: f64,
    outputs: &[f64],
) -> Result<(), InputError> {
    if y0.len() != dimension {
        return Err(InputError::StateLength {
            given: y0.len(),
            dimension,
        });
    }
    if !(t0.is_finite() && t_end.is_finite() && t0 <= t_end) {
        return Err(InputError::TimeSpan { t0, t_end });
    }
    if outputs.iter().any(|&t| !(t0..=t_end).contains(&t)) {
        return Err(InputError::OutputOutsideSpan { t0, t_end });
    }
    if outputs.windows(2).any(|pair| pair[0] > pair[1]) {
        return Err(InputError::UnsortedOutputs);
    }
    Ok(())
}
