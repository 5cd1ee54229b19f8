//! A run that its caller owns and advances (MuJoCo's `mj_step` over one `mjData`, rapier's
//! `PhysicsPipeline::step`): the run's system at its state, the integrator between two steps,
//! the sampler observing the steps, and the efforts applied from outside the program between
//! steps (`inputs`). A whole run (`run::run_with`) is its steps to the end of the settings'
//! duration.

use std::sync::Arc;
use std::time::Instant;

use super::clock::thread_cpu_seconds;
use super::inputs::{InputLaw, Inputs};
use super::ode::RunOde;
use super::report::{failure_message, fastest_coordinate, report, Ended, Report, RunFailure};
use super::sample::Sample;
use super::sampler::Sampler;
use super::sampling::SamplingClock;
use super::summary::Summary;
use super::system::MechanicalSystem;
use super::variational::{FixedStep, VariationalMarch};
use crate::dynamics::compiled::EffortScratch;
use crate::dynamics::energy::conservative_forces;
use crate::dynamics::loops::Stabilisation;
use crate::dynamics::mimics;
use crate::dynamics::model::Model;
use crate::integrate::{
    CallbackError, Failure, Integration, IntegrationError, Interrupt, Method,
    Settings as IntegratorSettings,
};
use crate::integrators::Feature;
use crate::prepare::{Integrator, Prepared};

/// A starting state of a prepared mechanism: declared coordinates and rates (for a mechanism
/// with loops, closed ones: the prepared start is).
#[derive(Clone, Copy, Debug)]
pub struct Start<'a> {
    pub coordinates: &'a [f64],
    pub rates: &'a [f64],
}

/// A simulation of a prepared mechanism that its caller advances: [`step`](Simulator::step)
/// takes one step of the integrator the settings name, [`advance_to`](Simulator::advance_to)
/// steps until a time and lands on it; between steps the caller reads the state
/// ([`time`](Simulator::time), [`coordinates`](Simulator::coordinates),
/// [`sample`](Simulator::sample) with the energies and the program's outputs), sets the efforts
/// of its inputs ([`set_inputs`](Simulator::set_inputs), held until set again) or a law of them
/// ([`set_law`](Simulator::set_law), evaluated at every stage of every step), and may start again
/// from another state ([`reset`](Simulator::reset)). The samples at the settings' output times
/// that the steps pass are kept until taken ([`take_samples`](Simulator::take_samples));
/// [`finish`](Simulator::finish) gives the run's report.
pub struct Simulator<'p> {
    prepared: &'p Prepared,
    system: MechanicalSystem<'p>,
    sampler: Sampler<'p>,
    stepping: Stepping,
    /// Whether the work of the non-conservative efforts rides along as one more state.
    tracks_work: bool,
    summary: Summary,
    /// The samples the steps delivered, not taken yet.
    samples: Vec<Sample>,
    interrupt: Option<Interrupt>,
    started: Instant,
    cpu_started: Option<f64>,
    /// Why the run stopped, once it did.
    stopped: Option<IntegrationError>,
    /// The sampling instants of the program's sampled states, which the steps land on.
    sampling: Option<SamplingClock>,
}

/// The integrator between two steps: one of the ODE methods, or the variational integrator.
enum Stepping {
    Ode(Integration),
    Variational(VariationalMarch),
}

