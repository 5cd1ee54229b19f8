//! The implicit integrator against dopri5 at equal error on the stiff examples
//! (`cargo bench --bench implicit_stiff`): the governor over 1 s and the stiff spring pendulum
//! over 10 s. For each case, dopri5 at its tolerance, and the implicit integrator at the
//! loosest of a ladder of tolerances whose error in the coordinates at the outputs (against a
//! reference: DOP853 at 1e-12 for the governor, dopri5 at 1e-12 for the pendulum, both held by
//! stability to steps far below what their tolerance needs) is at most dopri5's. Both are timed
//! by thread CPU time in 7 interleaved rounds (each round a batch of one, then of the other,
//! so that the machine's load falls on both alike), best and median. Prints one line per case:
//! `NAME dopri5_tolerance dopri5_error implicit_tolerance implicit_error dopri5_ms implicit_ms
//! ratio dopri5_steps implicit_steps dopri5_evaluations implicit_evaluations` (best times; the
//! medians and their ratio after them).

mod common;
use common::interleaved;

use lsdc::prepare::{prepare, Integrator, Prepared, Settings};
use lsdc::simulate::run::{run, Simulation};

fn prepared(name: &str, integrator: Integrator, tolerance: f64, duration: f64) -> Prepared {
    let path = std::path::PathBuf::from(format!("examples/{name}.lsd"));
    let compilation =
        lsdc::driver::compile_files(&[path], &Default::default()).expect("the example loads");
    let mechanism = compilation.mechanism.expect("elaborates");
    let mut prepared = prepare(&mechanism, &[], &Settings::default()).expect("prepares");
    prepared.settings = Settings {
        integrator,
        rtol: tolerance,
        atol: tolerance,
        duration,
        ..prepared.settings
    };
    prepared
}

/// The largest difference of the coordinates over the outputs.
fn coordinate_error(run: &Simulation, reference: &Simulation) -> f64 {
    assert_eq!(run.samples.len(), reference.samples.len());
    let pairs = run.samples.iter().zip(&reference.samples);
    pairs
        .flat_map(|(a, b)| a.coordinates.iter().zip(&b.coordinates))
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max)
}

fn main() {
    // name, duration, reference integrator, dopri5's tolerances
    let cases = [
        ("governor", 1.0, Integrator::Dop853, vec![1e-6]),
        (
            "stiff_spring_pendulum",
            10.0,
            Integrator::DormandPrince,
            vec![1e-4, 1e-6, 1e-8, 1e-10],
        ),
    ];
    for (name, duration, reference_integrator, tolerances) in cases {
        let reference = run(
            &prepared(name, reference_integrator, 1e-12, duration),
            &mut |_| {},
        );
        for tolerance in tolerances {
            let explicit = prepared(name, Integrator::DormandPrince, tolerance, duration);
            let explicit_run = run(&explicit, &mut |_| {});
            let target = coordinate_error(&explicit_run, &reference);
            let ladder = [3.0, 1.0, 0.3, 0.1, 0.03, 0.01, 3e-3, 1e-3];
            let Some((implicit_tolerance, implicit_run, error)) =
                ladder.into_iter().find_map(|factor| {
                    let tolerance = factor * tolerance;
                    let implicit = prepared(name, Integrator::Implicit, tolerance, duration);
                    let simulation = run(&implicit, &mut |_| {});
                    let error = coordinate_error(&simulation, &reference);
                    (error <= target).then_some((tolerance, simulation, error))
                })
            else {
                println!(
                    "{name} {tolerance:e} {target:.1e}: not reached by the implicit integrator"
                );
                continue;
            };
            let implicit = prepared(name, Integrator::Implicit, implicit_tolerance, duration);
            let [explicit_time, implicit_time] = interleaved(
                [
                    &mut || {
                        std::hint::black_box(run(&explicit, &mut |_| {}));
                    },
                    &mut || {
                        std::hint::black_box(run(&implicit, &mut |_| {}));
                    },
                ],
                0.05,
                7,
            );
            println!(
                "{name} {tolerance:.0e} {target:.1e} {implicit_tolerance:.1e} {error:.1e} {:.3} {:.3} {:.3} {} {} {} {} (medians {:.3} {:.3} {:.3})",
                1e3 * explicit_time.0,
                1e3 * implicit_time.0,
                implicit_time.0 / explicit_time.0,
                explicit_run.report.steps,
                implicit_run.report.steps,
                explicit_run.report.function_evaluations,
                implicit_run.report.function_evaluations,
                1e3 * explicit_time.1,
                1e3 * implicit_time.1,
                implicit_time.1 / explicit_time.1,
            );
        }
    }
}
