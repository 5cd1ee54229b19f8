//! Running a simulation: the integrator the settings name, outputs at regular times with the
//! declared coordinates, energy and momentum, and a report of the work and the accuracy. A run
//! that fails keeps every output computed before the failure.

use std::time::Instant;

use serde::Serialize;

use super::branch;
use super::clock::thread_cpu_seconds;
use super::ode::RunOde;
use super::report::{failure_message, fastest_coordinate};
pub use super::report::{
    passage_output_warning, step_error_warning, stiffness_warning, Interruption, Report,
    RunFailure, StepErrorReport,
};
pub use super::sample::{MomentumDrift, Sample};
use super::sampler::Sampler;
use super::stiffness;
use super::summary::Summary;
use super::system::{MechanicalSystem, RunObserver};
use super::variational;
use crate::dynamics::compiled::EffortScratch;
use crate::dynamics::energy::conservative_forces;
use crate::dynamics::mimics;
use crate::dynamics::model::Model;
use crate::integrate::{
    integrate, Failure, IntegrationError, Interrupt, Method, Settings as IntegratorSettings, Stats,
};
use crate::integrators::Feature;
use crate::prepare::{Integrator, Prepared};

#[derive(Clone, Debug, Serialize)]
pub struct Simulation {
    pub coordinate_names: Vec<String>,
    /// The joins whose reactions the samples carry (empty unless asked for).
    pub reaction_names: Vec<String>,
    /// The columns of the program's outputs (`output` declarations).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub output_names: Vec<String>,
    pub samples: Vec<Sample>,
    pub report: Report,
}

/// The features of `model` that an integrator may not handle (`Integrator::refusal`).
fn features(model: &Model) -> Vec<Feature> {
    let present = [
        (Feature::Contacts, model.has_contacts()),
        (Feature::Stops, !model.stops.is_empty()),
        (Feature::GearedRotors, !model.rotors.is_empty()),
        (Feature::Mimics, !model.mimics.is_empty()),
        (Feature::Friction, !model.frictions.is_empty()),
        (Feature::Drives, !model.drives.is_empty()),
    ];
    present
        .iter()
        .filter(|(_, p)| *p)
        .map(|(f, _)| *f)
        .collect()
}

fn output_times(duration: f64, interval: f64) -> Vec<f64> {
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

/// Runs the prepared simulation; `sink` receives every sample as soon as it is computed, and
/// the simulation keeps them all.
pub fn run(prepared: &Prepared, sink: &mut dyn FnMut(&Sample)) -> Simulation {
    run_with(prepared, &RunOptions::default(), sink)
}

/// How a run treats its samples, and what may stop it.
#[derive(Clone, Debug)]
pub struct RunOptions {
    /// Keep every sample in `Simulation::samples` (plots, JSON need them); when false, they only
    /// go to the sink, and the run's memory does not grow with its length (but for three
    /// numbers per output of a mechanism with loops, for the check of singular passages).
    pub keep_samples: bool,
    /// A flag that stops the run between two steps when set (to a signal's number, say): the
    /// report says when (`Report::interrupted`), every sample before is kept.
    pub interrupt: Option<Interrupt>,
}

impl Default for RunOptions {
    fn default() -> Self {
        RunOptions {
            keep_samples: true,
            interrupt: None,
        }
    }
}

/// Runs the prepared simulation with these options; `sink` receives every sample as soon as it
/// is computed.
pub fn run_with(
    prepared: &Prepared,
    options: &RunOptions,
    sink: &mut dyn FnMut(&Sample),
) -> Simulation {
    let start = Start {
        coordinates: &prepared.coordinates,
        rates: &prepared.rates,
    };
    simulate_from(prepared, &start, options, sink)
}

/// A starting state of a prepared mechanism: declared coordinates and rates (for a mechanism
/// with loops, closed ones: the prepared start is).
#[derive(Clone, Copy, Debug)]
pub struct Start<'a> {
    pub coordinates: &'a [f64],
    pub rates: &'a [f64],
}

