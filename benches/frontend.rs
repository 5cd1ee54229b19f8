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
        let parent = if i == 1 {
            "earth".to_string()
        } else {
            format!("[0.5,0,0] ++ 1 @ b{}", i - 1)
        };
        text.push_str(&format!("join {parent} and b{i} with hinge([0,0,1]);\n"));
        text.push_str(&format!(
            "apply force value = [0,0,-g * b{i}.mass], body = earth end on b{i}.iframe;\n"
        ));
    }
    text
}

struct Timing {
    parse: Duration,
    check: Duration,
    elaborate: Duration,
}

fn run(text: &str) -> Timing {
    let options = LoadOptions {
        library_dirs: Vec::new(),
        use_environment: false,
        scene: None,
    };
    let start = Instant::now();
    let (workspace, diagnostics) = load_text("chain.lsd", text, None, &options);
    let parse = start.elapsed();
    assert!(!diagnostics.has_errors());
    let start = Instant::now();
    let (checked, diagnostics) = lsdc::check::check(&workspace);
    let check = start.elapsed();
    assert!(!diagnostics.has_errors());
    let start = Instant::now();
    let (mechanism, _warnings) = lsdc::elab::elaborate(&workspace, &checked).expect("elaborates");
    let elaborate = start.elapsed();
    assert_eq!(mechanism.summary().joins, mechanism.joins.len());
    Timing {
        parse,
        check,
        elaborate,
    }
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

/// A library of `definitions` definitions (bodies, links, parameterised joints, constants) and a
/// program that uses three of them.
fn library_program(definitions: usize) -> String {
    let mut text = String::from("package lib =\n");
    for k in 0..definitions {
        text.push_str(&match k % 4 {
            0 => format!("  let part{k} = body mass = {k}.5, iframe = [0.1,0,0] ++ 1, inertia = [1,2,3] end;\n"),
            1 => format!("  let hinge{k}(axis) = link(q) dof = q || axis, torque = -{k}.0 * q' * axis end;\n"),
            2 => format!("  let slide{k} = link(x) dof = [x,0,0], force = [-{k}.0 * x, 0, 0] end;\n"),
            _ => format!("  let offset{k} = [0, 0, {k}.25] ++ (pi/{k} || [1,0,0]);\n"),
        });
    }
    text.push_str("end;\njoin earth and lib:part0 with lib:hinge1([0,0,1]);\n");
    text.push_str("join lib:offset3 @ lib:part0 and lib:part0.iframe with lib:slide2;\n");
    text
}

fn library_cost() {
    println!("\nA library of N definitions of which 3 are used (parse, check, elaborate; ms, best of 20):");
    println!(
        "{:>6} {:>9} {:>9} {:>9} {:>9}",
        "N", "parse", "check", "elab", "bodies"
    );
    let mut elab = Vec::new();
    for n in [4, 1_000] {
        let text = library_program(n);
        let t = best_of(20, &text);
        let options = LoadOptions {
            library_dirs: Vec::new(),
            use_environment: false,
            scene: None,
        };
        let (workspace, _) = load_text("library.lsd", &text, None, &options);
        let (checked, _) = lsdc::check::check(&workspace);
        let bodies = lsdc::elab::elaborate(&workspace, &checked)
            .expect("elaborates")
            .0
            .bodies
            .len();
        println!(
            "{n:>6} {:>9.3} {:>9.3} {:>9.3} {bodies:>9}",
            t.parse.as_secs_f64() * 1e3,
            t.check.as_secs_f64() * 1e3,
            t.elaborate.as_secs_f64() * 1e3
        );
        elab.push(t.elaborate.as_secs_f64());
    }
    println!(
        "elaboration time, 1,000 definitions vs 4: ratio {:.2}",
        elab[1] / elab[0]
    );
}

fn main() {
    println!(
        "{:>8} {:>9} {:>11} {:>11} {:>11} {:>11} {:>13}",
        "bodies", "bytes", "parse ms", "check ms", "elab ms", "total ms", "µs per body"
    );
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
    library_cost();
}
