//! What closed loops cost as they multiply: a row of N parallelogram four-bars (the programs of
//! `examples/hard/four_bar_row_N.lsd`, generated for any N by `common/rows.rs`) against the same 2N + 1 bodies
//! with the N closing joins removed (a tree: N + 1 cranks, each of the first N carrying a
//! coupler). For each N: one right-hand side of each, their ratio, and one projection onto the
//! loops. Then the long closed chains of `common/chains.rs`, the necklace (one loop of N rods)
//! and the ladder (N loops sharing their rungs), for N from 10 to 1,000: one right-hand side and
//! one projection, their start, and the exponent of their growth with N (least squares on log cost
//! against log N). Where the loops' two methods (`dynamics::loops::range_space`) trade places, the
//! necklace of N rods for N from 4 to 14 with each method forced (`switch`), and the necklace's
//! energy and closure over 0.2 s at dopri5 1e-12 for N = 10, 100 and 1,000 (`accuracy`).
//! Run with `cargo bench --bench loop_scaling [-- rows|chains|switch|accuracy|ladder-accuracy|ladder-projection]`; CPU time per
//! call, best of 7 batches of about 20 ms.

use lsdc::driver::compile_text;
use lsdc::dynamics::loops::{Method, Stabilisation};
use lsdc::load::LoadOptions;
use lsdc::prepare::{prepare, Integrator, Prepared, Settings};

#[path = "common/chains.rs"]
mod chains;
mod common;
#[path = "common/loop_costs.rs"]
mod loop_costs;
#[path = "common/rows.rs"]
mod rows;
use chains::{ladder_program, necklace_program};
use loop_costs::call_costs;
use rows::row_program;

const ROWS: [usize; 8] = [1, 2, 5, 10, 20, 40, 70, 100];
/// The necklace and the ladder to N = 1,000.
const NECKLACES: [usize; 5] = [10, 30, 100, 300, 1000];
const LADDERS: [usize; 5] = [10, 30, 100, 300, 1000];

/// Where the plots of cost per body against N are written.
const PLOT: &str = "target/loop_scaling.svg";
const CHAINS_PLOT: &str = "target/long_chains.svg";

fn prepared(text: &str) -> Prepared {
    let options = LoadOptions {
        library_dirs: Vec::new(),
        use_environment: false,
        scene: None,
    };
    let compilation = compile_text("row.lsd", text, None, &options);
    assert!(!compilation.has_errors(), "{:?}", compilation.diagnostics);
    let mechanism = compilation.mechanism.expect("elaborates");
    prepare(&mechanism, &[], &Settings::default()).expect("prepares")
}

fn main() {
    let asked: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with("--"))
        .collect();
    // `write ladder|necklace N FILE`: the chain's program to a file, to time the commands on it
    // (`lsdc check`, `tree`, `simulate`) with the same text the parts below measure.
    if let [write, chain, n, path] = asked.as_slice() {
        if write == "write" {
            let n: usize = n.parse().expect("N, a number of loops or rods");
            let text = match chain.as_str() {
                "ladder" => ladder_program(n),
                "necklace" => necklace_program(n),
                other => panic!("`{other}`: write `ladder` or `necklace`"),
            };
            std::fs::write(path, text).expect("the program is written");
            return;
        }
    }
    let wants = |part: &str| asked.is_empty() || asked.iter().any(|a| a == part);
    if wants("rows") {
        rows_against_trees();
    }
    if wants("chains") {
        long_chains();
    }
    if wants("switch") {
        methods_switch();
    }
    if wants("accuracy") {
        necklace_accuracy();
    }
    if wants("ladder-accuracy") {
        ladder_accuracy();
    }
    if asked.iter().any(|a| a == "ladder-projection") {
        ladder_projection();
    }
}

