//! What running a fully driven subtree as kinematics saves (`dynamics::driven_subtrees`): a
//! cart on a sprung slide carrying a chain of `LINKS` revolute joints that all follow drives,
//! under gravity, run with the reduction (hybrid dynamics: the articulated-body algorithm with
//! the chain's accelerations known, the drives' efforts from the chain's inverse dynamics) and
//! with the drives as rows of the constraint stack (the articulated-body algorithm, then the
//! mass matrix, its factorisation and the rows' solve). Per right-hand side (the derivative at
//! t = 0.1) and per run (0.5 s with RK4 at a 1 ms step, outputs every 10 ms). Run with `cargo
//! bench --bench driven_subtrees`. Times are CPU times of the timing thread, the two forms timed
//! in turn within each round (interleaved): the best over the rounds and the median of the
//! rounds (of each round's median batch for a right-hand side).

mod common;
use common::{best, initial_state, median, rhs_cpu_time, run_cpu_seconds};

use lsdc::api::{Program, SettingsChanges};
use lsdc::load::LoadOptions;
use lsdc::prepare::{Integrator, Prepared};
use lsdc::simulate::system::MechanicalSystem;

const ROUNDS: usize = 7;

/// The cart and its driven chain of `links` joints, the axes alternating between z and y.
fn program_text(links: usize) -> String {
    let mut text = String::from(
        "import joints ;\nimport gravity ;\n\
         let rod(m, l) = body mass = m, iframe = [0, 0, l / 2] ++ 1, inertia = [m * l * l / 12, m * l * l / 12, m * l * l / 24] end ;\n\
         let sprung_slider(axis, k, c) = link(x) dof = x * axis, force = (-k * x - c * x') * axis end ;\n\
         let cart = body mass = 20, iframe = 0, inertia = [1, 2, 2] end ;\n\
         join earth and cart with sprung_slider([1, 0, 0], 400, 2) as slide ;\n\
         apply weight(cart) on cart.iframe ;\n\
         initial slide.x = 0.05 ;\n",
    );
    for k in 1..=links {
        let parent = match k {
            1 => "[0, 0, 0.1] ++ 1 @ cart".to_string(),
            _ => format!("[0, 0, 0.2] ++ 1 @ link{}", k - 1),
        };
        let axis = if k % 2 == 1 { "[0, 0, 1]" } else { "[0, 1, 0]" };
        text += &format!(
            "let link{k} = rod(1, 0.2) ;\n\
             join {parent} and link{k} with revolute({axis}) as j{k} ;\n\
             apply weight(link{k}) on link{k}.iframe ;\n\
             drive j{k}.q = 0.3 * sin({} * time + {k}) ;\n",
            1.0 + 0.1 * k as f64
        );
    }
    text
}

fn prepared(links: usize, keep_rows: bool) -> Prepared {
    let options = LoadOptions {
        library_dirs: Vec::new(),
        use_environment: false,
        scene: None,
    };
    let program = Program::from_text("chain.lsd", &program_text(links), None, &options);
    assert!(!program.has_errors(), "{}", program.render());
    let changes = SettingsChanges {
        integrator: Some(Integrator::Rk4),
        step: Some(1e-3),
        duration: Some(0.5),
        output: Some(0.01),
        ..Default::default()
    };
    let mut prepared = program.prepare(&[], &changes).expect("prepares");
    assert_eq!(prepared.driven_subtrees().map(|s| s.bodies), Some(links));
    if keep_rows {
        prepared.keep_drive_rows();
    }
    prepared
}

fn time_rhs(prepared: &Prepared) -> (f64, f64) {
    let reference = prepared.coordinates.clone();
    let settings = prepared.settings.stabilisation;
    let mut system = MechanicalSystem::new(&prepared.model, reference, settings);
    system.use_driven_subtrees(prepared.driven_subtrees());
    rhs_cpu_time(&mut system, &initial_state(prepared))
}

fn main() {
    println!(
        "CPU time over {ROUNDS} interleaved rounds: the best, and the median of the rounds.\n"
    );
    println!("| driven links | form | RHS µs (best) | RHS µs (median) | run ms (best) | run ms (median) |");
    println!("|---:|---|---:|---:|---:|---:|");
    let mut ratios = Vec::new();
    for links in [6, 12, 24] {
        let forms = [prepared(links, false), prepared(links, true)];
        // Per form: each round's best and median batch of right-hand sides (µs), and runs (ms).
        let mut rhs_best = [Vec::new(), Vec::new()];
        let mut rhs_median = [Vec::new(), Vec::new()];
        let mut runs = [Vec::new(), Vec::new()];
        for _ in 0..ROUNDS {
            for (f, prepared) in forms.iter().enumerate() {
                let (b, m) = time_rhs(prepared);
                rhs_best[f].push(b * 1e6);
                rhs_median[f].push(m * 1e6);
                runs[f].push(run_cpu_seconds(prepared) * 1e3);
            }
        }
        for (f, name) in ["kinematics (hybrid)", "drives as rows"].iter().enumerate() {
            println!(
                "| {links} | {name} | {:.3} | {:.3} | {:.2} | {:.2} |",
                best(&rhs_best[f]),
                median(rhs_median[f].clone()),
                best(&runs[f]),
                median(runs[f].clone())
            );
        }
        ratios.push((
            links,
            best(&rhs_best[1]) / best(&rhs_best[0]),
            median(rhs_median[1].clone()) / median(rhs_median[0].clone()),
            best(&runs[1]) / best(&runs[0]),
            median(runs[1].clone()) / median(runs[0].clone()),
        ));
    }
    println!();
    for (links, rhs, rhs_median, run, run_median) in ratios {
        println!(
            "{links} driven links: rows / hybrid {rhs:.2} per RHS, {run:.2} per run (best); {rhs_median:.2} per RHS, {run_median:.2} per run (median)"
        );
    }
}
