//! lsdc's side of the peer benchmark (`bench/peers.py`, which times Pinocchio's and MuJoCo's side
//! the same way and alternates the three round by round). Run by the driver as
//!
//!     cargo bench --bench peers -- NAME=ROBOT.urdf... rowN...
//!
//! It loads every case, prints `ready CASE...`, then answers each line `CASE CALLS` of its
//! standard input with the CPU time, in seconds, that this thread spent on CALLS calls of CASE
//! (the thread's clock: the time the shared machine gave to other programs is left out). Cases:
//!
//! - `NAME/rnea`, `NAME/crba`, `NAME/aba` on a URDF robot read through lsdc's URDF import
//!   (fixed base, gravity): 256 random states (q uniform in [−π, π], v, a and τ in [−1, 1])
//!   cycled, as Pinocchio's side does; `NAME/rnea_derivatives` (∂τ/∂q, ∂τ/∂v) and
//!   `NAME/aba_derivatives` (∂q̈/∂q, ∂q̈/∂v, M⁻¹) on the same states, beside Pinocchio's
//!   `computeRNEADerivatives` and `computeABADerivatives`;
//! - `NAME/step`: one step of RK4 at 1 ms of the robot falling under gravity (`Simulator::step`,
//!   the stiffness check off and the joints' limits off: the integrator's work alone on the
//!   problem MuJoCo's `mj_step` solves), started again
//!   from rest at q = 0 every 1,000 steps, outside the timed steps;
//! - `rowN/evaluation`: one right-hand side of the row of N parallelogram four-bars at its
//!   initial state (`MechanicalSystem::derivative`: the tree, the loops' rows and their solve),
//!   beside MuJoCo's `mj_forward` on the same bodies; `rowN/tree`: the same bodies without the
//!   closing joins, a tree.

mod common;
#[path = "common/loop_costs.rs"]
mod loop_costs;
#[path = "common/rows.rs"]
mod rows;
use common::{prepared_file, thread_cpu_seconds};
use std::collections::HashMap;
use std::hint::black_box;
use std::io::{BufRead, Write};
use std::path::Path;

use lsdc::driver::compile_text;
use lsdc::dynamics::algorithms::aba_derivatives::AbaDerivatives;
use lsdc::dynamics::algorithms::rnea_derivatives::RneaDerivatives;
use lsdc::dynamics::algorithms::{aba_into, crba_into, rnea_into, Data};
use lsdc::load::LoadOptions;
use lsdc::prepare::{prepare, Integrator, Prepared, Settings};
use lsdc::simulate::simulator::{Simulator, Start};
use lsdc::spatial::Force;
use nalgebra::{DMatrix, DVector};

const OPTIONS: LoadOptions = LoadOptions {
    library_dirs: Vec::new(),
    use_environment: false,
    scene: None,
};

fn prepared_text(text: &str) -> Prepared {
    let compilation = compile_text("row.lsd", text, None, &OPTIONS);
    assert!(!compilation.has_errors(), "{:?}", compilation.diagnostics);
    prepare(
        &compilation.mechanism.expect("elaborates"),
        &[],
        &Settings::default(),
    )
    .expect("prepares")
}

/// Something to call `calls` times, which returns the CPU seconds the calls took (results are
/// kept from the optimiser).
type Case<'a> = Box<dyn FnMut(u64) -> f64 + 'a>;

/// The CPU seconds of `calls` calls of `f`.
fn timed(calls: u64, mut f: impl FnMut()) -> f64 {
    let start = thread_cpu_seconds();
    (0..calls).for_each(|_| f());
    thread_cpu_seconds() - start
}