/// Simulates a prepared mechanism from another starting state: the model is only read, so one
/// prepared mechanism serves runs from many starts, on as many threads (a parameter sweep).
pub fn run_from(
    prepared: &Prepared,
    start: &Start<'_>,
    sink: &mut dyn FnMut(&Sample),
) -> Simulation {
    simulate_from(prepared, start, &RunOptions::default(), sink)
}

/// A run in stages: its system at the start state (`start_system`), integrated with the outputs
/// observed on it (`integrate_observed`), then its report (`report`).
fn simulate_from(
    prepared: &Prepared,
    start: &Start<'_>,
    options: &RunOptions,
    sink: &mut dyn FnMut(&Sample),
) -> Simulation {
    let model = &prepared.model;
    let settings = &prepared.settings;
    let (mut system, mut y0) = match start_system(prepared, start) {
        Ok(started) => started,
        Err(message) => return failed_at_start(prepared, message),
    };
    let mut sampler = Sampler {
        conservative: conservative_forces(model),
        reactions: settings.reactions,
        outputs: &prepared.outputs,
        output_scratch: EffortScratch::default(),
        pending: Vec::new(),
        unsettled: Vec::new(),
        segment: None,
    };
    // The work of non-conservative efforts rides along as one more state (not with the
    // variational integrator, whose steps are its own), nor with native code, which computes
    // the accelerations alone (`simulate --compiled`).
    let tracks_work = !sampler.conservative.complete
        && settings.integrator != Integrator::Symplectic
        && prepared.native.is_none();
    if tracks_work {
        y0.push(0.0);
    }
    let mut samples = Vec::new();
    let mut summary = Summary::new(model, sampler.conservative.complete);
    let started = Instant::now();
    let cpu_started = thread_cpu_seconds();
    let mut deliver = |offered: Vec<Sample>, samples: &mut Vec<Sample>| {
        for sample in offered {
            sink(&sample);
            summary.add(&sample);
            if options.keep_samples {
                samples.push(sample);
            }
        }
    };
    let mut observer = |system: &mut MechanicalSystem<'_>, t: f64, y: &[f64]| {
        deliver(sampler.offer(system, t, y)?, &mut samples);
        Ok(())
    };
    let result = integrate_observed(
        prepared,
        &mut system,
        &y0,
        tracks_work,
        options,
        &mut observer,
    );
    // The outputs of a stretch with rows set aside that ended with the run.
    let result = match (result, sampler.finish(&mut system)) {
        (result, Ok(rest)) => {
            deliver(rest, &mut samples);
            result
        }
        (Ok((_, stats)), Err(error)) => Err(IntegrationError {
            time: settings.duration,
            failure: Failure::Observer(error.to_string()),
            stats: Box::new(stats),
        }),
        (failed, Err(_)) => failed,
    };
    let wall_seconds = started.elapsed().as_secs_f64();
    let cpu_seconds = thread_cpu_seconds()
        .zip(cpu_started)
        .map(|(now, then)| now - then);
    let ended = Ended {
        result,
        summary: &summary,
        outputs_off_branch: std::mem::take(&mut sampler.unsettled),
        cpu_seconds,
        wall_seconds,
    };
    let report = report(prepared, &mut system, ended);
    Simulation {
        coordinate_names: prepared.coordinate_names.clone(),
        reaction_names: reaction_names_of(prepared),
        output_names: output_names_of(prepared),
        samples,
        report,
    }
}

/// The run's system at a start, and the state it starts from (positions, velocities): the
/// followers where their leaders put them, the loops closed, the friction's phases decided,
/// the outputs' scratch prepared from the loops as the start found them. Why it cannot start.
fn start_system<'p>(
    prepared: &'p Prepared,
    start: &Start<'_>,
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
    system.use_native(prepared.native.as_ref().filter(|_| plain(model)));
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
    Ok((system, y0))
}