impl<'p> Simulator<'p> {
    /// A simulation of `prepared` from its initial state, with efforts applied along the
    /// velocities named in `inputs` (`swing.q` for a revolute join's angle; the names of
    /// [`Model::velocity_name`]), held at zero until set.
    pub fn new(prepared: &'p Prepared, inputs: &[&str]) -> Result<Simulator<'p>, RunFailure> {
        let start = Start {
            coordinates: &prepared.coordinates,
            rates: &prepared.rates,
        };
        Simulator::from_start(prepared, &start, inputs, None)
    }

    /// A simulation from `start`, with `inputs` (see [`Simulator::new`]), stopped between two
    /// steps when `interrupt` is set. Why it cannot start, at time 0.
    pub fn from_start(
        prepared: &'p Prepared,
        start: &Start<'_>,
        inputs: &[&str],
        interrupt: Option<Interrupt>,
    ) -> Result<Simulator<'p>, RunFailure> {
        let model = &prepared.model;
        let settings = &prepared.settings;
        let at_start = |message: String| RunFailure { time: 0.0, message };
        // The program's declared inputs first, held at their start values, then those the
        // caller names besides, held at zero.
        let declared = &model.effort_inputs;
        let names: Vec<&str> = (declared.iter().map(|(name, _)| name.as_str()))
            .chain(inputs.iter().copied())
            .collect();
        let names: Vec<&str> = (names.iter().enumerate())
            .filter(|&(k, name)| !names[..k].contains(name))
            .map(|(_, name)| *name)
            .collect();
        let mut inputs = Inputs::along(input_velocities(model, &names).map_err(at_start)?);
        for (held, (_, start)) in inputs.held.iter_mut().zip(declared) {
            *held = *start;
        }
        if inputs.any() && settings.integrator == Integrator::Symplectic {
            return Err(at_start(
                "the symplectic integrator does not apply inputs (its steps take the program's efforts only): choose `rk4`, `dopri5`, `dop853` or `implicit`".to_string(),
            ));
        }
        let (mut system, mut y0) = start_system(prepared, start, inputs).map_err(at_start)?;
        // The program's states ride along after the motion, from their starting values.
        y0.extend(model.states.iter().map(|state| state.initial));
        let conservative = conservative_forces(model);
        // The work of non-conservative efforts (inputs among them) rides along as one more
        // state (not with the variational integrator, whose steps are its own), nor with native
        // code, which computes the accelerations alone (`simulate --compiled`).
        let complete = conservative.complete && !system.state.inputs.any();
        let tracks_work =
            !complete && settings.integrator != Integrator::Symplectic && prepared.native.is_none();
        if tracks_work {
            y0.push(0.0);
        }
        let sampler = Sampler {
            conservative,
            reactions: settings.reactions,
            outputs: &prepared.outputs,
            output_scratch: EffortScratch::default(),
            pending: Vec::new(),
            unsettled: Vec::new(),
            segment: None,
        };
        let stepping = stepping(prepared, &mut system, &y0, tracks_work, interrupt.clone())
            .map_err(|e| at_start(failure_message(&e.failure, settings.max_steps)))?;
        Ok(Simulator {
            prepared,
            system,
            sampler,
            stepping,
            tracks_work,
            summary: Summary::new(model, complete),
            samples: Vec::new(),
            interrupt,
            started: Instant::now(),
            cpu_started: thread_cpu_seconds(),
            stopped: None,
            sampling: SamplingClock::new(model),
        })
    }

    /// The time of the current state.
    pub fn time(&self) -> f64 {
        match &self.stepping {
            Stepping::Ode(integration) => integration.time(),
            Stepping::Variational(march) => march.time(),
        }
    }

    /// The current state as the integrator holds it: the model's positions then velocities
    /// (quaternions for ball and free joints), then the program's states (`state(x0)`, in the
    /// order of [`Simulator::state_names`]), then the work of the non-conservative efforts when
    /// it is tracked.
    pub fn state(&self) -> Vec<f64> {
        match &self.stepping {
            Stepping::Ode(integration) => integration.state().to_vec(),
            Stepping::Variational(march) => march.state(),
        }
    }

    /// The declared coordinates and rates at the current state (in the order of
    /// `Simulation::coordinate_names`), angles continuous with the last sample.
    pub fn coordinates(&self) -> Result<(Vec<f64>, Vec<f64>), RunFailure> {
        let model = self.system.model;
        let state = self.state();
        let (q, v) = model.split_state(&state[..self.system.dimension()]);
        model
            .declared((self.time(), &q, v), &self.system.state.reference)
            .map_err(|e| self.failure_now(describe_error(&e)))
    }

