//! Symbolic equations of n-link pendulums (n = 5 … 100): generation time, size with shared
//! subexpressions and without, their simplification (time per node and the exponent of its
//! growth, operations before and after), and evaluation of the generated code against the
//! numeric ABA.
//! Run with `cargo bench --bench symbolic`.

mod common;
use common::{best_time_per_call, cpu_time_per_call};
use std::hint::black_box;
use std::time::Instant;

use lsdc::driver::{compile_files, compile_text};
use lsdc::dynamics::algorithms::{aba, crba, rnea, Data};
use lsdc::dynamics::model;
use lsdc::elab::Mechanism;
use lsdc::kinematics::eval::UnknownValues;
use lsdc::kinematics::model as kinematic_model;
use lsdc::load::LoadOptions;
use lsdc::spatial::Force;
use lsdc::symbolic::expr::Tape;
use lsdc::symbolic::simplify::simplify_equations;
use lsdc::symbolic::{self, Equations};
use lsdc::topology::Topology;

const SIZES: [usize; 5] = [5, 10, 20, 50, 100];

/// A planar pendulum of n links 1 m long about parallel axes, each with its weight: the classic
/// benchmark of symbolic multibody tools.
pub fn pendulum_program(n: usize) -> String {
    let mut text = String::from("let g = 9.81 ;\n");
    for i in 1..=n {
        text += &format!("let l{i} = body mass = 1, iframe = [0, 0, -0.5] ++ 1, inertia = [0.08, 0.08, 0.01] end ;\n");
        let parent = if i == 1 {
            "earth".to_string()
        } else {
            format!("[0, 0, -1] ++ 1 @ l{}", i - 1)
        };
        text += &format!(
            "join {parent} and l{i}.frame with link(q) dof = q || [0, 1, 0] end as j{i} ;\n"
        );
        text += &format!(
            "apply force value = [0, 0, -g * l{i}.mass], body = earth end on l{i}.iframe ;\n"
        );
    }
    text
}

fn mechanism(text: &str) -> (Mechanism, Topology) {
    let options = LoadOptions {
        library_dirs: Vec::new(),
        use_environment: false,
        scene: None,
    };
    let compilation = compile_text("pendulum.lsd", text, None, &options);
    let mechanism = compilation.mechanism.expect("elaborates");
    let topology = lsdc::topology::build(&mechanism).expect("connected");
    (mechanism, topology)
}

fn generation() {
    println!("Generation of M, S and F for planar n-link pendulums (best of 3):");
    println!(
        "{:>5} {:>12} {:>10} {:>10} {:>10} {:>16} {:>12} {:>10}",
        "links", "generate ms", "all nodes", "M nodes", "M/n²", "M as trees", "q̈ nodes", "q̈/n"
    );
    for n in SIZES {
        let (mechanism, topology) = mechanism(&pendulum_program(n));
        let mut best = f64::INFINITY;
        let mut equations: Option<Equations> = None;
        for _ in 0..3 {
            let start = Instant::now();
            let eq = symbolic::generate(&mechanism, &topology).expect("equations");
            best = best.min(start.elapsed().as_secs_f64());
            equations = Some(black_box(eq));
        }
        let eq = equations.expect("generated");
        let mass = Tape::new(&eq.pool, &eq.mass);
        let accelerations = Tape::new(&eq.pool, eq.accelerations.as_deref().unwrap_or_default());
        println!(
            "{n:>5} {:>12.2} {:>10} {:>10} {:>10.1} {:>16.3e} {:>12} {:>10.1}",
            best * 1e3,
            eq.size(),
            mass.size(),
            mass.size() as f64 / (n * n) as f64,
            mass.expanded_size(),
            accelerations.size(),
            accelerations.size() as f64 / n as f64
        );
    }
}

