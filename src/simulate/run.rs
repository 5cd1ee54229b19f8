//! Running a simulation: the integrator the settings name, outputs at regular times with the
//! declared coordinates, energy and momentum, and a report of the work and the accuracy. A run
//! that fails keeps every output computed before the failure.

use serde::Serialize;

use super::branch;
use super::report::{failure_message, fastest_coordinate};
pub use super::report::{
    passage_output_warning, step_error_warning, stiffness_warning, Interruption, Report,
    RunFailure, StepErrorReport,
};
pub use super::sample::{MomentumDrift, Sample};
pub use super::simulator::Simulator;
use super::stiffness;
use super::summary::Summary;
use super::system::MechanicalSystem;
use crate::dynamics::model::Model;
use crate::integrate::{Failure, IntegrationError, Interrupt, Stats};
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

/// A run: the steps of a [`Simulator`] to the end of the settings' duration, each sample
/// handed to `sink` as the steps deliver it, then the report.
fn simulate_from(
    prepared: &Prepared,
    start: &Start<'_>,
    options: &RunOptions,
    sink: &mut dyn FnMut(&Sample),
) -> Simulation {
    let interrupt = options.interrupt.clone();
    let mut simulator = match Simulator::from_start(prepared, start, &[], interrupt) {
        Ok(simulator) => simulator,
        Err(failure) => return failed_at_start(prepared, failure.message),
    };
    let mut samples = Vec::new();
    let mut deliver = |offered: Vec<Sample>| {
        for sample in offered {
            sink(&sample);
            if options.keep_samples {
                samples.push(sample);
            }
        }
    };
    while simulator.time() < prepared.settings.duration {
        let stepped = simulator.step();
        deliver(simulator.take_samples());
        if stepped.is_err() {
            break;
        }
    }
    let (rest, report) = simulator.finish();
    deliver(rest);
    Simulation {
        coordinate_names: prepared.coordinate_names.clone(),
        reaction_names: reaction_names_of(prepared),
        output_names: prepared.outputs.names.clone(),
        samples,
        report,
    }
}

/// How an integration ended, with what the outputs saw of it.
pub(super) struct Ended<'s> {
    pub(super) result: Result<(Vec<f64>, Stats), IntegrationError>,
    pub(super) summary: &'s Summary,
    /// The outputs inside a passage the run ended in (`Sampler::unsettled`).
    pub(super) outputs_off_branch: Vec<f64>,
    pub(super) cpu_seconds: Option<f64>,
    pub(super) wall_seconds: f64,
}

/// The report of an ended run: the integrator's work, the energy and momentum the outputs saw,
/// the loops' findings, the events, and why it stopped early if it did.
pub(super) fn report(
    prepared: &Prepared,
    system: &mut MechanicalSystem<'_>,
    ended: Ended<'_>,
) -> Report {
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
        output_names: prepared.outputs.names.clone(),
        samples: Vec::new(),
        report,
    }
}