    /// The sample of the current state: coordinates, rates, energies, momentum, the program's
    /// outputs (and reactions when the settings ask for them), on the loops' constraints.
    pub fn sample(&mut self) -> Result<Sample, RunFailure> {
        let (time, state) = (self.time(), self.state());
        let sampler = &mut self.sampler;
        let sampled = (self.system).sampling(|system| sampler.sample(system, time, &state));
        sampled.map_err(|e| self.failure_now(e.to_string()))
    }

    /// The names of the program's states (`let integral = state(0);`), in their order in
    /// [`Simulator::state`] after the positions and velocities.
    pub fn state_names(&self) -> Vec<String> {
        let states = &self.system.model.states;
        states.iter().map(|state| state.name.clone()).collect()
    }

    /// The values of the program's states at the current state, in the order of
    /// [`Simulator::state_names`].
    pub fn states(&self) -> Vec<f64> {
        let n = self.system.dimension();
        self.state()[n..n + self.system.state_count()].to_vec()
    }

    /// The names of the effort inputs' velocities, in the order of their efforts: the
    /// program's declared inputs (`input swing.q = 0;`), then those named to
    /// [`Simulator::new`] besides.
    pub fn input_names(&self) -> Vec<String> {
        let inputs = &self.system.state.inputs.velocities;
        inputs
            .iter()
            .map(|&v| self.system.model.velocity_name(v))
            .collect()
    }

    /// The values of the program's value inputs, in the order of
    /// [`Simulator::value_input_names`].
    pub fn value_inputs(&self) -> Vec<f64> {
        let states = &self.system.model.states;
        let values = self.states();
        (states.iter().zip(values))
            .filter(|(state, _)| state.input)
            .map(|(_, value)| value)
            .collect()
    }

    /// The names of the program's value inputs (`input voltage = 0;`), in their order among
    /// its states.
    pub fn value_input_names(&self) -> Vec<String> {
        let states = &self.system.model.states;
        (states.iter().filter(|state| state.input))
            .map(|state| state.name.clone())
            .collect()
    }

    /// Sets the input `name` to `value`, held until set again (a zero-order hold): an effort
    /// input by the name of its velocity (`swing.q`: the torque along it), a value input by
    /// its name (`voltage`). An unknown name is an error that lists the run's inputs.
    pub fn set_input(&mut self, name: &str, value: f64) -> Result<(), RunFailure> {
        if let Some(k) = self.input_names().iter().position(|n| n == name) {
            self.system.state.inputs.held[k] = value;
            self.restart();
            return Ok(());
        }
        let model = self.system.model;
        let state = (model.states.iter()).position(|state| state.input && state.name == name);
        let (Some(k), Stepping::Ode(integration)) = (state, &mut self.stepping) else {
            let known: Vec<String> = (self.input_names().into_iter())
                .chain(self.value_input_names())
                .collect();
            let listed = match known.is_empty() {
                true => "the run has none: declare one in the program (`input voltage = 0;`, `input swing.q = 0;`) or name an effort's velocity when the run is made".to_string(),
                false => format!("the run's inputs are {}", known.join(", ")),
            };
            let hint = crate::diag::suggest::did_you_mean(name, known.iter().map(String::as_str))
                .map_or(String::new(), |n| format!("; did you mean `{n}`?"));
            return Err(self.failure_now(format!("no input `{name}`: {listed}{hint}")));
        };
        // A value input is a state held by a zero rate: set in the integrator's state, from
        // which it starts again (as a sampled state's update is).
        let mut y = integration.state().to_vec();
        y[self.system.dimension() + k] = value;
        integration.set_state(&y);
        Ok(())
    }

