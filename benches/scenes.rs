//! What a scene costs against the mechanism it reads alone: the `left_trajectory` scene of
//! `examples/robot_cell.lsd` (one arm of a two-arm cell with a linkage, the rest left out of
//! its model) against a program of that arm alone with the same output, and against the whole
//! cell with that output (no scenes: nothing left out). Per right-hand side (the derivative at
//! the initial state) and per run (1 s with RK4 at a 1 ms step, outputs every 10 ms). Run with
//! `cargo bench --bench scenes`. Times are CPU times of the timing thread, the three programs
//! timed in turn within each round (interleaved, so that a change of the machine's speed falls
//! on all three): the best over the rounds, and the median over the rounds (of each round's
//! median batch for a right-hand side). The ratios are the result.

mod common;
use common::{best, initial_state, median, rhs_cpu_time, run_cpu_seconds};

use lsdc::api::{Program, SettingsChanges};
use lsdc::load::LoadOptions;
use lsdc::prepare::{Integrator, Prepared};
use lsdc::simulate::system::MechanicalSystem;

const CELL: &str = "examples/robot_cell.lsd";
const ROUNDS: usize = 7;

fn prepared(text: &str, scene: Option<&str>) -> Prepared {
    let options = LoadOptions {
        library_dirs: Vec::new(),
        use_environment: false,
        scene: scene.map(str::to_string),
    };
    let dir = std::path::Path::new("examples");
    let program = Program::from_text("cell.lsd", text, Some(dir), &options);
    assert!(!program.has_errors(), "{}", program.render());
    let changes = SettingsChanges {
        integrator: Some(Integrator::Rk4),
        step: Some(1e-3),
        duration: Some(1.0),
        output: Some(0.01),
        ..Default::default()
    };
    program.prepare(&[], &changes).expect("prepares")
}

/// The three programs: the scene, the arm alone, the whole cell.
fn programs() -> [(&'static str, Prepared); 3] {
    let cell = std::fs::read_to_string(CELL).expect("the example is readable");
    let scenes = cell.find("scene left_trajectory").expect("its first scene");
    let linkage = cell.find("let l0 =").expect("its linkage");
    let output = "output tip = position(arm[1]:tip) ;";
    let alone = format!(
        "{}\n{output}\n",
        cell[..linkage].replace("package arm[k in 1 .. 2]", "package arm[k in 1 .. 1]")
    );
    let whole = format!("{}\n{output}\n", &cell[..scenes]);
    [
        (
            "scene left_trajectory",
            prepared(&cell, Some("left_trajectory")),
        ),
        ("the arm alone", prepared(&alone, None)),
        ("the whole cell, same output", prepared(&whole, None)),
    ]
}

/// Per round: a right-hand side's best and median batch (µs), and a run (ms).
struct Timing {
    name: &'static str,
    rhs: Vec<(f64, f64)>,
    run: Vec<f64>,
}

impl Timing {
    /// The best right-hand side and run over the rounds.
    fn best(&self) -> (f64, f64) {
        let rhs: Vec<f64> = self.rhs.iter().map(|t| t.0).collect();
        (best(&rhs), best(&self.run))
    }

    /// The median over the rounds of a right-hand side's median batch, and of a run.
    fn median(&self) -> (f64, f64) {
        (
            median(self.rhs.iter().map(|t| t.1).collect()),
            median(self.run.clone()),
        )
    }
}

fn time_rhs(prepared: &Prepared) -> (f64, f64) {
    let reference = prepared.coordinates.clone();
    let settings = prepared.settings.stabilisation;
    let mut system = MechanicalSystem::new(&prepared.model, reference, settings);
    rhs_cpu_time(&mut system, &initial_state(prepared))
}

fn main() {
    let programs = programs();
    let mut timings: Vec<Timing> = (programs.iter())
        .map(|(name, _)| Timing {
            name,
            rhs: Vec::new(),
            run: Vec::new(),
        })
        .collect();
    for _ in 0..ROUNDS {
        for ((_, prepared), timing) in programs.iter().zip(&mut timings) {
            let rhs = time_rhs(prepared);
            timing.rhs.push((rhs.0 * 1e6, rhs.1 * 1e6));
            timing.run.push(run_cpu_seconds(prepared) * 1e3);
        }
    }
    println!(
        "CPU time over {ROUNDS} interleaved rounds: the best, and the median of the rounds.\n"
    );
    println!("| case | RHS µs (best) | RHS µs (median) | run ms (best) | run ms (median) |");
    println!("|---|---:|---:|---:|---:|");
    for t in &timings {
        let ((rhs, run), (rhs_median, run_median)) = (t.best(), t.median());
        println!(
            "| {} | {rhs:.3} | {rhs_median:.3} | {run:.2} | {run_median:.2} |",
            t.name
        );
    }
    let (scene, alone, whole) = (&timings[0], &timings[1], &timings[2]);
    let ratio = |a: (f64, f64), b: (f64, f64)| (a.0 / b.0, a.1 / b.1);
    let (best, median) = (
        ratio(scene.best(), alone.best()),
        ratio(scene.median(), alone.median()),
    );
    println!(
        "\nscene / arm alone: {:.3} per RHS, {:.3} per run (best); {:.3} per RHS, {:.3} per run (median)",
        best.0, best.1, median.0, median.1
    );
    let (best, median) = (
        ratio(whole.best(), scene.best()),
        ratio(whole.median(), scene.median()),
    );
    println!(
        "whole cell / scene: {:.2} per RHS, {:.2} per run (best); {:.2} per RHS, {:.2} per run (median)",
        best.0, best.1, median.0, median.1
    );
}
