//! Closed loops: cost per step and error against a tight-tolerance reference, for the four-bar
//! and the Delta robot (full ball-jointed model and reduced model). Run with
//! `cargo bench --bench loops`. Times are medians of a few runs on whatever machine runs this.

use std::path::PathBuf;

use lsdc::driver::compile_files;
use lsdc::load::LoadOptions;
use lsdc::prepare::{prepare, Integrator, Prepared, Settings};
use lsdc::simulate::run::{run, Report, Sample, Simulation};

mod common;
#[path = "common/loop_costs.rs"]
mod loop_costs;
use loop_costs::{call_costs, median, tree_cost};

/// The mechanisms whose loop overhead is measured: one constrained right-hand side against one
/// of the same bodies as a tree (the closing joins removed), and one projection.
const OVERHEAD: [&str; 7] = [
    "four_bar",
    "delta_isir88",
    "delta_isir88_reduced",
    "hard/squeezer",
    "hard/watt_six_bar",
    "hard/bennett",
    "hard/bricard",
];

/// Tolerances tried for the reference, tightest first: 1e-13 may fail to converge near round-off.
const REFERENCE_TOLERANCES: [f64; 2] = [1e-13, 1e-12];
/// Timed repetitions of each run (fewer for runs over a second); the median is reported.
const REPEATS: usize = 5;
const REPEATS_SLOW: usize = 3;

struct Case {
    file: &'static str,
    /// Fixed steps for RK4 and for the symplectic integrator.
    rk4_steps: &'static [f64],
    symplectic_steps: &'static [f64],
}

const CASES: [Case; 3] = [
    Case {
        file: "four_bar",
        rk4_steps: &[1e-2, 1e-3, 1e-4],
        symplectic_steps: &[1e-2, 1e-3],
    },
    Case {
        file: "delta_isir88",
        rk4_steps: &[5e-3, 1e-3, 1e-4],
        symplectic_steps: &[1e-3, 1e-4],
    },
    Case {
        file: "delta_isir88_reduced",
        rk4_steps: &[5e-3, 1e-3, 1e-4],
        symplectic_steps: &[1e-3, 1e-4],
    },
];

/// One integrator configuration of the table.
struct Method {
    label: String,
    integrator: Integrator,
    tolerance: Option<f64>,
    step: Option<f64>,
}

fn methods(case: &Case) -> Vec<Method> {
    let adaptive = |integrator: Integrator, name: &str, tol: f64| Method {
        label: format!("{name} {tol:.0e}"),
        integrator,
        tolerance: Some(tol),
        step: None,
    };
    let fixed = |integrator: Integrator, name: &str, h: f64| Method {
        label: format!("{name} h={h:.0e}"),
        integrator,
        tolerance: None,
        step: Some(h),
    };
    let mut list: Vec<Method> = [1e-6, 1e-8, 1e-10]
        .iter()
        .map(|&t| adaptive(Integrator::DormandPrince, "dopri5", t))
        .collect();
    list.extend(
        case.rk4_steps
            .iter()
            .map(|&h| fixed(Integrator::Rk4, "rk4", h)),
    );
    list.extend(
        [1e-6, 1e-8]
            .iter()
            .map(|&t| adaptive(Integrator::Implicit, "implicit", t)),
    );
    list.extend(
        case.symplectic_steps
            .iter()
            .map(|&h| fixed(Integrator::Symplectic, "symplectic", h)),
    );
    list
}

fn load(file: &str) -> Prepared {
    let options = LoadOptions {
        library_dirs: Vec::new(),
        use_environment: false,
        scene: None,
    };
    let compilation = compile_files(&[PathBuf::from(format!("examples/{file}.lsd"))], &options)
        .expect("example loads");
    let mechanism = compilation.mechanism.expect("example elaborates");
    prepare(&mechanism, &[], &Settings::default()).unwrap_or_else(|_| panic!("{file}: prepares"))
}

/// The example's own scenario (duration, outputs) with the method's integrator and accuracy.
fn configure(file: &str, method: &Method) -> Prepared {
    let mut prepared = load(file);
    prepared.settings.integrator = method.integrator.clone();
    prepared.settings.step = method.step;
    if let Some(tol) = method.tolerance {
        (prepared.settings.rtol, prepared.settings.atol) = (tol, tol);
    }
    prepared
}