    /// Sets the efforts along the effort inputs (in the order of
    /// [`Simulator::input_names`]), held until set again (a zero-order hold, as a sampled
    /// controller applies its commands); they add to the law's.
    pub fn set_inputs(&mut self, efforts: &[f64]) -> Result<(), RunFailure> {
        let held = &mut self.system.state.inputs.held;
        if efforts.len() != held.len() {
            let message = format!(
                "{} input efforts given for {} inputs",
                efforts.len(),
                held.len()
            );
            return Err(self.failure_now(message));
        }
        held.copy_from_slice(efforts);
        self.restart();
        Ok(())
    }

    /// The equations of motion changed at the current point: the integrator starts again from
    /// it rather than reuse what its last step computed there.
    fn restart(&mut self) {
        if let Stepping::Ode(integration) = &mut self.stepping {
            integration.restart();
        }
    }

    /// Sets a law of the inputs' efforts, `law(t, coordinates, rates, efforts)`, evaluated with
    /// the program's efforts at every evaluation of the equations of motion (every stage of
    /// every step, rejected ones included): a feedback law so applied gives the motion the same
    /// law written in LSD gives. Its efforts add to the held ones.
    pub fn set_law(
        &mut self,
        law: impl Fn(f64, &[f64], &[f64], &mut [f64]) + Send + Sync + 'static,
    ) {
        let law: InputLaw = Arc::new(law);
        self.system.state.inputs.law = Some(law);
        self.restart();
    }

    /// Takes one step of the integrator towards the end of the settings' duration (one
    /// accepted step of an adaptive method, one step of a fixed-step one). Why the run stopped,
    /// when it did; a stopped run stays where it stopped.
    pub fn step(&mut self) -> Result<(), RunFailure> {
        let end = self.prepared.settings.duration;
        if self.time() >= end {
            return Err(self.failure_now(format!(
                "the run reached the end of its duration, t = {end}: advance it with `advance_to`"
            )));
        }
        self.step_towards(end)
    }

    /// Steps until time `t` and lands on it exactly (the last step shortened to it), delivering
    /// the samples at the output times passed. Steps towards `t` differ from those towards the
    /// end of the duration (`step`) where `t` cuts one short.
    pub fn advance_to(&mut self, t: f64) -> Result<(), RunFailure> {
        while self.time() < t {
            self.step_towards(t)?;
        }
        Ok(())
    }

    /// Starts again from `start` at time 0, the inputs, their law and the samples not taken
    /// kept, everything the run found forgotten (as a new simulator would start).
    pub fn reset(&mut self, start: &Start<'_>) -> Result<(), RunFailure> {
        let names = self.input_names();
        let names: Vec<&str> = names.iter().map(String::as_str).collect();
        let interrupt = self.interrupt.clone();
        let mut fresh = Simulator::from_start(self.prepared, start, &names, interrupt)?;
        let (inputs, kept) = (&self.system.state.inputs, &mut fresh.system.state.inputs);
        kept.held.clone_from(&inputs.held);
        kept.law.clone_from(&inputs.law);
        for (name, value) in self.value_input_names().iter().zip(self.value_inputs()) {
            fresh.set_input(name, value)?;
        }
        fresh.samples = std::mem::take(&mut self.samples);
        *self = fresh;
        Ok(())
    }

    /// Takes the samples the steps delivered since they were last taken.
    pub fn take_samples(&mut self) -> Vec<Sample> {
        std::mem::take(&mut self.samples)
    }

