//! What closed loops cost as they multiply: a row of N parallelogram four-bars (the programs of
//! `examples/hard/four_bar_row_N.lsd`, generated for any N by `common/rows.rs`) against the same 2N + 1 bodies
//! with the N closing joins removed (a tree: N + 1 cranks, each of the first N carrying a
//! coupler). For each N: one right-hand side of each, their ratio, and one projection onto the
//! loops. Run with `cargo bench --bench loop_scaling`; CPU time per call, best of 7 batches of
//! about 20 ms.

use lsdc::driver::compile_text;
use lsdc::load::LoadOptions;
use lsdc::prepare::{prepare, Prepared, Settings};

mod common;
#[path = "common/loop_costs.rs"]
mod loop_costs;
#[path = "common/rows.rs"]
mod rows;
use loop_costs::call_costs;
use rows::row_program;

const ROWS: [usize; 8] = [1, 2, 5, 10, 20, 40, 70, 100];

/// Where the plot of cost per body against N is written.
const PLOT: &str = "target/loop_scaling.svg";

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
    println!("A row of N parallelogram four-bars against the same bodies as a tree (release build, CPU time per call, best batch).\n");
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
        measured.push((n, tree, loops, projection));
    }
    match plot(&measured) {
        Ok(()) => println!("\nPlot of the cost per body: {PLOT}"),
        Err(e) => println!("\nNo plot: {e}"),
    }
}

/// Cost per body (µs) against N, log-log: the tree, the loops and the projection.
fn plot(measured: &[(usize, f64, f64, f64)]) -> Result<(), Box<dyn std::error::Error>> {
    use plotters::prelude::*;
    lsdc::output::plot::register_fonts()?;
    let family = lsdc::output::plot::FONT_FAMILY;
    let per_body = |cost: f64, n: usize| cost / (2 * n + 1) as f64;
    let highest = measured
        .iter()
        .map(|&(n, _, loops, projection)| per_body(loops.max(projection), n))
        .fold(1.0, f64::max);
    let root = SVGBackend::new(PLOT, (720, 440)).into_drawing_area();
    root.fill(&WHITE)?;
    let mut chart = ChartBuilder::on(&root)
        .caption(
            "A row of N four-bars: cost of one evaluation per body",
            (family, 18),
        )
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(
            (1f64..100f64).log_scale(),
            (0.1f64..2.0 * highest).log_scale(),
        )?;
    chart
        .configure_mesh()
        .x_desc("N (loops)")
        .y_desc("µs per body")
        .label_style((family, 13))
        .draw()?;
    let series = [
        ("tree (closing joins removed)", BLUE, 1),
        ("loops: right-hand side", RED, 2),
        ("loops: projection", GREEN, 3),
    ];
    for (label, colour, column) in series {
        let points = measured.iter().map(|m| {
            let cost = [m.1, m.2, m.3][column - 1];
            (m.0 as f64, per_body(cost, m.0))
        });
        chart
            .draw_series(LineSeries::new(points, colour.stroke_width(2)))?
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
