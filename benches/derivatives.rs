//! The cost of the analytical derivatives against the algorithms they differentiate, on URDF
//! robots read with a fixed base and gravity (`cargo bench --bench derivatives -- ROBOT.urdf...`;
//! by default UR5, Panda and Talos reduced from `tests/fixtures/urdf`). Per robot, the thread CPU
//! time per call of RNEA, its derivatives (∂τ/∂q, ∂τ/∂v), ABA and its derivatives (∂q̈/∂q,
//! ∂q̈/∂v, M⁻¹), in interleaved rounds (each round times a batch of every one of them in turn,
//! so that the machine's load falls on all alike), best and median of 9 rounds, and the ratios
//! derivatives / algorithm. Prints one line per robot:
//! `NAME nv rnea_ns rnea_derivatives_ns ratio aba_ns aba_derivatives_ns ratio` (best, then median).
//!
//! The states are 256 random (q, v, a, τ), q uniform in [−π, π], the rest in [−1, 1], cycled.

mod common;
use common::{files_or, interleaved, prepared_file, random_states};
use std::hint::black_box;
use std::path::PathBuf;

use lsdc::dynamics::algorithms::aba_derivatives::AbaDerivatives;
use lsdc::dynamics::algorithms::rnea_derivatives::RneaDerivatives;
use lsdc::dynamics::algorithms::{aba_into, rnea_into, Data};
use lsdc::spatial::Force;
use nalgebra::DVector;

const ROUNDS: usize = 9;

fn main() {
    let paths = files_or(
        ["ur5", "panda", "talos_reduced"]
            .map(|r| PathBuf::from(format!("tests/fixtures/urdf/{r}.urdf")))
            .to_vec(),
    );
    for path in paths {
        let model = prepared_file(&path).model;
        let external = vec![Force::zeros(); model.body_count() + 1];
        let states = random_states(&model);
        let mut tau = DVector::zeros(model.nv);
        let mut accelerations = DVector::zeros(model.nv);
        let mut inverse = RneaDerivatives::new(&model);
        let mut forward = AbaDerivatives::new(&model);
        let mut data: Vec<Data> = (0..4).map(|_| Data::new(&model)).collect();
        let [d0, d1, d2, d3] = &mut data[..] else {
            unreachable!("four scratch spaces")
        };
        let cycle = std::cell::Cell::new(0usize);
        let next = || {
            cycle.set((cycle.get() + 1) % states.len());
            &states[cycle.get()]
        };
        let times = interleaved(
            [
                &mut || {
                    let [q, v, a, _] = next();
                    rnea_into(&model, d0, q, v, a, &external, &mut tau).expect("rnea");
                    black_box(&tau);
                },
                &mut || {
                    let [q, v, a, _] = next();
                    inverse
                        .compute(&model, d1, q, v, a, &external)
                        .expect("derivatives");
                    black_box(&inverse.dtau_dq);
                },
                &mut || {
                    let [q, v, _, t] = next();
                    aba_into(&model, d2, q, v, t, &external, &mut accelerations).expect("aba");
                    black_box(&accelerations);
                },
                &mut || {
                    let [q, v, _, t] = next();
                    forward
                        .compute(&model, d3, q, v, t, &external)
                        .expect("derivatives");
                    black_box(&forward.dacceleration_dq);
                },
            ],
            0.01,
            ROUNDS,
        );
        let name = path.file_stem().and_then(|s| s.to_str()).unwrap_or("robot");
        for (label, pick) in [("best", 0), ("median", 1)] {
            let t = |k: usize| if pick == 0 { times[k].0 } else { times[k].1 };
            println!(
                "{name} {label} nv={} rnea {:.0} ns, derivatives {:.0} ns ({:.2}x); aba {:.0} ns, derivatives {:.0} ns ({:.2}x)",
                model.nv,
                t(0) * 1e9,
                t(1) * 1e9,
                t(1) / t(0),
                t(2) * 1e9,
                t(3) * 1e9,
                t(3) / t(2),
            );
        }
    }
}