/// Whether the model has none of what the native code and the variational integrator know
/// nothing of: geared rotors, mimic couplings, joint friction (the model's own evaluation
/// counts them).
fn plain(model: &Model) -> bool {
    model.rotors.is_empty() && model.mimics.is_empty() && model.frictions.is_empty()
}

/// Integrates the run's system from y0 with the integrator the settings name, `observer`
/// receiving every output.
fn integrate_observed<'m>(
    prepared: &Prepared,
    system: &mut MechanicalSystem<'m>,
    y0: &[f64],
    tracks_work: bool,
    options: &RunOptions,
    observer: &mut RunObserver<'_, 'm>,
) -> Result<(Vec<f64>, Stats), IntegrationError> {
    let settings = &prepared.settings;
    let outputs = output_times(settings.duration, settings.output);
    let integrator_settings = IntegratorSettings {
        rtol: settings.rtol,
        atol: settings.atol,
        initial_step: settings.step,
        max_step: settings.max_step,
        controlled: Some(system.dimension()),
        max_steps: settings.max_steps,
        stiffness_check: settings.stiffness_check,
        interrupt: options.interrupt.clone(),
        ..IntegratorSettings::default()
    };
    let fixed_step = settings.step.unwrap_or(settings.output.min(1e-3));
    let method = match settings.integrator {
        Integrator::Rk4 => Some(Method::Rk4 { step: fixed_step }),
        Integrator::DormandPrince => Some(Method::DormandPrince),
        Integrator::Dop853 => Some(Method::Dop853),
        Integrator::Implicit => Some(Method::Automatic),
        Integrator::Symplectic => None,
    };
    match method {
        Some(method) => {
            let mut ode = RunOde {
                system,
                tracks_work,
                observer,
            };
            integrate(
                &method,
                &mut ode,
                0.0,
                y0,
                settings.duration,
                &outputs,
                &integrator_settings,
                // The outputs are the run's own observation (`RunOde::observe`).
                &mut |_, _| Ok(()),
            )
        }
        None => {
            // The RATTLE steps keep the loops closed themselves.
            system.scratch.loops.stabilisation = crate::dynamics::loops::Stabilisation::Integrator;
            variational::integrate(
                system,
                0.0,
                y0,
                settings.duration,
                variational::FixedStep {
                    step: fixed_step,
                    rtol: settings.rtol,
                    atol: settings.atol,
                    max_steps: settings.max_steps,
                    interrupt: options.interrupt.clone(),
                },
                &outputs,
                observer,
            )
        }
    }
}

/// How an integration ended, with what the outputs saw of it.
struct Ended<'s> {
    result: Result<(Vec<f64>, Stats), IntegrationError>,
    summary: &'s Summary,
    /// The outputs inside a passage the run ended in (`Sampler::unsettled`).
    outputs_off_branch: Vec<f64>,
    cpu_seconds: Option<f64>,
    wall_seconds: f64,
}