    /// Ends the run: the outputs it did not reach yet (when it reached the end of its steps)
    /// and those still pending, then its report.
    pub fn finish(mut self) -> (Vec<Sample>, Report) {
        let end = self.prepared.settings.duration;
        if let (None, Stepping::Ode(integration)) = (&self.stopped, &mut self.stepping) {
            let mut observer =
                observe_into(&mut self.sampler, &mut self.summary, &mut self.samples);
            let mut ode = RunOde {
                system: &mut self.system,
                tracks_work: self.tracks_work,
                observer: &mut observer,
            };
            if let Err(error) = integration.deliver_rest(&mut ode, &mut |_, _| Ok(())) {
                self.stopped = Some(error);
            }
        }
        let result = match &self.stepping {
            Stepping::Ode(integration) => (integration.state().to_vec(), integration.stats()),
            Stepping::Variational(march) => (march.state(), march.stats.clone()),
        };
        let result = match self.stopped.take() {
            Some(error) => Err(error),
            None => Ok(result),
        };
        // The outputs of a stretch with rows set aside that ended with the run.
        let result = match (result, self.sampler.finish(&mut self.system)) {
            (result, Ok(rest)) => {
                for sample in rest {
                    self.summary.add(&sample);
                    self.samples.push(sample);
                }
                result
            }
            (Ok((_, stats)), Err(error)) => Err(IntegrationError {
                time: end,
                failure: Failure::Observer(error.to_string()),
                stats: Box::new(stats),
            }),
            (failed, Err(_)) => failed,
        };
        let wall_seconds = self.started.elapsed().as_secs_f64();
        let cpu_seconds = thread_cpu_seconds()
            .zip(self.cpu_started)
            .map(|(now, then)| now - then);
        let ended = Ended {
            result,
            summary: &self.summary,
            outputs_off_branch: std::mem::take(&mut self.sampler.unsettled),
            cpu_seconds,
            wall_seconds,
            sampling: (self.sampling.as_mut()).map(|clock| clock.report(self.system.model)),
        };
        let report = report(self.prepared, &mut self.system, ended);
        (self.samples, report)
    }

    /// One step towards `t_end`, or the next sampling instant before it, the samples it
    /// passes kept; on an instant, the sampled states updated.
    fn step_towards(&mut self, t_end: f64) -> Result<(), RunFailure> {
        if let Some(stopped) = &self.stopped {
            return Err(self.failure(stopped.time, &stopped.failure));
        }
        let t_end = (self.sampling.as_ref()).map_or(t_end, |clock| clock.landing(t_end));
        let mut observer = observe_into(&mut self.sampler, &mut self.summary, &mut self.samples);
        let stepped = match &mut self.stepping {
            Stepping::Ode(integration) => {
                let mut ode = RunOde {
                    system: &mut self.system,
                    tracks_work: self.tracks_work,
                    observer: &mut observer,
                };
                // The outputs are the run's own observation (`RunOde::observe`).
                integration.step(&mut ode, t_end, &mut |_, _| Ok(()))
            }
            Stepping::Variational(march) => march.step(&mut self.system, t_end, &mut observer),
        };
        drop(observer);
        let stepped = stepped.and_then(|()| self.sample_instant());
        stepped.map_err(|error| {
            let failure = self.failure(error.time, &error.failure);
            self.stopped = Some(error);
            failure
        })
    }

    /// On a sampling instant, the sampled states' updates set in the integrator's state, from
    /// which it starts again (`sampling`).
    fn sample_instant(&mut self) -> Result<(), IntegrationError> {
        let (Some(clock), Stepping::Ode(integration)) = (&mut self.sampling, &mut self.stepping)
        else {
            return Ok(());
        };
        let t = integration.time();
        let mut y = integration.state().to_vec();
        match clock.sample(&mut self.system, t, &mut y) {
            Ok(true) => integration.set_state(&y),
            Ok(false) => {}
            Err(error) => {
                return Err(IntegrationError {
                    time: t,
                    failure: Failure::System(error.to_string()),
                    stats: Box::new(integration.stats()),
                })
            }
        }
        Ok(())
    }

    /// A failure at `time` in the run's words, with where the run was heading.
    fn failure(&self, time: f64, failure: &Failure) -> RunFailure {
        let prepared = self.prepared;
        RunFailure {
            time,
            message: format!(
                "{}{}",
                failure_message(failure, prepared.settings.max_steps),
                fastest_coordinate(&prepared.coordinate_names, self.summary.last())
            ),
        }
    }

    fn failure_now(&self, message: String) -> RunFailure {
        RunFailure {
            time: self.time(),
            message,
        }
    }
}