/// RNEA, CRBA, ABA and the derivatives of RNEA and ABA on a URDF robot, over cycled random
/// states.
fn algorithm_cases<'a>(name: &str, prepared: &'a Prepared, cases: &mut Vec<(String, Case<'a>)>) {
    let model = &prepared.model;
    // Gravity is a field of the model (no per-body effort to evaluate), as in Pinocchio.
    assert!(
        model.applied.is_empty() && model.link_efforts.is_empty(),
        "{name}: efforts other than gravity"
    );
    let states = std::rc::Rc::new(common::random_states(model));
    let external = vec![Force::zeros(); model.body_count() + 1];
    {
        let (states, external) = (states.clone(), external.clone());
        let mut data = Data::new(model);
        let mut tau = DVector::zeros(model.nv);
        let mut k = 0;
        cases.push((
            format!("{name}/rnea"),
            Box::new(move |calls| {
                timed(calls, || {
                    k = (k + 1) % states.len();
                    let [q, v, a, _] = &states[k];
                    rnea_into(model, &mut data, q, v, a, &external, &mut tau).expect("rnea");
                    black_box(&tau);
                })
            }),
        ));
    }
    {
        let states = states.clone();
        let mut data = Data::new(model);
        let mut mass = DMatrix::zeros(model.nv, model.nv);
        let mut k = 0;
        cases.push((
            format!("{name}/crba"),
            Box::new(move |calls| {
                timed(calls, || {
                    k = (k + 1) % states.len();
                    crba_into(model, &mut data, &states[k][0], &mut mass).expect("crba");
                    black_box(&mass);
                })
            }),
        ));
    }
    {
        let (states, external) = (states.clone(), external.clone());
        let mut data = Data::new(model);
        let mut inverse = RneaDerivatives::new(model);
        let mut k = 0;
        cases.push((
            format!("{name}/rnea_derivatives"),
            Box::new(move |calls| {
                timed(calls, || {
                    k = (k + 1) % states.len();
                    let [q, v, a, _] = &states[k];
                    (inverse.compute(model, &mut data, q, v, a, &external)).expect("derivatives");
                    black_box(&inverse.dtau_dq);
                })
            }),
        ));
    }
    {
        let (states, external) = (states.clone(), external.clone());
        let mut data = Data::new(model);
        let mut forward = AbaDerivatives::new(model);
        let mut k = 0;
        cases.push((
            format!("{name}/aba_derivatives"),
            Box::new(move |calls| {
                timed(calls, || {
                    k = (k + 1) % states.len();
                    let [q, v, _, t] = &states[k];
                    (forward.compute(model, &mut data, q, v, t, &external)).expect("derivatives");
                    black_box(&forward.dacceleration_dq);
                })
            }),
        ));
    }
    let mut data = Data::new(model);
    let mut accelerations = DVector::zeros(model.nv);
    let mut k = 0;
    cases.push((
        format!("{name}/aba"),
        Box::new(move |calls| {
            timed(calls, || {
                k = (k + 1) % states.len();
                let [q, v, _, t] = &states[k];
                aba_into(model, &mut data, q, v, t, &external, &mut accelerations).expect("aba");
                black_box(&accelerations);
            })
        }),
    ));
}

/// Steps of RK4 at 1 ms from rest at q = 0, started again every 1,000 steps (not timed).
fn step_case<'a>(prepared: &'a Prepared, start: &'a [Vec<f64>; 2]) -> Case<'a> {
    let start = Start {
        coordinates: &start[0],
        rates: &start[1],
    };
    let mut simulator = Simulator::from_start(prepared, &start, &[], None).expect("starts");
    let mut steps = 0u64;
    Box::new(move |calls| {
        let started = thread_cpu_seconds();
        let mut untimed = 0.0;
        for _ in 0..calls {
            if steps.is_multiple_of(1000) {
                let before = thread_cpu_seconds();
                simulator.reset(&start).expect("starts again");
                untimed += thread_cpu_seconds() - before;
            }
            simulator.step().expect("steps");
            steps += 1;
        }
        black_box(simulator.time());
        thread_cpu_seconds() - started - untimed
    })
}

