//! The mass matrix of the composite-rigid-body algorithm (`dynamics::algorithms::crba`) against
//! an independent algorithm: column j of M(q) is the inverse dynamics (RNEA) at rest with the
//! unit acceleration e_j, gravity off. On trees with branches (Talos: legs, arms and head on
//! one torso; Solo12: four legs), a prismatic axis along −y (Panda's finger), joints whose motion
//! column is not along one axis of the body's frame, spherical and free joints, merged welds and
//! geared rotors.

use lsdc::dynamics::algorithms::{crba, rnea, Data};
use lsdc::dynamics::model::Model;
use lsdc::spatial::Force;

use crate::common::programs::prepared_file;
use nalgebra::{DMatrix, Vector3};

/// M(q) column by column from inverse dynamics.
fn rnea_columns(model: &Model, q: &[f64]) -> DMatrix<f64> {
    let mut no_gravity = model.clone();
    no_gravity.gravity = Vector3::zeros();
    let mut data = Data::new(&no_gravity);
    let external = vec![Force::zeros(); model.body_count() + 1];
    let rest = vec![0.0; model.nv];
    let mut columns = DMatrix::zeros(model.nv, model.nv);
    for j in 0..model.nv {
        let mut a = rest.clone();
        a[j] = 1.0;
        let tau = rnea(&no_gravity, &mut data, q, &rest, &a, &external).expect("rnea");
        columns.set_column(j, &tau);
    }
    columns
}

#[test]
fn crba_equals_inverse_dynamics_columns_on_branched_trees_and_every_joint_kind() {
    let files = [
        "tests/fixtures/urdf/talos_reduced.urdf",
        "tests/fixtures/urdf/solo12.urdf",
        "tests/fixtures/urdf/panda.urdf",
        "tests/fixtures/urdf/kinova.urdf",
        "examples/heavy_top.lsd",
        "examples/free_body.lsd",
        "examples/satellite_numeric.lsd",
        "examples/robot_cell.lsd",
        "examples/geared_arm.lsd",
    ];
    for file in files {
        let model = prepared_file(file).model;
        let mut data = Data::new(&model);
        for seed in 0..3 {
            // Quaternions of spherical and free joints are normalised where they are read.
            let q: Vec<f64> = (0..model.nq)
                .map(|i| ((i * 7 + seed * 13 + 1) as f64 * 0.37).sin())
                .collect();
            // The same Data for every state: what one call leaves must not leak into the next.
            let mass = crba(&model, &mut data, &q).expect("crba");
            let columns = rnea_columns(&model, &q);
            let difference = (&mass - &columns).amax() / columns.amax();
            assert!(
                difference <= 1e-12,
                "{file} at seed {seed}: CRBA − RNEA columns {difference:e}\n{mass}{columns}"
            );
        }
    }
}