/// Median integration time (the report's `wall_seconds`) and the work of one run. Timed with
/// outputs only at the start and the end: sampling an output costs a projection and the energy,
/// and the interpolated outputs do not change the steps, so this is the integration alone.
fn timed_run(file: &str, method: &Method) -> (f64, Report) {
    let mut prepared = configure(file, method);
    prepared.settings.output = prepared.settings.duration;
    let mut seconds = Vec::new();
    let mut report = None;
    while seconds.len()
        < if seconds.iter().any(|&s| s > 1.0) {
            REPEATS_SLOW
        } else {
            REPEATS
        }
    {
        let simulation = run(&prepared, &mut |_| {});
        seconds.push(simulation.report.wall_seconds);
        report = Some(simulation.report);
    }
    (median(seconds), report.expect("at least one run"))
}

/// The largest |coordinate − reference| over the output times both runs reached.
fn max_error(samples: &[Sample], reference: &[Sample]) -> f64 {
    samples
        .iter()
        .zip(reference)
        .take_while(|(s, r)| (s.time - r.time).abs() <= 1e-9)
        .flat_map(|(s, r)| {
            s.coordinates
                .iter()
                .zip(&r.coordinates)
                .map(|(a, b)| (a - b).abs())
        })
        .fold(0.0, f64::max)
}

/// The reference at the tightest tolerance that completes without failure.
fn reference(file: &str) -> (Simulation, f64) {
    for tol in REFERENCE_TOLERANCES {
        let method = Method {
            label: String::new(),
            integrator: Integrator::DormandPrince,
            tolerance: Some(tol),
            step: None,
        };
        let simulation = run(&configure(file, &method), &mut |_| {});
        match &simulation.report.failure {
            None => return (simulation, tol),
            Some(f) => println!(
                "reference at {tol:e} failed at t = {}: {}",
                f.time, f.message
            ),
        }
    }
    panic!("{file}: no reference run completed");
}

fn optional(value: Option<f64>) -> String {
    value.map_or("—".to_string(), |v| format!("{v:.1e}"))
}

/// A table row: work and time from the timed runs, accuracy from a run with the scenario's outputs.
/// The symplectic integrator's "evaluations" are its Newton iterations (midpoint terms).
fn row(file: &str, method: &Method, reference: &[Sample]) -> String {
    let (seconds, work) = timed_run(file, method);
    let simulation = run(&configure(file, method), &mut |_| {});
    let r = &simulation.report;
    if let Some(failure) = r.failure.as_ref().filter(|_| r.steps == 0) {
        return format!(
            "| {} | failed: {} | | | | | | |",
            method.label, failure.message
        );
    }
    let failed = r
        .failure
        .as_ref()
        .map_or(String::new(), |f| format!(" (failed at t = {:.3})", f.time));
    format!(
        "| {}{failed} | {} ({} rejected) | {:.1} | {:.1} | {:.1} | {:.1e} | {} | {} |",
        method.label,
        work.steps,
        work.rejected_steps,
        seconds * 1e3,
        seconds / work.steps as f64 * 1e6,
        seconds / work.function_evaluations as f64 * 1e6,
        max_error(&simulation.samples, reference),
        optional(r.energy_drift),
        optional(r.constraints.as_ref().map(|c| c.position_residual)),
    )
}

fn main() {
    println!("Timings are from the machine running this benchmark (release build), medians of {REPEATS} runs ({REPEATS_SLOW} over a second).");
    println!("\n### Loop overhead per evaluation\n");
    println!(
        "| mechanism | loops µs | tree µs | loops / tree | projection µs | projection / loops |"
    );
    println!("|---|---:|---:|---:|---:|---:|");
    for file in OVERHEAD {
        let prepared = load(file);
        let (rhs, projection) = call_costs(&prepared);
        let tree = tree_cost(&prepared);
        println!(
            "| {file} | {rhs:.2} | {tree:.2} | {:.1} | {projection:.2} | {:.2} |",
            rhs / tree,
            projection / rhs
        );
    }
    for case in &CASES {
        let base = load(case.file);
        let (reference, tol) = reference(case.file);
        let (rhs, projection) = call_costs(&base);
        let s = &base.settings;
        println!(
            "\n### {} ({} s, output every {} s)\n",
            case.file, s.duration, s.output
        );
        println!(
            "Reference: dopri5 at rtol = atol = {tol:.0e}, {} steps. One constrained right-hand side: {rhs:.2} µs; one projection: {projection:.2} µs.\n",
            reference.report.steps
        );
        println!("| method | steps | run ms | µs per step | µs per evaluation | max coordinate error | energy drift | position residual |");
        println!("|---|---:|---:|---:|---:|---:|---:|---:|");
        for method in methods(case) {
            println!("{}", row(case.file, &method, &reference.samples));
        }
    }
}