/// The run's observer: the samples the sampler makes of each output, counted in the summary
/// and kept.
fn observe_into<'s, 'p: 's, 'm>(
    sampler: &'s mut Sampler<'p>,
    summary: &'s mut Summary,
    samples: &'s mut Vec<Sample>,
) -> impl FnMut(&mut MechanicalSystem<'m>, f64, &[f64]) -> Result<(), CallbackError> + use<'s, 'p, 'm>
{
    move |system, t, y| {
        for sample in sampler.offer(system, t, y)? {
            summary.add(&sample);
            samples.push(sample);
        }
        Ok(())
    }
}

/// The model's velocities named `names`, or why one is not found (with the name nearest).
pub(super) fn input_velocities(model: &Model, names: &[&str]) -> Result<Vec<usize>, String> {
    let known: Vec<String> = (0..model.velocities())
        .map(|v| model.velocity_name(v))
        .collect();
    names
        .iter()
        .map(|name| match known.iter().position(|k| k == name) {
            Some(velocity) => Ok(velocity),
            None => {
                let nearest =
                    crate::diag::suggest::did_you_mean(name, known.iter().map(String::as_str));
                let hint = nearest.map_or(String::new(), |n| format!("; did you mean `{n}`?"));
                Err(format!(
                    "no velocity `{name}` to apply an input along (the mechanism's are {}){hint}",
                    known.join(", ")
                ))
            }
        })
        .collect()
}

/// The features of `model` that an integrator may not handle (`Integrator::refusal`).
pub(super) fn features(model: &Model) -> Vec<Feature> {
    let present = [
        (Feature::Contacts, model.has_contacts()),
        (Feature::Stops, !model.stops.is_empty()),
        (Feature::GearedRotors, !model.rotors.is_empty()),
        (Feature::Mimics, !model.mimics.is_empty()),
        (Feature::Friction, !model.frictions.is_empty()),
        (
            Feature::Drives,
            !model.drives.is_empty() || !model.position_drives.is_empty(),
        ),
        (Feature::States, model.states.iter().any(|s| s.continuous())),
        (
            Feature::Sampled,
            model.states.iter().any(|s| !s.continuous()),
        ),
        (Feature::Actuators, model.actuation.is_some()),
    ];
    present
        .iter()
        .filter(|(_, p)| *p)
        .map(|(f, _)| *f)
        .collect()
}

/// The run's system at a start, with its inputs, and the state it starts from (positions,
/// velocities): the followers where their leaders put them, the loops closed, the friction's
/// phases decided, the outputs' scratch prepared from the loops as the start found them. Why it
/// cannot start.
pub(super) fn start_system<'p>(
    prepared: &'p Prepared,
    start: &Start<'_>,
    inputs: Inputs,
) -> Result<(MechanicalSystem<'p>, Vec<f64>), String> {
    let model = &prepared.model;
    let settings = &prepared.settings;
    let (q0, v0) = model
        .state_from_declared(start.coordinates, start.rates)
        .map_err(|e| {
            format!(
                "the initial state cannot be evaluated: {}",
                describe_error(&e)
            )
        })?;
    if let Some(refusal) = settings.integrator.refusal(&features(model)) {
        return Err(refusal);
    }
    let mut y0 = q0;
    y0.extend_from_slice(&v0);
    let reference = start.coordinates.to_vec();
    let mut system = MechanicalSystem::new(model, reference, settings.stabilisation);
    // Native code computes the program's accelerations alone: not with inputs.
    let native = prepared.native.as_ref();
    system.use_native(native.filter(|_| plain(model) && !inputs.any()));
    system.use_planar(prepared.planar_form());
    system.close_in_plane(prepared.planar.as_deref().ok());
    system.force_loop_method(prepared.loop_method);
    system.use_driven_subtrees(prepared.driven_subtrees());
    system.state.inputs = inputs;
    // The followers start where their leaders put them, whatever `initial` said (then with
    // loops, the loops and couplings are closed together).
    let (q0, v0) = y0.split_at_mut(model.positions());
    mimics::impose(&model.mimics, q0, v0);
    system.start_loops(&mut y0).map_err(|e| e.to_string())?;
    system
        .start_friction(0.0, &mut y0)
        .map_err(|e| e.to_string())?;
    // What the start found of the loops (rank, redundant rows) holds for the outputs too.
    system.prepare_sampling();
    system
        .start_reference(0.0, &y0)
        .map_err(|e| e.to_string())?;
    Ok((system, y0))
}

