//! The regressor of inverse dynamics (`dynamics::algorithms::regressor`) against RNEA itself:
//! RNEA is affine in the bodies' inertial parameters, so Y(q, v, a) π, with π the model's own
//! parameters, is RNEA at (q, v, a) less RNEA with every body's inertia zeroed (what is left:
//! the external forces and the geared rotors). Exact to round-off (1e-12 of the largest
//! generalised force) on random trees of every joint kind of `common::trees` (welds merged,
//! rotors, friction, mimics), on the examples without loops and on the UR5, Panda and Talos.

use lsdc::driver::compile_files;
use lsdc::dynamics::algorithms::regressor::{model_parameters, regressor};
use lsdc::dynamics::algorithms::{rnea, Data};
use lsdc::dynamics::model::Model;
use lsdc::load::LoadOptions;
use lsdc::prepare::{prepare, Settings};
use lsdc::spatial::{Inertia, RigidInertia};
use nalgebra::DVector;
use proptest::prelude::*;

use crate::common::example_paths;
use crate::common::trees::{featured_tree_program, JOINTS};
use crate::derivatives::{point, robot_model, Point};
use crate::dynamics::model_of;

/// max |Y π − (RNEA(π) − RNEA(0))| / max(1, max |RNEA(π)|) at a state made of `numbers`.
fn regressor_mismatch(model: &Model, numbers: &[f64]) -> f64 {
    let Point {
        q, v, a, external, ..
    } = point(model, numbers);
    let mut data = Data::new(model);
    let full = rnea(model, &mut data, &q, &v, &a, &external).expect("rnea");
    let mut without = model.clone();
    for body in &mut without.dynamic_bodies {
        // Both forms of the body's inertia: RNEA reads the compact one.
        body.inertia = Inertia::zeros();
        body.rigid = RigidInertia::zeros();
    }
    let rest = rnea(&without, &mut Data::new(&without), &q, &v, &a, &external).expect("rnea");
    let y = regressor(model, &mut data, &q, &v, &a).expect("regressor");
    let predicted = &y * DVector::from_vec(model_parameters(model));
    (predicted - (&full - rest)).amax() / full.amax().max(1.0)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

    #[test]
    fn the_regressor_gives_rnea_on_random_trees(
        parents in prop::collection::vec(any::<prop::sample::Index>(), 1..12),
        kinds in prop::collection::vec(0..JOINTS.len(), 12),
        features in prop::collection::vec(0usize..8, 12),
        numbers in prop::collection::vec(-1.5f64..1.5, 64),
    ) {
        let parents: Vec<usize> = parents.iter().enumerate().map(|(i, p)| p.index(i + 1)).collect();
        let text = featured_tree_program(&parents, &kinds, &features, &numbers);
        let model = model_of(&text);
        let measure = regressor_mismatch(&model, &numbers);
        prop_assert!(measure <= 1e-12, "{measure:e}\n{text}");
    }
}

#[test]
fn the_regressor_gives_rnea_on_the_examples_and_robots() {
    let numbers: Vec<f64> = (0..64)
        .map(|k| ((k * 37 % 61) as f64 / 20.0) - 1.5)
        .collect();
    let options = LoadOptions {
        library_dirs: Vec::new(),
        use_environment: false,
        scene: None,
    };
    let mut covered = Vec::new();
    for path in example_paths() {
        let Ok(compilation) = compile_files(std::slice::from_ref(&path), &options) else {
            continue;
        };
        if compilation.has_errors() {
            continue;
        }
        let Some(mechanism) = compilation.mechanism else {
            continue;
        };
        let Ok(prepared) = prepare(&mechanism, &[], &Settings::default()) else {
            continue;
        };
        // The loops' coordinates are left out: the regressor is the tree's, as RNEA is.
        let measure = regressor_mismatch(&prepared.model, &numbers);
        assert!(measure <= 1e-12, "{}: {measure:e}", path.display());
        covered.push(path);
    }
    assert!(
        covered.len() >= 30,
        "only {} examples: {covered:?}",
        covered.len()
    );
    for (robot, floating) in [("ur5", false), ("panda", false), ("talos_reduced", true)] {
        let measure = regressor_mismatch(&robot_model(robot, floating), &numbers);
        assert!(measure <= 1e-12, "{robot}: {measure:e}");
    }
}