/// The ladder's projection alone at N = 100, 300 and 1,000 (cost per call, as in `chains`),
/// then 5 s of CPU of projections at 1,000, for a profiler to sample apart from the start.
fn ladder_projection() {
    println!("\nThe ladder's projection (CPU time per call, best batch).\n");
    println!("| N | projection µs | per body µs |");
    println!("|---:|---:|---:|");
    for n in [100, 300, 1000] {
        let chain = prepared(&ladder_program(n));
        let (_, projection) = call_costs(&chain);
        println!(
            "| {n} | {projection:.1} | {:.3} |",
            projection / (2 * n + 2) as f64
        );
        // One projection of the closed state (at rest) with every velocity moved by 1e-9, then
        // by 0.1: the rows left on the state it returns.
        for moved in [1e-9, 0.1] {
            use lsdc::dynamics::algorithms::{forward_kinematics, Data};
            use lsdc::dynamics::loops::{constraints_into, Constraints, Extent};
            let model = &chain.model;
            let (mut system, mut y) = loop_costs::loop_system(&chain);
            let nq = y.len() - model.velocities();
            y[nq..].iter_mut().for_each(|v| *v += moved);
            let rows = |y: &[f64]| {
                let (q, v) = model.split_state(y);
                let mut data = Data::new(model);
                let mut c = Constraints::new(model);
                forward_kinematics(model, &mut data, &q, v).expect("kinematics");
                constraints_into(model, &mut data, &q, v, Extent::Rows, &mut c).expect("rows");
                (c.residual.amax(), c.velocity.amax())
            };
            let before = rows(&y);
            system.keep_closed(0.0, &mut y).expect("projects");
            let after = rows(&y);
            println!(
                "|   | velocities moved by {moved:e}: rows before {:.1e}, {:.1e}; after {:.1e}, {:.1e} |  |",
                before.0, before.1, after.0, after.1
            );
        }
        if n == 1000 {
            let (mut system, y) = loop_costs::loop_system(&chain);
            let start = common::thread_cpu_seconds();
            while common::thread_cpu_seconds() - start < 5.0 {
                let mut z = y.clone();
                std::hint::black_box(system.keep_closed(0.0, &mut z).expect("projects"));
            }
        }
    }
}

/// The necklace of N rods has 3 kept rows and N − 2 allowed motions: each method's cost of one
/// right-hand side and one projection on both sides of the rule's switch (range-space where
/// N − 2 ≥ 2 · 3).
fn methods_switch() {
    println!(
        "\nThe necklace with each method forced ({}, CPU time per call, best batch).\n",
        common::build_profile()
    );
    println!("| N | allowed motions | rule's method | null-space RHS µs | range-space RHS µs | null-space projection µs | range-space projection µs |");
    println!("|---:|---:|---|---:|---:|---:|---:|");
    for n in [4, 5, 6, 7, 8, 10, 14] {
        let costs = |method| {
            let mut prepared = prepared(&necklace_program(n));
            prepared.loop_method = Some(method);
            call_costs(&prepared)
        };
        let (null, range) = (costs(Method::NullSpace), costs(Method::RangeSpace));
        let rule = if n - 2 >= 6 {
            "range-space"
        } else {
            "null-space"
        };
        println!(
            "| {n} | {} | {rule} | {:.2} | {:.2} | {:.2} | {:.2} |",
            n - 2,
            null.0,
            range.0,
            null.1,
            range.1
        );
    }
}

/// A run of `program` over `duration` with dopri5 at 1e-12, projected after each step and
/// sampled every `output`, with its CPU seconds; it must not fail.
fn projected_run(
    program: &str,
    duration: f64,
    output: f64,
) -> (lsdc::simulate::run::Simulation, f64) {
    let mut prepared = prepared(program);
    prepared.settings = Settings {
        integrator: Integrator::DormandPrince,
        duration,
        output,
        rtol: 1e-12,
        atol: 1e-12,
        stabilisation: Stabilisation::Projection,
        ..prepared.settings
    };
    let start = common::thread_cpu_seconds();
    let simulation = lsdc::simulate::run::run(&prepared, &mut |_| {});
    let seconds = common::thread_cpu_seconds() - start;
    let failure = &simulation.report.failure;
    assert!(failure.is_none(), "{failure:?}");
    (simulation, seconds)
}

/// The necklace at N = 10, 100, 300 and 1,000 over 0.2 s with dopri5 at 1e-12, projected after
/// each step: its energy drift and its loops' largest residuals (the suite's
/// `long_chains` runs N = 10 and 100).
fn necklace_accuracy() {
    println!(
        "\nThe necklace over 0.2 s, dopri5 at 1e-12 ({}).\n",
        common::build_profile()
    );
    println!("| N | method (the rule's) | steps | energy drift | position residual | velocity residual | smallest conditioning (passages) | run s (CPU) |");
    println!("|---:|---|---:|---:|---:|---:|---|---:|");
    for n in [10, 100, 300, 1000] {
        let (simulation, seconds) = projected_run(&necklace_program(n), 0.2, 0.02);
        let report = &simulation.report;
        let c = report.constraints.as_ref().expect("loops");
        println!(
            "| {n} | range-space | {} | {:.1e} | {:.1e} | {:.1e} | {} | {seconds:.2} |",
            report.steps,
            report.energy_drift.expect("conservative"),
            c.position_residual,
            c.velocity_residual,
            conditioning(c)
        );
    }
}

