//! What a scene costs against the mechanism it reads alone: the `left_trajectory` scene of
//! `examples/robot_cell.lsd` (one arm of a two-arm cell with a linkage, the rest left out of
//! its model) against a program of that arm alone with the same output, and against the whole
//! cell with that output (no scenes: nothing left out). Per right-hand side (the derivative at
//! the initial state) and per run (1 s with RK4 at a 1 ms step, outputs every 10 ms). Run with
//! `cargo bench --bench scenes`. Times are CPU times of the timing thread: the best over rounds,
//! and the median of the last round. The ratios are the result.

mod common;
use common::{cpu_time_per_call, thread_cpu_seconds};
use std::hint::black_box;

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

struct Timing {
    name: &'static str,
    rhs: (f64, f64),
    run: (f64, f64),
}

fn time_rhs(prepared: &Prepared) -> (f64, f64) {
    let model = &prepared.model;
    let (q, v) = model
        .state_from_declared(&prepared.coordinates, &prepared.rates)
        .expect("initial state");
    let mut y = q;
    y.extend_from_slice(&v);
    let reference = prepared.coordinates.clone();
    let mut system = MechanicalSystem::new(model, reference, prepared.settings.stabilisation);
    let mut dydt = vec![0.0; y.len()];
    cpu_time_per_call(|| {
        system
            .derivative(0.1, black_box(&y), &mut dydt)
            .expect("evaluates");
    })
}

fn time_run(prepared: &Prepared) -> f64 {
    let start = thread_cpu_seconds();
    let simulation = lsdc::api::run(prepared, &mut |s| {
        black_box(s);
    });
    assert!(simulation.report.failure.is_none());
    thread_cpu_seconds() - start
}

fn main() {
    let programs = programs();
    let mut timings: Vec<Timing> = (programs.iter())
        .map(|(name, _)| Timing {
            name,
            rhs: (f64::INFINITY, 0.0),
            run: (f64::INFINITY, 0.0),
        })
        .collect();
    for _ in 0..ROUNDS {
        for ((_, prepared), timing) in programs.iter().zip(&mut timings) {
            let rhs = time_rhs(prepared);
            let run = time_run(prepared);
            timing.rhs = (timing.rhs.0.min(rhs.0 * 1e6), rhs.1 * 1e6);
            timing.run = (timing.run.0.min(run * 1e3), run * 1e3);
        }
    }
    println!(
        "{:<30} {:>8} {:>8} {:>9} {:>9}  (CPU time; best, last round)",
        "case", "RHS µs", "last", "run ms", "last"
    );
    for t in &timings {
        println!(
            "{:<30} {:>8.2} {:>8.2} {:>9.2} {:>9.2}",
            t.name, t.rhs.0, t.rhs.1, t.run.0, t.run.1
        );
    }
    let (scene, alone, whole) = (&timings[0], &timings[1], &timings[2]);
    println!(
        "scene / arm alone: {:.3} per RHS, {:.3} per run; whole cell / scene: {:.2} per RHS, {:.2} per run",
        scene.rhs.0 / alone.rhs.0,
        scene.run.0 / alone.run.0,
        whole.rhs.0 / scene.rhs.0,
        whole.run.0 / scene.run.0
    );
}
