//! The lsdc side of the speed comparison with Pinocchio (`bench/speed_vs_pinocchio.sh`): RNEA,
//! CRBA and ABA per call on URDF robots, read through `lsdc`'s URDF import with a fixed base and
//! gravity. Run with `cargo bench --bench pinocchio_peer -- ROBOT.urdf...`; prints one line per
//! robot: `NAME rnea_ns crba_ns aba_ns nv`.
//!
//! The states are 256 random (q, v, a, τ), q uniform in [−π, π], the rest in [−1, 1], cycled;
//! each time is the best of 7 batches of about 20 ms, as on the Pinocchio side.

mod common;
use common::{best_time_per_call, load_urdf as load, random_states};
use std::hint::black_box;
use std::path::PathBuf;

use lsdc::dynamics::algorithms::{aba_into, crba_into, rnea_into, Data};
use lsdc::spatial::Force;
use nalgebra::{DMatrix, DVector};

fn main() {
    let paths: Vec<PathBuf> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with("--"))
        .map(PathBuf::from)
        .collect();
    for path in paths {
        let model = load(&path);
        // Gravity is a field of the model (no per-body effort to evaluate), as in Pinocchio.
        assert!(
            model.applied.is_empty() && model.link_efforts.is_empty(),
            "{}: efforts other than gravity",
            path.display()
        );
        let mut data = Data::new(&model);
        let external = vec![Force::zeros(); model.body_count() + 1];
        let states = random_states(&model);
        let mut tau = DVector::zeros(model.nv);
        let mut mass = DMatrix::zeros(model.nv, model.nv);
        let mut accelerations = DVector::zeros(model.nv);
        let mut k = 0;
        let mut next = || {
            k = (k + 1) % states.len();
            &states[k]
        };
        let rnea_ns = best_time_per_call(|| {
            let [q, v, a, _] = next();
            rnea_into(&model, &mut data, q, v, a, &external, &mut tau).expect("rnea");
            black_box(&tau);
        });
        let crba_ns = best_time_per_call(|| {
            let [q, ..] = next();
            crba_into(&model, &mut data, q, &mut mass).expect("crba");
            black_box(&mass);
        });
        let aba_ns = best_time_per_call(|| {
            let [q, v, _, t] = next();
            aba_into(&model, &mut data, q, v, t, &external, &mut accelerations).expect("aba");
            black_box(&accelerations);
        });
        let name = path.file_stem().and_then(|s| s.to_str()).unwrap_or("robot");
        println!(
            "{name} {:.0} {:.0} {:.0} {}",
            rnea_ns * 1e9,
            crba_ns * 1e9,
            aba_ns * 1e9,
            model.nv
        );
    }
}
