//! What closed loops cost as they multiply: a row of N parallelogram four-bars (the programs of
//! `examples/hard/four_bar_row_N.lsd`, generated here for any N) against the same 2N + 1 bodies
//! with the N closing joins removed (a tree: N + 1 cranks, each of the first N carrying a
//! coupler). For each N: one right-hand side of each, their ratio, and one projection onto the
//! loops. Run with `cargo bench --bench loop_scaling`; medians over batches of about 10 ms.

use std::cell::RefCell;
use std::hint::black_box;
use std::rc::Rc;
use std::time::Instant;

use lsdc::driver::compile_text;
use lsdc::load::LoadOptions;
use lsdc::simulate::prepare::{prepare, Prepared, Settings};
use lsdc::simulate::system::MechanicalSystem;

const ROWS: [usize; 6] = [1, 2, 5, 10, 20, 40];

/// The row of `n` four-bars, with its closing joins or without them.
fn row_program(n: usize, closed: bool) -> String {
    let mut text = String::from(
        "import joints ;\nimport gravity ;\nlet R = 0.5 ;\nlet L = 1.0 ;\nlet z = [0, 0, 1] ;\n\
         let down = [0, -9.81, 0] ;\n\
         let bar(l) = body mass = l, iframe = [l / 2, 0, 0] ++ 1, inertia = [1e-4 * l, l * l * l / 12, l * l * l / 12] end ;\n",
    );
    for i in 0..=n {
        text += &format!("let crank{i} = bar(R) ;\n");
        text +=
            &format!("join [{i} * L, 0, 0] ++ 1 @ earth and crank{i} with revolute(z) as c{i} ;\n");
        text += &format!("apply weight_in(crank{i}, down) on crank{i}.iframe ;\n");
    }
    let mut initial = vec!["c0.q = -pi / 2 fixed".to_string()];
    for i in 1..=n {
        text += &format!("let rod{i} = bar(L) ;\n");
        text += &format!(
            "join [R, 0, 0] ++ 1 @ crank{} and rod{i} with revolute(z) as p{i} ;\n",
            i - 1
        );
        text += &format!("apply weight_in(rod{i}, down) on rod{i}.iframe ;\n");
        initial.push(format!("c{i}.q = -pi / 2"));
        initial.push(format!("p{i}.q = pi / 2"));
        if closed {
            text += &format!(
                "join [L, 0, 0] ++ 1 @ rod{i} and [R, 0, 0] ++ 1 @ crank{i} with revolute(z) as e{i} ;\n"
            );
            initial.push(format!("e{i}.q = -pi / 2"));
        }
    }
    text += &format!("initial {} ;\ninitial c0.q' = 12.0 ;\n", initial.join(", "));
    text
}

fn prepared(text: &str) -> Prepared {
    let options = LoadOptions {
        library_dirs: Vec::new(),
        use_environment: false,
    };
    let compilation = compile_text("row.lsd", text, None, &options);
    assert!(!compilation.has_errors(), "{:?}", compilation.diagnostics);
    let mechanism = compilation.mechanism.expect("elaborates");
    prepare(&mechanism, &[], &Settings::default()).expect("prepares")
}

fn median(mut values: Vec<f64>) -> f64 {
    values.sort_by(f64::total_cmp);
    values[values.len() / 2]
}

/// Median time of one call of `f` over batches of about 10 ms.
fn time_per_call(mut f: impl FnMut()) -> f64 {
    let start = Instant::now();
    let mut calls = 0u64;
    while start.elapsed().as_secs_f64() < 0.01 {
        f();
        calls += 1;
    }
    let batches = (0..9)
        .map(|_| {
            let start = Instant::now();
            (0..calls).for_each(|_| f());
            start.elapsed().as_secs_f64() / calls as f64
        })
        .collect();
    median(batches)
}

/// One right-hand side and one projection (µs) at the program's initial state.
fn costs(prepared: &Prepared) -> (f64, f64) {
    let model = &prepared.model;
    let (mut y, v) = model
        .state_from_declared(&prepared.coordinates, &prepared.rates)
        .expect("initial state");
    y.extend_from_slice(&v);
    let reference = Rc::new(RefCell::new(prepared.coordinates.clone()));
    let mut system = MechanicalSystem::new(model, reference, prepared.settings.stabilisation);
    system.start_loops(&mut y).expect("loops close");
    let mut dydt = vec![0.0; y.len()];
    let rhs = time_per_call(|| {
        system
            .derivative(0.0, black_box(&y), &mut dydt)
            .expect("evaluates")
    });
    let projection = time_per_call(|| {
        let mut z = y.clone();
        black_box(system.keep_closed(0.0, &mut z).expect("projects"));
    });
    (rhs * 1e6, projection * 1e6)
}

fn main() {
    println!("A row of N parallelogram four-bars against the same bodies as a tree (release build, medians).\n");
    println!("| N | bodies | tree µs | loops µs | loops / tree | projection µs | projection / loops RHS |");
    println!("|---:|---:|---:|---:|---:|---:|---:|");
    for n in ROWS {
        let (tree, _) = costs(&prepared(&row_program(n, false)));
        let (loops, projection) = costs(&prepared(&row_program(n, true)));
        println!(
            "| {n} | {} | {tree:.2} | {loops:.2} | {:.1} | {projection:.2} | {:.2} |",
            2 * n + 1,
            loops / tree,
            projection / loops
        );
    }
}