/// The simplifier on the pendulums and the satellite: thread CPU time (best and median of 7 batches), per node of
/// the input, the exponent of the time's growth from the previous size (1 is linear), and the
/// operations of M, S and F and of all the roots (with the accelerations) before and after.
fn simplification() {
    println!(
        "\nSimplification of the pendulums' equations (thread CPU time, best and median of 7):"
    );
    println!(
        "{:>5} {:>10} {:>10} {:>10} {:>9} {:>9} {:>12} {:>12} {:>12} {:>12}",
        "links",
        "best ms",
        "median ms",
        "nodes",
        "µs/node",
        "growth",
        "M,S,F ops",
        "simplified",
        "all ops",
        "simplified"
    );
    let mut previous: Option<(usize, f64)> = None;
    for n in SIZES {
        let (mechanism, topology) = mechanism(&pendulum_program(n));
        let eq = symbolic::generate(&mechanism, &topology).expect("equations");
        let best = simplification_row(
            &n.to_string(),
            &eq,
            previous.map(|(m, t)| (n as f64 / m as f64, t)),
        );
        previous = Some((n, best));
    }
    let path = std::path::PathBuf::from("examples/satellite.lsd");
    let options = LoadOptions {
        library_dirs: Vec::new(),
        use_environment: false,
        scene: None,
    };
    if let Some(mechanism) = compile_files(&[path], &options)
        .ok()
        .and_then(|c| c.mechanism)
    {
        let topology = lsdc::topology::build(&mechanism).expect("connected");
        let eq = symbolic::generate(&mechanism, &topology).expect("equations");
        simplification_row("sat.", &eq, None);
    }
}

/// One row of the simplification table; `previous` is the ratio of the sizes (links) and the
/// best time of the previous row, for the growth exponent. Returns the best time.
fn simplification_row(label: &str, eq: &Equations, previous: Option<(f64, f64)>) -> f64 {
    let (best, median) = cpu_time_per_call(|| {
        black_box(simplify_equations(black_box(eq)));
    });
    let simplified = simplify_equations(eq);
    let operations = |eq: &Equations, all: bool| {
        let mut roots: Vec<_> = [&eq.mass, &eq.second_member, &eq.forces]
            .into_iter()
            .flatten()
            .copied()
            .collect();
        if all {
            roots = eq.roots();
        }
        Tape::new(&eq.pool, &roots).operation_count()
    };
    let nodes = eq.size();
    let growth = previous
        .map(|(ratio, t)| (best / t).ln() / ratio.ln())
        .unwrap_or(f64::NAN);
    println!(
        "{label:>5} {:>10.2} {:>10.2} {nodes:>10} {:>9.2} {growth:>9.2} {:>12} {:>12} {:>12} {:>12}",
        best * 1e3,
        median * 1e3,
        best * 1e6 / nodes as f64,
        operations(eq, false),
        operations(&simplified, false),
        operations(eq, true),
        operations(&simplified, true)
    );
    best
}

/// A program that times the generated functions of one pendulum and prints ns per call, by the
/// same best-of-batches rule as `best_time_per_call`.
const HARNESS: &str = r#"
fn best(mut f: impl FnMut()) -> f64 {
    let start = std::time::Instant::now();
    let mut calls = 0u64;
    while start.elapsed().as_secs_f64() < 0.02 { f(); calls += 1; }
    (0..7).map(|_| {
        let start = std::time::Instant::now();
        for _ in 0..calls { f(); }
        start.elapsed().as_secs_f64() / calls as f64
    }).fold(f64::INFINITY, f64::min)
}

fn main() {
    let p: Vec<f64> = (0..N).map(|i| (i as f64 * 0.37).sin()).collect();
    let q: Vec<f64> = (0..N).map(|i| (i as f64 * 0.91).cos()).collect();
    let k = [0.0; 0];
    let mut m = vec![0.0; N * N];
    let mut rhs = vec![0.0; N];
    let mut qdd = vec![0.0; N];
    let fd = best(|| { forward_dynamics(0.0, std::hint::black_box(&p), &q, &k, &mut qdd).unwrap(); std::hint::black_box(&qdd); });
    let mm = best(|| { mass_matrix(std::hint::black_box(&p), &k, &mut m); std::hint::black_box(&m); });
    let rh = best(|| { right_hand_side(0.0, std::hint::black_box(&p), &q, &k, &mut rhs); std::hint::black_box(&rhs); });
    println!("{} {} {}", fd * 1e9, mm * 1e9, rh * 1e9);
    for x in &qdd { println!("{x:e}"); }
}
"#;