/// The ladder at N = 10, 100, 300 and 1,000 over 0.05 s with dopri5 at 1e-12, projected after
/// each step: its energy drift and its loops' largest residuals.
fn ladder_accuracy() {
    println!("\nThe ladder over 0.05 s, dopri5 at 1e-12.\n");
    println!("| N | steps | energy drift | position residual | velocity residual | before projection (position, velocity) | smallest conditioning (passages) | run s (CPU) |");
    println!("|---:|---:|---:|---:|---:|---|---|---:|");
    for n in [10, 100, 300, 1000] {
        let (simulation, seconds) = projected_run(&ladder_program(n), 0.05, 0.05);
        let report = &simulation.report;
        let c = report.constraints.as_ref().expect("loops");
        println!(
            "| {n} | {} | {:.1e} | {:.1e} | {:.1e} | {:.1e}, {:.1e} | {} | {seconds:.2} |",
            report.steps,
            report.energy_drift.expect("conservative"),
            c.position_residual,
            c.velocity_residual,
            c.position_residual_before_projection,
            c.velocity_residual_before_projection,
            conditioning(c)
        );
    }
}

/// The smallest conditioning of the kept rows a run saw (`ClosestApproach::ratio`, on the rows
/// made dimensionless) and how many singular passages it reported.
fn conditioning(c: &lsdc::simulate::constraints::ConstraintReport) -> String {
    let ratio = c.closest.as_ref().map_or(1.0, |closest| closest.ratio);
    format!("{ratio:.2e} ({})", c.singular.len())
}

fn rows_against_trees() {
    println!("A row of N parallelogram four-bars against the same bodies as a tree ({}, CPU time per call, best batch).\n", common::build_profile());
    println!("| N | bodies | tree µs | loops µs | loops / tree | projection µs | projection / loops RHS |");
    println!("|---:|---:|---:|---:|---:|---:|---:|");
    let mut measured = Vec::new();
    for n in ROWS {
        let (tree, _) = call_costs(&prepared(&row_program(n, false)));
        let (loops, projection) = call_costs(&prepared(&row_program(n, true)));
        println!(
            "| {n} | {} | {tree:.2} | {loops:.2} | {:.1} | {projection:.2} | {:.2} |",
            2 * n + 1,
            loops / tree,
            projection / loops
        );
        measured.push((
            n as f64,
            [tree, loops, projection].map(|c| c / (2 * n + 1) as f64),
        ));
    }
    let names = [
        "tree (closing joins removed)",
        "loops: right-hand side",
        "loops: projection",
    ];
    let series: Vec<Series> = (names.iter().enumerate())
        .map(|(column, name)| {
            let line = measured.iter().map(|&(n, c)| (n, c[column])).collect();
            (name.to_string(), line)
        })
        .collect();
    let caption = "A row of N four-bars: cost of one evaluation per body";
    match plot(PLOT, caption, &series) {
        Ok(()) => println!("\nPlot of the cost per body: {PLOT}"),
        Err(e) => println!("\nNo plot: {e}"),
    }
}

