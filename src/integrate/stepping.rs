//! An integration that its caller advances step by step ([`Integration`]): the method's state
//! between steps, kept apart from the system it integrates, which each step borrows. The whole
//! integration of [`integrate`](super::integrate) is its steps to the end, and a simulation that
//! a program owns steps the same way (MuJoCo's `mj_step` over one `mjData`, rapier's
//! `PhysicsPipeline::step`).

use super::driver::{AdaptiveMarch, AdaptiveStepper};
use super::evaluator::{all_finite, Evaluator, Halt};
use super::march::{Marching, Problem};
use super::outcome::{Failure, InputError, IntegrationError, Stats};
use super::output::Outputs;
use super::rk4::Rk4March;
use super::settings::{Method, Settings};
use super::system::{Observer, OdeSystem};
use super::{dop853, dopri5, radau, rosenbrock, switching};

/// An integration from (t0, y0) with one of the methods of [`Method`], advanced by
/// [`step`](Integration::step) towards an end its caller chooses at each step; outputs at the
/// times given at its start, delivered to an observer as the steps pass them.
///
/// ```
/// use lsdc::integrate::{CallbackError, Integration, Method, OdeSystem, Settings};
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
/// let settings = Settings { rtol: 1e-10, atol: 1e-12, ..Settings::default() };
/// let mut integration =
///     Integration::new(&Method::DormandPrince, &mut Decay, 0.0, &[1.0], Vec::new(), &settings)
///         .unwrap();
/// for end in [0.5, 1.0] {
///     while integration.time() < end {
///         integration.step(&mut Decay, end, &mut |_, _| Ok(())).unwrap();
///     }
///     // Each end is landed on exactly.
///     assert_eq!(integration.time(), end);
///     assert!((integration.state()[0] - (-end).exp()).abs() < 1e-10);
/// }
/// ```
pub struct Integration {
    settings: Settings,
    t0: f64,
    march: Box<dyn Marching>,
    /// Whether the first step started the method, and whether the next must start it again
    /// (`Integration::restart`).
    started: bool,
    restart: bool,
    outputs: Outputs,
    /// What the evaluations counted so far.
    stats: Stats,
    /// Why the integration stopped, once it did: every later step says it again.
    failure: Option<IntegrationError>,
}

impl Integration {
    /// An integration of `system` from (t0, y0) with `method`, its outputs at `outputs` (sorted,
    /// from t0 on). Nothing is evaluated until the first step, but what the automatic method
    /// reads to choose its stiff method.
    pub fn new(
        method: &Method,
        system: &mut dyn OdeSystem,
        t0: f64,
        y0: &[f64],
        outputs: Vec<f64>,
        settings: &Settings,
    ) -> Result<Integration, IntegrationError> {
        let invalid = |error: InputError| IntegrationError {
            time: t0,
            failure: Failure::InvalidInput(error),
            stats: Box::default(),
        };
        let dimension = system.dimension();
        if y0.len() != dimension {
            let given = y0.len();
            return Err(invalid(InputError::StateLength { given, dimension }));
        }
        if !t0.is_finite() {
            return Err(invalid(InputError::TimeSpan { t0, t_end: t0 }));
        }
        if outputs.first().is_some_and(|&t| t < t0) {
            let t_end = outputs.last().copied().unwrap_or(t0);
            return Err(invalid(InputError::OutputOutsideSpan { t0, t_end }));
        }
        if outputs.windows(2).any(|pair| pair[0] > pair[1]) {
            return Err(invalid(InputError::UnsortedOutputs));
        }
        check_settings(method, settings).map_err(invalid)?;
        if !all_finite(y0) {
            return Err(Halt::fatal(t0, Failure::NotFinite).into_error(Stats::default()));
        }
        Ok(Integration {
            march: march(method, system, t0, y0, settings),
            settings: settings.clone(),
            t0,
            started: false,
            restart: false,
            outputs: Outputs::new(outputs, dimension),
            stats: Stats::default(),
            failure: None,
        })
    }

    /// The time of the current point.
    pub fn time(&self) -> f64 {
        self.march.time()
    }

    /// The state at the current point.
    pub fn state(&self) -> &[f64] {
        self.march.state()
    }

    /// The work done so far.
    pub fn stats(&self) -> Stats {
        let mut stats = self.stats.clone();
        self.march.count(&mut stats);
        stats
    }

