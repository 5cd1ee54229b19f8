//! The cost of the constrained dynamics' derivatives (`loops::derivatives`: ∂q̈/∂q, ∂q̈/∂v,
//! ∂q̈/∂τ in every state velocity) against one constrained right-hand side of the same
//! mechanism (`MechanicalSystem::derivative`: efforts, rows, the null-space solve), at its
//! closed initial state (`cargo bench --bench loop_derivatives -- FILE.lsd...`; by default the
//! four-bar, the slider-crank, Bennett's and Bricard's linkages, Watt's six-bar and a row of ten
//! four-bars). Thread CPU time per call, the two interleaved round by round (`interleaved`),
//! best and median of 9 rounds. Prints per mechanism:
//! `NAME best|median n=VELOCITIES rows=KEPT rhs NS, derivatives NS (RATIOx)`.

mod common;
#[path = "common/loop_costs.rs"]
mod loop_costs;
use common::{files_or, interleaved, prepared_file};
use loop_costs::loop_system;
use std::hint::black_box;
use std::path::PathBuf;

use lsdc::dynamics::algorithms::Data;
use lsdc::dynamics::loops::derivatives::ConstrainedDerivatives;
use lsdc::dynamics::loops::Structure;
use lsdc::spatial::Force;

const ROUNDS: usize = 9;

fn main() {
    let paths = files_or(
        [
            "four_bar",
            "slider_crank",
            "hard/bennett",
            "hard/bricard",
            "hard/watt_six_bar",
            "hard/four_bar_row_10",
        ]
        .map(|name| PathBuf::from(format!("examples/{name}.lsd")))
        .to_vec(),
    );
    for path in paths {
        let prepared = prepared_file(&path);
        let model = &prepared.model;
        let (mut system, y) = loop_system(&prepared);
        let (q, v) = y.split_at(model.positions());
        let structure = Structure::decide(model, &mut Data::new(model), q).expect("structure");
        let tau = vec![0.0; model.velocities()];
        let external = vec![Force::zeros(); model.body_count() + 1];
        let mut derivatives = ConstrainedDerivatives::new(model);
        let mut data = Data::new(model);
        let mut dydt = vec![0.0; y.len()];
        let times = interleaved(
            [
                &mut || {
                    system
                        .derivative(0.0, black_box(&y), &mut dydt)
                        .expect("evaluates");
                    black_box(&dydt);
                },
                &mut || {
                    derivatives
                        .compute(model, &mut data, &structure, q, v, &tau, &external)
                        .expect("derivatives");
                    black_box(&derivatives.dacceleration_dq);
                },
            ],
            0.01,
            ROUNDS,
        );
        let name = path.display().to_string();
        for (label, pick) in [("best", 0), ("median", 1)] {
            let t = |k: usize| if pick == 0 { times[k].0 } else { times[k].1 };
            println!(
                "{name} {label} n={} rows={} rhs {:.0} ns, derivatives {:.0} ns ({:.1}x)",
                model.velocities(),
                structure.choice.rows.len(),
                t(0) * 1e9,
                t(1) * 1e9,
                t(1) / t(0),
            );
        }
    }
}
