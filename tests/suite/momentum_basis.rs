//! The orthonormal basis of the allowed motions that the outputs' momentum projection takes from
//! the loops' sparse factorisation (`orthonormal_allowed_motions`), against an independent one:
//! a dense QR factorisation of the same rows (`Factored::dense_null_space`), near the flat
//! (singular) configuration of a row of two parallelogram four-bars.

use nalgebra::DMatrix;

use crate::common::programs::prepared;
use lsdc::dynamics::algorithms::Data;
use lsdc::dynamics::loops::orthonormal::orthonormal_allowed_motions;
use lsdc::dynamics::loops::{constraints, Extent, Factored, Structure, DAMPING};

/// The largest entry of the difference of the orthogonal projectors onto the spans of two
/// orthonormal bases: zero when they span the same space, whatever the bases.
fn projector_gap(a: &DMatrix<f64>, b: &DMatrix<f64>) -> f64 {
    (a * a.transpose() - b * b.transpose()).amax()
}

/// The allowed motions' bases of the row of two four-bars turned to `angle` from its flat
/// configuration (cranks and couplers translate: ck = angle, pk = −angle, ek = angle), with the
/// rows and free coordinates chosen at the start (hanging): (sparse and corrected, dense QR,
/// free coordinates' allowed motions alone made orthonormal, conditioning of the kept rows).
fn bases(angle: f64) -> (DMatrix<f64>, DMatrix<f64>, DMatrix<f64>, f64) {
    let prepared = prepared("hard/four_bar_row_2", &[]);
    let model = &prepared.model;
    let mut data = Data::new(model);
    let start = (model)
        .state_from_declared(&prepared.coordinates, &prepared.rates)
        .expect("state");
    let structure = Structure::decide(model, &mut data, &start.0).expect("structure");
    let coordinates: Vec<f64> = (prepared.coordinate_names.iter())
        .map(|name| match name.chars().next() {
            Some('p') => -angle,
            _ => angle,
        })
        .collect();
    let (q, v) = (model)
        .state_from_declared(&coordinates, &prepared.rates)
        .expect("state");
    let c = constraints(model, &mut data, &q, &v, Extent::Rows).expect("constraints");
    let factored = Factored::new(&c.jacobian, &structure.choice);
    let damped = factored.damped(DAMPING).expect("factors");
    let sparse = orthonormal_allowed_motions(&factored, &damped, &structure.free);
    let uncorrected = damped.allowed_motions(&structure.free).qr().q();
    let conditioning = factored.conditioning_of(&Ok(damped)).0;
    let dense = factored.dense_null_space().clone();
    (sparse, dense, uncorrected, conditioning)
}

#[test]
fn the_sparse_orthonormal_basis_spans_the_dense_one_near_a_singular_configuration() {
    for angle in [0.3, 1e-2, 1e-3, 3e-4] {
        let (sparse, dense, uncorrected, conditioning) = bases(angle);
        assert_eq!(sparse.shape(), dense.shape(), "at {angle}");
        let identity = DMatrix::identity(sparse.ncols(), sparse.ncols());
        let orthonormality = (sparse.transpose() * &sparse - identity).amax();
        let gap = projector_gap(&sparse, &dense);
        let uncorrected_gap = projector_gap(&uncorrected, &dense);
        eprintln!(
            "angle {angle:e}: conditioning {conditioning:.2e}, |NᵀN − I| {orthonormality:.1e}, \
             gap {gap:.1e}, uncorrected {uncorrected_gap:.1e}"
        );
        assert!(orthonormality < 1e-14, "at {angle}: {orthonormality:e}");
        assert!(gap < 1e-12, "at {angle}: {gap:e}");
        if conditioning < 1e-4 {
            // Uncorrected, the solves on the normal matrix leave ε/σ² of each motion across the
            // rows (2.3e-10 at 3.2e-5): this test tells the corrections from their absence.
            assert!(uncorrected_gap > 1e-11, "at {angle}: {uncorrected_gap:e}");
        }
    }
}