/// The settings of a step case: RK4 at 1 ms, no stiffness check, outputs and steps enough for
/// any batch; and the joints' limits off, as MuJoCo's side has them (`bench/peers.py`): the
/// URDF's limits are stops in lsdc, and Panda's fingers start on theirs (lower limit 0), so
/// with them lsdc would hold the fingers at rest (rows solved at every evaluation) where MuJoCo
/// lets them move.
fn stepping(mut prepared: Prepared) -> Prepared {
    prepared.model.stops.clear();
    let settings = &mut prepared.settings;
    settings.integrator = Integrator::Rk4;
    settings.step = Some(1e-3);
    settings.duration = 1e6;
    settings.output = 1e6;
    settings.max_steps = usize::MAX;
    settings.stiffness_check = false;
    prepared
}

fn main() {
    let arguments: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with("--"))
        .collect();
    // Everything the cases borrow is made first and kept for the whole run.
    let mut robots = Vec::new();
    let mut rows = Vec::new();
    for argument in &arguments {
        if let Some((name, path)) = argument.split_once('=') {
            let prepared = prepared_file(Path::new(path));
            let start = [
                vec![0.0; prepared.coordinates.len()],
                vec![0.0; prepared.rates.len()],
            ];
            let stepped = stepping(prepared_file(Path::new(path)));
            robots.push((name.to_string(), prepared, stepped, start));
        } else if let Some(n) = argument.strip_prefix("row").and_then(|n| n.parse().ok()) {
            let closed = prepared_text(&rows::row_program(n, true));
            let open = prepared_text(&rows::row_program(n, false));
            rows.push((argument.clone(), closed, open));
        } else {
            eprintln!("usage: cargo bench --bench peers -- NAME=ROBOT.urdf... rowN...");
            std::process::exit(2);
        }
    }
    let trees: Vec<_> = rows
        .iter()
        .map(|(_, _, open)| loop_costs::tree_model(open))
        .collect();
    let mut cases: Vec<(String, Case)> = Vec::new();
    for (name, prepared, stepped, start) in &robots {
        algorithm_cases(name, prepared, &mut cases);
        cases.push((format!("{name}/step"), step_case(stepped, start)));
    }
    for ((name, closed, open), (tree, y_tree)) in rows.iter().zip(&trees) {
        let (mut system, y) = loop_costs::loop_system(closed);
        let mut dydt = vec![0.0; y.len()];
        cases.push((
            format!("{name}/evaluation"),
            Box::new(move |calls| {
                timed(calls, || {
                    system
                        .derivative(0.0, black_box(&y), &mut dydt)
                        .expect("evaluates")
                })
            }),
        ));
        let mut call = loop_costs::tree_call(open, tree, y_tree);
        cases.push((
            format!("{name}/tree"),
            Box::new(move |calls| timed(calls, &mut call)),
        ));
    }
    serve(cases);
}

/// The protocol: `ready CASE...`, then one line of CPU seconds per line `CASE CALLS`.
fn serve(cases: Vec<(String, Case)>) {
    let names: Vec<String> = cases.iter().map(|(name, _)| name.clone()).collect();
    let mut cases: HashMap<String, Case> = cases.into_iter().collect();
    let stdout = std::io::stdout();
    let mut out = stdout.lock();
    writeln!(out, "ready {}", names.join(" ")).expect("stdout");
    out.flush().expect("stdout");
    for line in std::io::stdin().lock().lines() {
        let line = line.expect("stdin");
        let mut words = line.split_whitespace();
        let (Some(name), Some(calls)) = (words.next(), words.next().and_then(|c| c.parse().ok()))
        else {
            writeln!(out, "error: expected `CASE CALLS`, got `{line}`").expect("stdout");
            out.flush().expect("stdout");
            continue;
        };
        match cases.get_mut(name) {
            Some(case) => writeln!(out, "{:.9e}", case(calls)).expect("stdout"),
            None => writeln!(out, "error: no case `{name}`").expect("stdout"),
        }
        out.flush().expect("stdout");
    }
}
