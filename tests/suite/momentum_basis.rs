//! The orthonormal basis of the allowed motions that the outputs' momentum projection takes from
//! the loops' sparse factorisation (`orthonormal_allowed_motions`), against an independent one:
//! a dense QR factorisation of the same rows (`Factored::dense_null_space`), near the flat
//! (singular) configuration of a row of two parallelogram four-bars; and the momentum projection
//! that uses it, against the same projection computed from scratch.

use nalgebra::{DMatrix, DVector};

use crate::common::programs::prepared;
use lsdc::dynamics::algorithms::{crba, forward_kinematics, Data};
use lsdc::dynamics::loops::orthonormal::orthonormal_allowed_motions;
use lsdc::dynamics::loops::{
    constraints, decompose, project_from, project_momentum, Extent, Factored, MomentumBasis,
    ProjectionScratch, Structure, DAMPING,
};

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

/// The velocities of the momentum projection (`project_momentum`), which works on the rows and
/// factorisation the position projection ended with, against the same projection computed
/// independently at the projected positions: the rows evaluated afresh, a singular value
/// decomposition of all of them for the allowed motions N, the mass matrix M by CRBA, and
/// v' = N(NᵀMN)⁻¹NᵀMv. The state starts off the loops, so the projection moves it; well
/// conditioned (1.2 rad from flat) and near the loops, its later steps keep the factor of its
/// first (a chord method), whose rows are then no longer the final ones.
#[test]
fn the_momentum_projection_uses_the_rows_where_the_positions_ended() {
    let prepared = prepared("hard/four_bar_row_2", &[]);
    let model = &prepared.model;
    let mut data = Data::new(model);
    let start = (model)
        .state_from_declared(&prepared.coordinates, &prepared.rates)
        .expect("state");
    let structure = Structure::decide(model, &mut data, &start.0).expect("structure");
    for (angle, off) in [(1.2, 1e-7), (1.2, 1e-3), (1e-3, 1e-9)] {
        let coordinates: Vec<f64> = (prepared.coordinate_names.iter())
            .map(|name| match name.chars().next() {
                Some('p') => -angle,
                _ => angle,
            })
            .collect();
        let (mut q, mut v) = (model)
            .state_from_declared(&coordinates, &prepared.rates)
            .expect("state");
        // Off the loops in positions and velocities, by different amounts per coordinate.
        for (k, (x, y)) in q.iter_mut().zip(v.iter_mut()).enumerate() {
            *x += off * (1.0 + k as f64).sin();
            *y += 0.5 * (2.0 + k as f64).cos();
        }
        let mut scratch = ProjectionScratch::new(model);
        forward_kinematics(model, &mut data, &q, &v).expect("kinematics");
        scratch
            .constraints_at(model, &mut data, &q, &v)
            .expect("constraints");
        // As a run's monitor does before projecting (its factor may serve the projection).
        let conditioning = scratch.conditioning(&structure.choice).0;
        let arriving = v.clone();
        project_from(
            model,
            &mut data,
            &structure.choice,
            &mut q,
            &mut v,
            &mut scratch,
        )
        .expect("projects");
        v.copy_from_slice(&arriving);
        let basis = MomentumBasis::Orthonormal;
        project_momentum(
            model,
            &mut data,
            &structure,
            (&q, &mut v),
            basis,
            &mut scratch,
        )
        .expect("momentum");

        let rest = vec![0.0; v.len()];
        let c = constraints(model, &mut data, &q, &rest, Extent::Rows).expect("constraints");
        let allowed = decompose(&c.jacobian.dense()).null_space;
        // The loops' own coordinates (after the tree's) carry no mass.
        let mass = crba(model, &mut data, &q).expect("mass");
        let tree = allowed.rows(0, model.nv);
        let momentum = &mass * DVector::from_column_slice(&arriving[..model.nv]);
        let reduced = tree.transpose() * &mass * tree;
        let expected =
            &allowed * (reduced.cholesky().expect("massive")).solve(&(tree.transpose() * momentum));
        let gap = (DVector::from_column_slice(&v) - &expected).amax() / expected.amax();
        eprintln!(
            "angle {angle:e} (conditioning {conditioning:.1e}), off by {off:e}: \
             relative gap {gap:.1e}"
        );
        assert!(gap < 1e-12, "at {angle}, off by {off}: {gap:e}");
    }
}
