//! Running a simulation: the integrator the settings name, outputs at regular times with the
//! declared coordinates, energy and momentum, and a report of the work and the accuracy. A run
//! that fails keeps every output computed before the failure.

use serde::Serialize;

#[cfg(lsdc_internals)]
pub use super::report::stiffness_warning;
pub use super::report::{Report, RunFailure};
#[cfg(lsdc_internals)]
pub use super::sample::MomentumDrift;
pub use super::sample::Sample;
pub use super::simulator::{Simulator, Start};
use crate::dynamics::driven_points;
use crate::dynamics::model::Model;
use crate::integrate::Interrupt;
use crate::prepare::Prepared;

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

/// Simulates a prepared mechanism from another starting state: the model is only read, so one
/// prepared mechanism serves runs from many starts, on as many threads (a parameter sweep).
pub fn run_from(
    prepared: &Prepared,
    start: &Start<'_>,
    sink: &mut dyn FnMut(&Sample),
) -> Simulation {
    simulate_from(prepared, start, &RunOptions::default(), sink)
}

/// As [`run_from`], with `options` (a sweep keeps no samples and stops on its signals).
pub fn run_from_with(
    prepared: &Prepared,
    start: &Start<'_>,
    options: &RunOptions,
    sink: &mut dyn FnMut(&Sample),
) -> Simulation {
    simulate_from(prepared, start, options, sink)
}

/// A run: the steps of a [`Simulator`] to the end of the settings' duration, each sample
/// handed to `sink` as the steps deliver it, then the report.
fn simulate_from(
    prepared: &Prepared,
    start: &Start<'_>,
    options: &RunOptions,
    sink: &mut dyn FnMut(&Sample),
) -> Simulation {
    if prepared.kinematics_only {
        let run_options = (options.keep_samples, options.interrupt.as_ref());
        let (samples, report) = super::kinematic::run(prepared, start, run_options, sink);
        return Simulation {
            coordinate_names: prepared.coordinate_names.clone(),
            reaction_names: Vec::new(),
            output_names: output_names_of(prepared),
            samples,
            report,
        };
    }
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
        output_names: output_names_of(prepared),
        samples,
        report,
    }
}

/// The joins whose reactions the samples carry: none unless the settings ask for them.
/// The outputs' columns: the drives' efforts (`crank.drive_effort`), the program's states by
/// name (`integral`), then the program's outputs and the named frames' states
/// (`Outputs::names`). A scene that asks only for kinematics writes no drive effort.
pub fn output_names_of(prepared: &Prepared) -> Vec<String> {
    let model = &prepared.model;
    let efforts = !prepared.kinematics_only;
    let drives = (model.drives.iter().filter(|_| efforts)).map(|d| d.effort_name());
    let points = (model.position_drives.iter()).flat_map(driven_points::force_names);
    let states = model.states.iter().map(|s| s.name.clone());
    drives
        .chain(points)
        .chain(states)
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

fn failed_at_start(prepared: &Prepared, message: String) -> Simulation {
    let report = Report {
        failure: Some(RunFailure { time: 0.0, message }),
        model: prepared.scene.clone(),
        ..Report::empty(
            prepared.settings.integrator.name(),
            prepared.settings.duration,
        )
    };
    Simulation {
        coordinate_names: prepared.coordinate_names.clone(),
        reaction_names: Vec::new(),
        output_names: output_names_of(prepared),
        samples: Vec::new(),
        report,
    }
}
