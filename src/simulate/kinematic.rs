//! The run of a scene that asks only for kinematics (`prepare::kinematic_scene`): at each
//! output time the driven coordinates are put on their laws, the loops closed by assembly from
//! the previous output's configuration (`kinematics::assembly`, Gauss–Newton on the exact
//! closure Jacobian), the other coordinates' rates solved from the closure
//! (`kinematic_scene::rates_along_drives`), and the outputs evaluated on the bodies' poses and
//! velocities. Nothing is integrated, so that no step, tolerance or mass enters the motion;
//! the energies are left empty (no mass is modelled) and no drive effort is written.

use super::clock::thread_cpu_seconds;
use super::report::{Interruption, Report, RunFailure};
use super::sample::Sample;
use super::simulator::{describe_error, output_times, Start};
use crate::dynamics::algorithms::{forward_kinematics, Data};
use crate::dynamics::compiled::{EffortScratch, EffortState};
use crate::integrate::Interrupt;
use crate::kinematics::assembly::{assemble, AssemblyOptions};
use crate::prepare::kinematic_scene::{driven_mask, rates_along_drives};
use crate::prepare::Prepared;

/// The integrator's name in the report: each "step" an assembly at an output time.
pub const ASSEMBLY: &str = "assembly";

/// Tighter than assembly's default (1e-12): the configurations are the run's results, which
/// equal an integrated run's, closed by projection to round-off.
const CLOSURE_TOLERANCE: f64 = 1e-14;

/// The run of a kinematic scene from `start`, each sample handed to `sink` (and kept when
/// `keep_samples`) until the end, a failure or `interrupt`: the samples kept, and the report.
pub(super) fn run(
    prepared: &Prepared,
    start: &Start<'_>,
    (keep_samples, interrupt): (bool, Option<&Interrupt>),
    sink: &mut dyn FnMut(&Sample),
) -> (Vec<Sample>, Report) {
    let (cpu_start, wall_start) = (thread_cpu_seconds(), std::time::Instant::now());
    let model = &prepared.model;
    let driven = driven_mask(prepared);
    let fixed = driven.clone();
    let assembly = AssemblyOptions {
        tolerance: CLOSURE_TOLERANCE,
        ..AssemblyOptions::default()
    };
    let mut q = start.coordinates.to_vec();
    let mut data = Data::new(model);
    let mut scratch = EffortScratch::default();
    let mut law_values = Vec::new();
    let (mut assemblies, mut evaluations) = (0, 0);
    let mut samples = Vec::new();
    let mut failure = None;
    let mut interrupted = None;
    for time in output_times(prepared.settings.duration, prepared.settings.output) {
        if let Some(signal) = interrupt.and_then(|i| i.requested()) {
            interrupted = Some(Interruption { time, signal });
            break;
        }
        let mut driven_rates = Vec::with_capacity(model.drives.len());
        for drive in &model.drives {
            let law = drive.evaluate(time, &mut law_values);
            q[drive.declared] = law.position;
            driven_rates.push(law.rate);
        }
        let sample = (|| -> Result<Sample, String> {
            if model.has_loops() {
                let closed = assemble(&prepared.kinematics, &q, &fixed, &assembly)
                    .map_err(|_| "the loops cannot be closed along the drives".to_string())?;
                (assemblies, evaluations) = (assemblies + 1, evaluations + closed.iterations);
                q = closed.q;
            }
            let rates = rates_along_drives(&prepared.kinematics, &q, &driven, &driven_rates)
                .map_err(|e| describe_error(&e))?
                .ok_or("the drives no longer determine every coordinate (a singular configuration of the loops)")?;
            let (positions, velocities) =
                (model.state_from_declared(&q, &rates)).map_err(|e| describe_error(&e))?;
            forward_kinematics(model, &mut data, &positions, &velocities)
                .map_err(|e| describe_error(&e))?;
            let state = EffortState {
                world: &data.world,
                velocity: &data.velocity,
                coordinates: &q,
                rates: &rates,
                states: &[],
                time,
                model: &[],
            };
            let outputs = prepared.outputs.values(&state, &mut scratch);
            Ok(Sample {
                time,
                coordinates: q.clone(),
                rates,
                // No mass is modelled: the energies are not known (written as empty cells).
                kinetic_energy: f64::NAN,
                potential_energy: None,
                work: None,
                balance: None,
                momentum: [f64::NAN; 6],
                reactions: Vec::new(),
                outputs,
            })
        })();
        match sample {
            Ok(sample) => {
                sink(&sample);
                if keep_samples {
                    samples.push(sample);
                }
            }
            Err(message) => {
                failure = Some(RunFailure { time, message });
                break;
            }
        }
    }
    let cpu_seconds = cpu_start.zip(thread_cpu_seconds()).map(|(a, b)| b - a);
    let report = Report {
        steps: assemblies,
        function_evaluations: evaluations,
        cpu_seconds,
        wall_seconds: wall_start.elapsed().as_secs_f64(),
        failure,
        model: prepared.scene.clone(),
        interrupted,
        ..Report::empty(ASSEMBLY, prepared.settings.duration)
    };
    (samples, report)
}
