//! Dynamics algorithms per call on chains of revolute joints (6, 7, 32 links and 10 to 1,000
//! links), and simulation throughput on the examples. Run with `cargo bench --bench dynamics`.
//! Times are the best of several batches; ABA's time per link shows its O(n) growth.

mod common;
use common::best_time_per_call;
use std::hint::black_box;

use lsdc::driver::{compile_files, compile_text};
use lsdc::dynamics::algorithms::{aba, crba, rnea, Data};
use lsdc::dynamics::model::{self, Model};
use lsdc::kinematics::eval::UnknownValues;
use lsdc::kinematics::model as kinematic_model;
use lsdc::load::LoadOptions;
use lsdc::prepare::{prepare, Settings};
use lsdc::simulate::run::run;
use lsdc::spatial::Force;

fn options() -> LoadOptions {
    LoadOptions {
        library_dirs: Vec::new(),
        use_environment: false,
        scene: None,
    }
}

/// A chain of n links with revolute joints about alternating axes, each link 0.3 m long.
fn chain(n: usize) -> Model {
    let mut text = String::from("import joints;\n");
    let axes = ["[0,0,1]", "[0,1,0]", "[1,0,0]"];
    for i in 1..=n {
        text += &format!("let b{i} = body mass = 1.2, iframe = [0.15, 0, 0] ++ 1, inertia = [0.01, 0.02, 0.02] end;\n");
        let parent = if i == 1 {
            "earth".to_string()
        } else {
            format!("[0.3, 0, 0] ++ 1 @ b{}", i - 1)
        };
        text += &format!("join {parent} and b{i} with revolute({});\n", axes[i % 3]);
    }
    let compilation = compile_text("chain.lsd", &text, None, &options());
    let mechanism = compilation.mechanism.expect("elaborates");
    let topology = lsdc::topology::build(&mechanism).expect("connected");
    let kinematics =
        kinematic_model::build(&mechanism, topology, UnknownValues::new()).expect("numeric");
    model::build(&mechanism, &kinematics).expect("model")
}

fn main() {
    println!(
        "{:>6} {:>12} {:>12} {:>12} {:>14}",
        "links", "RNEA ns", "CRBA ns", "ABA ns", "ABA ns/link"
    );
    for n in [6, 7, 10, 32, 100, 300, 1000] {
        let model = chain(n);
        let mut data = Data::new(&model);
        let q: Vec<f64> = (0..model.nq).map(|i| (i as f64 * 0.37).sin()).collect();
        let v: Vec<f64> = (0..model.nv).map(|i| (i as f64 * 0.91).cos()).collect();
        let tau: Vec<f64> = (0..model.nv).map(|i| (i as f64 * 0.13).sin()).collect();
        let external = vec![Force::zeros(); n + 1];
        let rnea_ns = best_time_per_call(|| {
            black_box(rnea(&model, &mut data, &q, &v, &tau, &external).expect("evaluates"));
        }) * 1e9;
        let crba_ns = if n <= 300 {
            best_time_per_call(|| {
                black_box(crba(&model, &mut data, &q).expect("evaluates"));
            }) * 1e9
        } else {
            f64::NAN
        };
        let aba_ns = best_time_per_call(|| {
            black_box(aba(&model, &mut data, &q, &v, &tau, &external).expect("regular"));
        }) * 1e9;
        println!(
            "{n:>6} {rnea_ns:>12.0} {crba_ns:>12.0} {aba_ns:>12.0} {:>14.1}",
            aba_ns / n as f64
        );
    }
    println!("\nSimulation throughput on the examples (their own `simulate` settings):");
    println!(
        "{:<22} {:>10} {:>8} {:>12} {:>14}",
        "example", "simulated", "steps", "evaluations", "steps per s"
    );
    for name in [
        "pendulum",
        "double_pendulum",
        "heavy_top",
        "free_body",
        "satellite_springs",
    ] {
        let path = std::path::PathBuf::from(format!("examples/{name}.lsd"));
        let Ok(compilation) = compile_files(&[path], &options()) else {
            continue;
        };
        let Some(mechanism) = compilation.mechanism else {
            continue;
        };
        let Ok(prepared) = prepare(&mechanism, &[], &Settings::default()) else {
            continue;
        };
        let simulation = run(&prepared, &mut |_| {});
        let r = &simulation.report;
        println!(
            "{name:<22} {:>9.1}s {:>8} {:>12} {:>14.0}",
            r.duration,
            r.steps,
            r.function_evaluations,
            r.steps as f64 / r.wall_seconds
        );
    }
}
