//! What the planar form saves (`dynamics::planar`): one right-hand side of planar mechanisms in
//! planar form (3-vectors per body, 3 rows per loop; `simulate --planar`) against the same in
//! spatial form (the default), at the initial state, with the largest difference of their
//! results.
//! The row of 40 four-bars is the target (at least 2× per right-hand side). Run with
//! `cargo bench --bench planar`. Times are CPU times of the timing thread, the two forms timed
//! in turn within each round (interleaved, so that a change of the machine's speed falls on
//! both): the best batch over the rounds, and the median over the rounds of each round's
//! median batch. The ratios are the result.

mod common;
#[path = "common/loop_costs.rs"]
mod loop_costs;
use common::cpu_time_per_call;
use loop_costs::{loop_system, median};
use std::hint::black_box;

use lsdc::driver::compile_files;
use lsdc::load::LoadOptions;
use lsdc::prepare::{prepare, Prepared, Settings};
use lsdc::simulate::system::MechanicalSystem;

const CASES: [&str; 6] = [
    "hard/four_bar_row_40",
    "hard/four_bar_row_10",
    "four_bar",
    "slider_crank",
    "double_pendulum",
    "hard/watt_six_bar",
];

const ROUNDS: usize = 7;

fn prepared(name: &str, spatial: bool) -> Prepared {
    let options = LoadOptions {
        library_dirs: Vec::new(),
        use_environment: false,
        scene: None,
    };
    let path = std::path::PathBuf::from(format!("examples/{name}.lsd"));
    let compilation = compile_files(&[path], &options).expect("loads");
    assert!(!compilation.has_errors(), "{:?}", compilation.diagnostics);
    let mechanism = compilation.mechanism.expect("elaborates");
    let mut prepared = prepare(&mechanism, &[], &Settings::default()).expect("prepares");
    if !spatial {
        prepared.take_planar().expect("planar");
    }
    prepared
}

/// The run's system at the initial state (its loops closed), evaluating in planar form where
/// the program has one, and that state.
fn system(prepared: &Prepared) -> (MechanicalSystem<'_>, Vec<f64>) {
    let (mut system, y) = loop_system(prepared);
    system.use_planar(prepared.planar_form());
    (system, y)
}

fn main() {
    println!("One right-hand side, planar form against spatial form (release build, µs of CPU per call; best batch over {ROUNDS} interleaved rounds, and the median of the rounds' medians).\n");
    println!("| mechanism | bodies | planar best | spatial best | ratio (best) | planar median | spatial median | ratio (median) | largest difference (relative) |");
    println!("|---|---:|---:|---:|---:|---:|---:|---:|---:|");
    for name in CASES {
        let (planar, spatial) = (prepared(name, false), prepared(name, true));
        assert!(planar.planar_form().is_some(), "{name} is planar");
        let (mut planar_system, _) = system(&planar);
        let (mut spatial_system, y_spatial) = system(&spatial);
        assert!(planar_system.uses_planar() && !spatial_system.uses_planar());
        let mut planar_rates = vec![0.0; y_spatial.len()];
        let mut spatial_rates = vec![0.0; y_spatial.len()];
        // The same state for both: the spatial start's.
        planar_system
            .derivative(0.0, &y_spatial, &mut planar_rates)
            .expect("planar");
        spatial_system
            .derivative(0.0, &y_spatial, &mut spatial_rates)
            .expect("spatial");
        let scale = spatial_rates.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let difference = planar_rates
            .iter()
            .zip(&spatial_rates)
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()))
            / scale;
        let (mut planar_times, mut spatial_times) = (Vec::new(), Vec::new());
        for _ in 0..ROUNDS {
            planar_times.push(cpu_time_per_call(|| {
                (planar_system)
                    .derivative(0.0, black_box(&y_spatial), &mut planar_rates)
                    .expect("planar")
            }));
            spatial_times.push(cpu_time_per_call(|| {
                (spatial_system)
                    .derivative(0.0, black_box(&y_spatial), &mut spatial_rates)
                    .expect("spatial")
            }));
        }
        let best = |times: &[(f64, f64)]| times.iter().map(|t| t.0).fold(f64::INFINITY, f64::min);
        let middle = |times: &[(f64, f64)]| median(times.iter().map(|t| t.1).collect());
        let (planar_best, spatial_best) = (best(&planar_times) * 1e6, best(&spatial_times) * 1e6);
        let (planar_median, spatial_median) =
            (middle(&planar_times) * 1e6, middle(&spatial_times) * 1e6);
        println!(
            "| {name} | {} | {planar_best:.2} | {spatial_best:.2} | {:.2} | {planar_median:.2} | {spatial_median:.2} | {:.2} | {difference:.1e} |",
            planar.model.body_count(),
            spatial_best / planar_best,
            spatial_median / planar_median,
        );
    }
}