/// The report of an ended run: the integrator's work, the energy and momentum the outputs saw,
/// the loops' findings, the events, and why it stopped early if it did.
fn report(prepared: &Prepared, system: &mut MechanicalSystem<'_>, ended: Ended<'_>) -> Report {
    let model = &prepared.model;
    let settings = &prepared.settings;
    let summary = ended.summary;
    let (stats, stopped) = match ended.result {
        Ok((_, stats)) => (stats, None),
        Err(e) => (*e.stats, Some((e.time, e.failure))),
    };
    let interrupted = match stopped {
        Some((time, Failure::Interrupted(signal))) => Some(Interruption { time, signal }),
        _ => None,
    };
    let failure = stopped
        .filter(|(_, failure)| !matches!(failure, Failure::Interrupted(_)))
        .map(|(time, failure)| RunFailure {
            time,
            message: format!(
                "{}{}",
                failure_message(&failure, settings.max_steps),
                fastest_coordinate(&prepared.coordinate_names, summary.last())
            ),
        });
    let constraints = model.has_loops().then(|| {
        let mut report = system.scratch.loops.report(&system.state.loops);
        report.outputs_off_branch = ended.outputs_off_branch;
        report
    });
    let left_branch = constraints
        .as_ref()
        .filter(|c| !c.singular.is_empty())
        .and_then(|c| branch::left_branch(summary.branch_outputs(), &c.singular))
        .map(|left| RunFailure {
            time: left.time,
            message: left.message,
        });
    let failure = match (failure, left_branch) {
        (Some(stopped), Some(left)) if left.time < stopped.time => Some(left),
        (None, left) => left,
        (stopped, _) => stopped,
    };
    Report {
        integrator: settings.integrator.name().to_string(),
        duration: settings.duration,
        steps: stats.steps,
        rejected_steps: stats.rejected,
        function_evaluations: stats.rhs_evaluations,
        stiff_steps: (settings.integrator == Integrator::Implicit).then_some(stats.stiff_steps),
        method_switches: (settings.integrator == Integrator::Implicit)
            .then_some(stats.method_switches),
        cpu_seconds: ended.cpu_seconds,
        wall_seconds: ended.wall_seconds,
        energy_drift: summary.energy_drift(),
        energy_balance: summary.energy_balance(),
        final_energies: summary.final_energies(),
        momentum_drift: summary.momentum_drift(),
        constraints,
        step_error: stats.largest_step_error.map(|e| StepErrorReport {
            largest: e.norm,
            time: e.time,
            rtol: settings.rtol,
            atol: settings.atol,
        }),
        stiffness: stats
            .stability_bound
            .as_ref()
            .and_then(|bound| stiffness::describe(prepared, bound)),
        impacts: std::mem::take(&mut system.state.impacts),
        friction_switches: std::mem::take(&mut system.state.switches),
        failure,
        interrupted,
    }
}

/// The joins whose reactions the samples carry: none unless the settings ask for them.
/// The outputs' columns: the drives' efforts (`crank.drive_effort`), then the program's
/// outputs and the named frames' states (`Outputs::names`).
pub fn output_names_of(prepared: &Prepared) -> Vec<String> {
    let drives = prepared.model.drives.iter().map(|d| d.effort_name());
    drives
        .chain(prepared.outputs.names.iter().cloned())
        .collect()
}

pub fn reaction_names_of(prepared: &Prepared) -> Vec<String> {
    match prepared.settings.reactions {
        true => reaction_names(&prepared.model),
        false => Vec::new(),
    }
}

/// The joins in the order of the reactions: the tree's, then the complementary links.
fn reaction_names(model: &Model) -> Vec<String> {
    model
        .joints
        .iter()
        .map(|j| j.chain.name.clone())
        .chain(model.loops.iter().map(|l| l.name.clone()))
        .chain(model.contacts.iter().map(|c| c.name.clone()))
        .collect()
}

fn describe_error(e: &crate::kinematics::eval::EvalError) -> String {
    use crate::kinematics::eval::{EvalError, NOT_FINITE};
    match e {
        EvalError::Missing(_) => "a value is missing".to_string(),
        EvalError::NotGeometric(what) => format!("it depends on {what}"),
        EvalError::NotFinite => NOT_FINITE.to_string(),
    }
}

fn failed_at_start(prepared: &Prepared, message: String) -> Simulation {
    let report = Report {
        integrator: prepared.settings.integrator.name().to_string(),
        duration: prepared.settings.duration,
        steps: 0,
        rejected_steps: 0,
        function_evaluations: 0,
        stiff_steps: None,
        method_switches: None,
        cpu_seconds: Some(0.0),
        wall_seconds: 0.0,
        energy_drift: None,
        energy_balance: None,
        final_energies: None,
        momentum_drift: None,
        constraints: None,
        step_error: None,
        stiffness: None,
        impacts: Vec::new(),
        friction_switches: Vec::new(),
        failure: Some(RunFailure { time: 0.0, message }),
        interrupted: None,
    };
    Simulation {
        coordinate_names: prepared.coordinate_names.clone(),
        reaction_names: Vec::new(),
        output_names: output_names_of(prepared),
        samples: Vec::new(),
        report,
    }
}