/// The necklace and the ladder at each N of `NECKLACES` and `LADDERS`: cost per call and per
/// body, and the exponent of the growth of each cost with N.
fn long_chains() {
    println!(
        "\nLong closed chains ({}, CPU time per call, best batch).\n",
        common::build_profile()
    );
    println!("| chain | N | bodies | start s | right-hand side µs | projection µs | RHS µs per body | projection µs per body |");
    println!("|---|---:|---:|---:|---:|---:|---:|---:|");
    /// A chain's name, its program for N, its bodies for N, and the N it is timed at.
    type Chain = (
        &'static str,
        fn(usize) -> String,
        fn(usize) -> usize,
        &'static [usize],
    );
    let programs: [Chain; 2] = [
        ("necklace", necklace_program, |n| n, &NECKLACES),
        ("ladder", ladder_program, |n| 2 * n + 2, &LADDERS),
    ];
    let mut series: Vec<Series> = Vec::new();
    for (name, program, bodies, sizes) in programs {
        let mut costs = Vec::new();
        let mut starts = Vec::new();
        for &n in sizes {
            // The start: compiling the program, assembling and closing its loops, deciding
            // their structure (`prepare`, the thread's CPU time).
            let text = program(n);
            let before = common::thread_cpu_seconds();
            let chain = prepared(&text);
            let start = common::thread_cpu_seconds() - before;
            starts.push((n as f64, start));
            let (rhs, projection) = call_costs(&chain);
            let b = bodies(n) as f64;
            println!(
                "| {name} | {n} | {} | {start:.3} | {rhs:.1} | {projection:.1} | {:.3} | {:.3} |",
                bodies(n),
                rhs / b,
                projection / b
            );
            costs.push((n as f64, [rhs / b, projection / b]));
        }
        let rhs: Vec<_> = costs.iter().map(|&(n, c)| (n, c[0])).collect();
        let projection: Vec<_> = costs.iter().map(|&(n, c)| (n, c[1])).collect();
        println!(
            "\n{name}: cost ∝ N^p, p = {:.2} (right-hand side), {:.2} (projection), {:.2} (start)\n",
            growth_exponent(&rhs) + 1.0,
            growth_exponent(&projection) + 1.0,
            growth_exponent(&starts)
        );
        series.push((format!("{name}: right-hand side"), rhs));
        series.push((format!("{name}: projection"), projection));
    }
    let caption = "Long closed chains: cost of one evaluation per body";
    match plot(CHAINS_PLOT, caption, &series) {
        Ok(()) => println!("Plot of the cost per body: {CHAINS_PLOT}"),
        Err(e) => println!("No plot: {e}"),
    }
}

/// The slope of log y against log x by least squares.
fn growth_exponent(points: &[(f64, f64)]) -> f64 {
    let logs: Vec<(f64, f64)> = points.iter().map(|&(x, y)| (x.ln(), y.ln())).collect();
    let count = logs.len() as f64;
    let (mean_x, mean_y) = logs
        .iter()
        .fold((0.0, 0.0), |(a, b), &(x, y)| (a + x / count, b + y / count));
    let covariance: f64 = logs.iter().map(|&(x, y)| (x - mean_x) * (y - mean_y)).sum();
    let variance: f64 = logs.iter().map(|&(x, _)| (x - mean_x).powi(2)).sum();
    covariance / variance
}

/// A line of a plot: its name, and its points (N, µs per body).
type Series = (String, Vec<(f64, f64)>);

/// Cost per body (µs) against N, log-log, one line per series.
fn plot(path: &str, caption: &str, series: &[Series]) -> Result<(), Box<dyn std::error::Error>> {
    use plotters::prelude::*;
    lsdc::output::plot::register_fonts()?;
    let family = lsdc::output::plot::FONT_FAMILY;
    let points = || series.iter().flat_map(|(_, line)| line.iter().copied());
    let highest = points().map(|p| p.1).fold(1e-3, f64::max);
    let lowest = points().map(|p| p.1).fold(highest, f64::min);
    let largest_n = points().map(|p| p.0).fold(1.0, f64::max);
    let smallest_n = points().map(|p| p.0).fold(largest_n, f64::min);
    let root = SVGBackend::new(path, (720, 440)).into_drawing_area();
    root.fill(&WHITE)?;
    let mut chart = ChartBuilder::on(&root)
        .caption(caption, (family, 18))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(
            (smallest_n..largest_n).log_scale(),
            (0.5 * lowest..2.0 * highest).log_scale(),
        )?;
    chart
        .configure_mesh()
        .x_desc("N")
        .y_desc("µs per body")
        .label_style((family, 13))
        .draw()?;
    let colours = [BLUE, RED, GREEN, MAGENTA];
    for (k, (label, line)) in series.iter().enumerate() {
        let colour = colours[k % colours.len()];
        chart
            .draw_series(LineSeries::new(
                line.iter().copied(),
                colour.stroke_width(2),
            ))?
            .label(label)
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], colour));
    }
    chart
        .configure_series_labels()
        .label_font((family, 13))
        .background_style(WHITE)
        .border_style(BLACK)
        .draw()?;
    root.present()?;
    Ok(())
}