/// Emits, compiles (rustc -C opt-level=3, as the release profile) and runs the generated code
/// of `equations`: ns per call of forward dynamics, mass matrix and right-hand side, the
/// compile time, and the accelerations at the harness's state.
fn time_generated(equations: &Equations, label: &str) -> Option<([f64; 3], f64, Vec<f64>)> {
    let name: String = label.chars().filter(char::is_ascii_alphanumeric).collect();
    let dir = std::env::temp_dir().join(format!("lsdc-symbolic-bench-{}", std::process::id()));
    std::fs::create_dir_all(&dir).ok()?;
    let source = dir.join(format!("{name}.rs"));
    std::fs::write(&source, symbolic::emit::rust(equations, label) + HARNESS).ok()?;
    let binary = dir.join(&name);
    let rustc = std::env::var("RUSTC").unwrap_or_else(|_| "rustc".to_string());
    let start = Instant::now();
    let status = std::process::Command::new(rustc)
        .args(["-C", "opt-level=3", "--edition", "2021"])
        .arg(&source)
        .arg("-o")
        .arg(&binary)
        .status()
        .ok()?;
    let compile = start.elapsed().as_secs_f64();
    if !status.success() {
        return None;
    }
    let output = std::process::Command::new(&binary).output().ok()?;
    let text = String::from_utf8(output.stdout).ok()?;
    let mut lines = text.lines();
    let times: Vec<f64> = lines
        .next()?
        .split_whitespace()
        .filter_map(|x| x.parse().ok())
        .collect();
    let accelerations = lines.filter_map(|x| x.parse().ok()).collect();
    Some(([times[0], times[1], times[2]], compile, accelerations))
}

/// The generated code against the numeric algorithms on the same mechanisms, in the same run:
/// the pendulums, then real robots (URDF fixtures).
fn evaluation() {
    println!("\nGenerated Rust against the numeric algorithms (ns per call, best of 7 batches):");
    println!(
        "{:>14} {:>10} {:>10} {:>8} {:>10} {:>10} {:>8} {:>10} {:>10} {:>8} {:>10} {:>10}",
        "mechanism",
        "gen. q̈",
        "ABA",
        "ratio",
        "gen. M",
        "CRBA",
        "ratio",
        "gen. S+F",
        "RNEA",
        "ratio",
        "compile s",
        "max |Δq̈|"
    );
    for n in SIZES {
        let (mechanism, topology) = mechanism(&pendulum_program(n));
        compare_generated(&format!("{n} links"), &mechanism, topology);
    }
    for robot in ["ur5", "panda", "talos_reduced"] {
        let path = std::path::PathBuf::from(format!("tests/fixtures/urdf/{robot}.urdf"));
        let options = LoadOptions {
            library_dirs: Vec::new(),
            use_environment: false,
            scene: None,
        };
        let Some(mechanism) = compile_files(&[path], &options)
            .ok()
            .and_then(|c| c.mechanism)
        else {
            continue;
        };
        let topology = lsdc::topology::build(&mechanism).expect("connected");
        compare_generated(robot, &mechanism, topology);
    }
}

fn compare_generated(label: &str, mechanism: &Mechanism, topology: Topology) {
    let eq = symbolic::generate(mechanism, &topology).expect("equations");
    let n = eq.dimension();
    let Some(([fd, mm, rh], compile, generated)) = time_generated(&eq, label) else {
        println!("{label:>14} (rustc unavailable or failed)");
        return;
    };
    let kinematics =
        kinematic_model::build(mechanism, topology, UnknownValues::new()).expect("numeric");
    let model = model::build(mechanism, &kinematics).expect("model");
    let mut data = Data::new(&model);
    let q: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin()).collect();
    let v: Vec<f64> = (0..n).map(|i| (i as f64 * 0.91).cos()).collect();
    let zero = vec![0.0; n];
    let none = vec![Force::zeros(); model.body_count() + 1];
    let aba_ns = best_time_per_call(|| {
        black_box(aba(&model, &mut data, black_box(&q), &v, &zero, &none).expect("regular"));
    }) * 1e9;
    let crba_ns = best_time_per_call(|| {
        black_box(crba(&model, &mut data, black_box(&q)).expect("evaluates"));
    }) * 1e9;
    let rnea_ns = best_time_per_call(|| {
        black_box(rnea(&model, &mut data, black_box(&q), &v, &zero, &none).expect("evaluates"));
    }) * 1e9;
    let numeric = aba(&model, &mut data, &q, &v, &zero, &none).expect("regular");
    let gap = numeric
        .iter()
        .zip(&generated)
        .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
    println!(
        "{label:>14} {fd:>10.0} {aba_ns:>10.0} {:>8.2} {mm:>10.0} {crba_ns:>10.0} {:>8.2} {rh:>10.0} {rnea_ns:>10.0} {:>8.2} {compile:>10.1} {gap:>10.1e}",
        fd / aba_ns,
        mm / crba_ns,
        rh / rnea_ns
    );
}

fn main() {
    generation();
    simplification();
    if std::env::args().any(|a| a == "simplification") {
        return;
    }
    evaluation();
}
