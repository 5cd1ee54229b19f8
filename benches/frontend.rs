//! Front-end time on generated chains of 1,000, 10,000 and 100,000 bodies, by phase.
//! Run with `cargo bench --bench frontend`. Prints the time per body of each size: linear growth
//! shows as a constant time per body.

use std::time::{Duration, Instant};

use lsdc::load::{load_text, LoadOptions};

/// A chain of `n` bodies on revolute joints, each 0.5 m from its parent, with gravity on each.
fn chain_program(n: usize) -> String {
    let mut text = String::with_capacity(n * 200);
    text.push_str("let g = 9.81;\nlet hinge(axis) = link(q) dof = q || axis, torque = -0.1 * q' * axis end;\n");
    for i in 1..=n {
        text.push_str(&format!("let b{i} = body mass = 1.5, iframe = [0.25,0,0] ++ 1, inertia = [0.01,0.02,0.02] end;\n"));
        let parent = if i == 1 { "earth".to_string() } else { format!("[0.5,0,0] ++ 1 @ b{}", i - 1) };
        text.push_str(&format!("join {parent} and b{i} with hinge([0,0,1]);\n"));
        text.push_str(&format!("apply force value = [0,0,-g * b{i}.mass], body = earth end on b{i}.iframe;\n"));
    }
    text
}

struct Timing {
    parse: Duration,
    check: Duration,
    elaborate: Duration,
}

fn run(text: &str) -> Timing {
    let options = LoadOptions { library_dirs: Vec::new(), use_environment: false };
    let start = Instant::now();
    let (workspace, diagnostics) = load_text("chain.lsd", text, None, &options);
    let parse = start.elapsed();
    assert!(!diagnostics.has_errors());
    let start = Instant::now();
    let (checked, diagnostics) = lsdc::check::check(&workspace);
    let check = start.elapsed();
    assert!(!diagnostics.has_errors());
    let start = Instant::now();
    let mechanism = lsdc::elab::elaborate(&workspace, &checked).expect("elaborates");
    let elaborate = start.elapsed();
    assert_eq!(mechanism.summary().joins, mechanism.joins.len());
    Timing { parse, check, elaborate }
}

fn best_of(runs: usize, text: &str) -> Timing {
    let mut best = run(text);
    for _ in 1..runs {
        let t = run(text);
        if t.parse + t.check + t.elaborate < best.parse + best.check + best.elaborate {
            best = t;
        }
    }
    best
}

fn main() {
    println!("{:>8} {:>9} {:>11} {:>11} {:>11} {:>11} {:>13}", "bodies", "bytes", "parse ms", "check ms", "elab ms", "total ms", "µs per body");
    let mut per_body = Vec::new();
    for n in [1_000, 10_000, 100_000] {
        let text = chain_program(n);
        let runs = if n >= 100_000 { 3 } else { 10 };
        let t = best_of(runs, &text);
        let total = t.parse + t.check + t.elaborate;
        let micros = total.as_secs_f64() * 1e6 / n as f64;
        per_body.push(micros);
        println!(
            "{n:>8} {:>9} {:>11.2} {:>11.2} {:>11.2} {:>11.2} {micros:>13.3}",
            text.len(),
            t.parse.as_secs_f64() * 1e3,
            t.check.as_secs_f64() * 1e3,
            t.elaborate.as_secs_f64() * 1e3,
            total.as_secs_f64() * 1e3
        );
    }
    println!(
        "time per body, 100,000 vs 1,000 bodies: ratio {:.2} (1.0 is perfectly linear)",
        per_body[2] / per_body[0]
    );
}
