//! Symbolic equations of n-link pendulums (n = 5 … 100): generation time, size with shared
//! subexpressions and without, and evaluation of the generated code against the numeric ABA.
//! Run with `cargo bench --bench symbolic`.

mod common;
use common::best_time_per_call;
use std::hint::black_box;
use std::time::Instant;

use lsdc::driver::compile_text;
use lsdc::elab::Mechanism;
use lsdc::load::LoadOptions;
use lsdc::symbolic::expr::Tape;
use lsdc::symbolic::{self, Equations};
use lsdc::topology::Topology;

const SIZES: [usize; 5] = [5, 10, 20, 50, 100];

/// A planar pendulum of n links 1 m long about parallel axes, each with its weight: the classic
/// benchmark of symbolic multibody tools.
pub fn pendulum_program(n: usize) -> String {
    let mut text = String::from("let g = 9.81 ;\n");
    for i in 1..=n {
        text += &format!("let l{i} = body mass = 1, iframe = [0, 0, -0.5] ++ 1, inertia = [0.08, 0.08, 0.01] end ;\n");
        let parent = if i == 1 { "earth".to_string() } else { format!("[0, 0, -1] ++ 1 @ l{}", i - 1) };
        text += &format!("join {parent} and l{i}.frame with link(q) dof = q || [0, 1, 0] end as j{i} ;\n");
        text += &format!("apply force value = [0, 0, -g * l{i}.mass], body = earth end on l{i}.iframe ;\n");
    }
    text
}

fn mechanism(text: &str) -> (Mechanism, Topology) {
    let options = LoadOptions { library_dirs: Vec::new(), use_environment: false };
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

fn main() {
    generation();
    let _ = best_time_per_call(|| {});
}