    /// Takes one step of `system` from the current point towards `t_end` (which must lie ahead),
    /// landing on it exactly if the step reaches it; `observer` receives the outputs it passes
    /// (after [`OdeSystem::observe`]). The first step starts the method, delivering the outputs
    /// at the start. After a failure, the integration stays where it failed and every step
    /// returns the failure.
    pub fn step(
        &mut self,
        system: &mut dyn OdeSystem,
        t_end: f64,
        observer: &mut Observer,
    ) -> Result<(), IntegrationError> {
        if let Some(failure) = &self.failure {
            return Err(failure.clone());
        }
        let t = self.time();
        if !(t_end > t && t_end.is_finite()) {
            let invalid = InputError::TimeSpan { t0: t, t_end };
            return Err(Halt::fatal(t, Failure::InvalidInput(invalid)).into_error(self.stats()));
        }
        let mut eval = Evaluator::resume(system, &mut self.stats);
        let problem = Problem {
            t0: self.t0,
            t_end,
            settings: &self.settings,
        };
        let (march, outputs) = (&mut self.march, &mut self.outputs);
        let started = match (self.started, self.restart) {
            (true, false) => Ok(()),
            (true, true) => march.restart(&mut eval),
            (false, _) => outputs
                .deliver_start(self.t0, march.state(), (&mut eval, observer))
                .and_then(|()| march.start(&mut eval, &problem)),
        };
        (self.started, self.restart) = (true, false);
        let stepped = started.and_then(|()| march.step(&mut eval, &problem, outputs, observer));
        stepped.map_err(|halt| {
            let failure = halt.made_fatal().into_error(self.stats());
            self.failure = Some(failure.clone());
            failure
        })
    }

    /// Says that the system's derivative changed at the current point, between two steps (an
    /// effort set from outside): the next step starts the method again from there, as after
    /// an event, rather than reuse what the last step computed at its end.
    pub fn restart(&mut self) {
        self.restart = true;
    }

    /// Changes the state at the current point, between two steps (a sampled controller's
    /// states at its instant): the next step starts the method again from the new state, as
    /// [`restart`](Integration::restart) does. `y` has the system's dimension.
    pub fn set_state(&mut self, y: &[f64]) {
        self.march.state_mut().copy_from_slice(y);
        self.restart = true;
    }

    /// Delivers the outputs not passed yet at the current state (those after the end).
    pub fn deliver_rest(
        &mut self,
        system: &mut dyn OdeSystem,
        observer: &mut Observer,
    ) -> Result<(), IntegrationError> {
        let mut eval = Evaluator::resume(system, &mut self.stats);
        let y = self.march.state();
        let delivered = self.outputs.deliver_rest(y, (&mut eval, observer));
        delivered.map_err(|halt| halt.into_error(self.stats()))
    }
}

/// `method` made for `system` at (t0, y0), not started yet.
fn march(
    method: &Method,
    system: &mut dyn OdeSystem,
    t0: f64,
    y0: &[f64],
    settings: &Settings,
) -> Box<dyn Marching> {
    let n = y0.len();
    let rosenbrock = |scheme| Box::new(rosenbrock::RosenbrockW::new(scheme, n, settings));
    let stepper: Box<dyn AdaptiveStepper> = match method {
        Method::Rk4 { step } => return Box::new(Rk4March::new(t0, y0, *step, settings)),
        Method::DormandPrince => Box::new(dopri5::DormandPrince::new(n, settings)),
        Method::Dop853 => Box::new(dop853::Dop853::new(n, settings)),
        Method::Rosenbrock => rosenbrock(rosenbrock::Scheme::Ros34pw2),
        Method::Rodas4 => rosenbrock(rosenbrock::Scheme::Rodas4),
        Method::Radau5 => Box::new(radau::Radau5::new(n, settings)),
        Method::Automatic => {
            let implicit = stiff_method(system, t0, y0, settings);
            Box::new(switching::Switching::new(implicit, n, settings))
        }
    };
    Box::new(AdaptiveMarch::new(stepper, t0, y0, settings))
}

/// The stiff method of [`Method::Automatic`]: Radau IIA of order 5, except on a system that
/// moves on a manifold (a mechanism's closed loops), whose Jacobian is formed along the
/// manifold's tangent directions only: there the W-method ROS34PW2, whose order holds with any
/// matrix (on a stiff four-bar over 2 s at 1e-8, RODAS4 took 26,460 steps, ROS34PW2 638).
fn stiff_method(
    system: &mut dyn OdeSystem,
    t0: f64,
    y0: &[f64],
    settings: &Settings,
) -> switching::Stiff {
    let n = y0.len();
    match system.tangent_basis(t0, y0) {
        Ok(Some(_)) => switching::Stiff::Rosenbrock(rosenbrock::RosenbrockW::new(
            rosenbrock::Scheme::Ros34pw2,
            n,
            settings,
        )),
        _ => switching::Stiff::Radau(radau::Radau5::new(n, settings)),
    }
}

pub(super) fn check_settings(method: &Method, settings: &Settings) -> Result<(), InputError> {
    if let Method::Rk4 { step } = *method {
        if !(step.is_finite() && step > 0.0) {
            return Err(InputError::Rk4Step { step });
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
    } = *settings;
    if !(rtol >= 0.0 && atol >= 0.0 && rtol + atol > 0.0 && rtol.is_finite() && atol.is_finite()) {
        return Err(InputError::Tolerances { rtol, atol });
    }
    if !(max_step > 0.0 && min_step >= 0.0 && min_step <= max_step) {
        return Err(InputError::StepLimits { min_step, max_step });
    }
    if initial_step.is_some_and(|h| !(h.is_finite() && h > 0.0)) {
        return Err(InputError::InitialStep);
    }
    Ok(())
}