/// Whether the model has none of what the native code and the variational integrator know
/// nothing of: geared rotors, mimic couplings, joint friction, states (the model's own
/// evaluation counts them).
fn plain(model: &Model) -> bool {
    model.rotors.is_empty()
        && model.mimics.is_empty()
        && model.frictions.is_empty()
        && model.states.is_empty()
}

pub(super) fn describe_error(e: &crate::kinematics::eval::EvalError) -> String {
    use crate::kinematics::eval::{EvalError, NOT_FINITE};
    match e {
        EvalError::Missing(_) => "a value is missing".to_string(),
        EvalError::NotGeometric(what) => format!("it depends on {what}"),
        EvalError::NotFinite => NOT_FINITE.to_string(),
    }
}

/// The times of a run's samples: every `interval` from 0, and the end of its `duration`.
pub fn output_times(duration: f64, interval: f64) -> Vec<f64> {
    let count = (duration / interval + 1e-9).floor() as usize;
    let mut times: Vec<f64> = (0..=count)
        .map(|k| (k as f64 * interval).min(duration))
        .collect();
    if times
        .last()
        .is_some_and(|&t| t < duration - 1e-12 * duration.max(1.0))
    {
        times.push(duration);
    }
    times
}

/// The integrator the settings name, at the start y0 of the run's system (with the work when
/// `tracks_work`), its outputs at the settings' output times.
fn stepping(
    prepared: &Prepared,
    system: &mut MechanicalSystem<'_>,
    y0: &[f64],
    tracks_work: bool,
    interrupt: Option<Interrupt>,
) -> Result<Stepping, IntegrationError> {
    let settings = &prepared.settings;
    let outputs = output_times(settings.duration, settings.output);
    let fixed_step = settings.step.unwrap_or(settings.output.min(1e-3));
    let method = match settings.integrator {
        Integrator::Rk4 => Method::Rk4 { step: fixed_step },
        Integrator::DormandPrince => Method::DormandPrince,
        Integrator::Dop853 => Method::Dop853,
        Integrator::Implicit => Method::Automatic,
        Integrator::Symplectic => {
            // The RATTLE steps keep the loops closed themselves.
            system.scratch.loops.stabilisation = Stabilisation::Integrator;
            let steps = FixedStep {
                step: fixed_step,
                rtol: settings.rtol,
                atol: settings.atol,
                max_steps: settings.max_steps,
                interrupt,
            };
            let march = VariationalMarch::new(system, 0.0, y0, steps, outputs)?;
            return Ok(Stepping::Variational(march));
        }
    };
    let integrator_settings = IntegratorSettings {
        rtol: settings.rtol,
        atol: settings.atol,
        initial_step: settings.step,
        max_step: settings.max_step,
        controlled: Some(system.dimension() + system.state_count()),
        max_steps: settings.max_steps,
        stiffness_check: settings.stiffness_check,
        interrupt,
        ..IntegratorSettings::default()
    };
    let mut unobserved = |_: &mut MechanicalSystem<'_>, _: f64, _: &[f64]| Ok(());
    let mut ode = RunOde {
        system,
        tracks_work,
        observer: &mut unobserved,
    };
    let integration = Integration::new(&method, &mut ode, 0.0, y0, outputs, &integrator_settings)?;
    Ok(Stepping::Ode(integration))
}
