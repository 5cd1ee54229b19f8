//! The sparse orthogonal elimination of rows (`src/elimination.rs`) against a singular value
//! decomposition of the same dense matrix: the rank it picks, an orthonormal basis of the same
//! null space, and the same minimum-norm solution of a consistent system, on a matrix with a
//! dependent row and on the rows of a ladder of 40 loops; a vector's part orthogonal to the
//! rows, and the search taken in blocks of rows (as for chains beyond a hundred loops).

use lsdc::dynamics::loops::{decompose, elimination::sparse_rows};
use lsdc::elimination::{pivoted, pivoted_in_blocks, Sparse};
use nalgebra::{DMatrix, DVector};

use crate::common::programs::prepared_text;
use crate::long_chains::chains;

fn rows_of(m: &DMatrix<f64>) -> Vec<Sparse> {
    (0..m.nrows())
        .map(|r| {
            (0..m.ncols())
                .filter(|&c| m[(r, c)] != 0.0)
                .map(|c| (c, m[(r, c)]))
                .collect()
        })
        .collect()
}

/// The elimination of `rows` agrees with the SVD of `dense`.
fn agrees_with_the_svd(dense: &DMatrix<f64>, rows: Vec<Sparse>) {
    let every: Vec<usize> = (0..dense.nrows()).collect();
    let elimination = pivoted(rows.clone(), dense.ncols(), &every, 1e-9);
    let svd = decompose(dense);
    let picked = elimination.picked().len();
    assert_eq!(picked, svd.rank, "rank");
    let null = elimination.null_space(picked);
    assert_eq!(
        null.ncols(),
        svd.null_space.ncols(),
        "null space's dimension"
    );
    let scale = dense.amax();
    assert!(
        (dense * &null).amax() <= 1e-13 * scale,
        "G Z = {:e}",
        (dense * &null).amax()
    );
    let gram = null.transpose() * &null - DMatrix::identity(null.ncols(), null.ncols());
    assert!(gram.amax() <= 1e-13, "ZᵀZ − I = {:e}", gram.amax());
    // A vector's part orthogonal to the rows: its projection onto the SVD's null space.
    let y = DVector::from_fn(dense.ncols(), |i, _| (0.91 * i as f64 + 0.3).cos());
    let mut part = y.clone();
    elimination.orthogonal_part(picked, part.as_mut_slice());
    let projected = &svd.null_space * (svd.null_space.transpose() * &y);
    let error = (&part - &projected).amax();
    assert!(error <= 1e-13, "orthogonal part error {error:e}");
    // Taken in blocks of 5 rows (each block to its end), the same rank and the same null
    // space (its projector).
    let blocks = pivoted_in_blocks(rows.clone(), dense.ncols(), &every, 1e-9, 5);
    assert_eq!(blocks.picked().len(), svd.rank, "rank in blocks");
    let by_blocks = blocks.null_space(blocks.picked().len());
    let projector = |z: &DMatrix<f64>| z * z.transpose();
    let error = (projector(&by_blocks) - projector(&svd.null_space)).amax();
    assert!(
        error <= 1e-12,
        "null space in blocks: projectors differ by {error:e}"
    );
    // A consistent right-hand side: the minimum-norm solutions agree.
    let x = DVector::from_fn(dense.ncols(), |i, _| (0.37 * i as f64 + 0.1).sin());
    let b = dense * x;
    let expected = -(&svd.pseudo_inverse * &b);
    let found = elimination.minimum_norm_correction(picked, b.as_slice());
    let error = (&found - &expected).amax();
    assert!(
        error <= 1e-12 * expected.amax().max(1.0),
        "step error {error:e}"
    );
}

#[test]
fn a_matrix_with_a_dependent_row_is_eliminated_as_its_svd_decomposes_it() {
    let mut g = DMatrix::from_fn(9, 7, |i, j| {
        let value = ((i * 7 + j * 13) % 11) as f64 - 5.0;
        if (i + j) % 3 == 0 {
            0.0
        } else {
            value
        }
    });
    let dependent = g.row(0) + g.row(1) * 2.0;
    g.row_mut(3).copy_from(&dependent);
    agrees_with_the_svd(&g, rows_of(&g));
}

#[test]
fn a_ladders_rows_are_eliminated_as_their_svd_decomposes_them() {
    let prepared = prepared_text(&chains::ladder_program(40));
    let model = &prepared.model;
    let (q, v) = model
        .state_from_declared(&prepared.coordinates, &prepared.rates)
        .expect("a state");
    let mut data = lsdc::dynamics::algorithms::Data::new(model);
    let c = lsdc::dynamics::loops::constraints(
        model,
        &mut data,
        &q,
        &v,
        lsdc::dynamics::loops::Extent::Rows,
    )
    .expect("constraints");
    agrees_with_the_svd(&c.jacobian.dense(), sparse_rows(&c.jacobian, |_, _| 1.0));
}
