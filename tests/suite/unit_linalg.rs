//! The minimum-norm solutions on a matrix's independent rows (`linalg::MinimumNormRows`)
//! against the pseudo-inverse from the singular value decomposition, on wide matrices with
//! rows that are combinations of others (as the loops' redundant rows are), and on the rows
//! found independent kept for a nearby matrix.

use lsdc::linalg::{pseudo_inverse, MinimumNormRows};
use nalgebra::DMatrix;
use proptest::prelude::*;

/// A p × n matrix whose last `dependent` rows are combinations of the first ones, from seeds.
fn with_dependent_rows(entries: &[f64], p: usize, n: usize, dependent: usize) -> DMatrix<f64> {
    let mut a = DMatrix::from_fn(p, n, |i, j| entries[(i * n + j) % entries.len()]);
    for k in 0..dependent {
        let row = p - 1 - k;
        let combination = a.row(0) * 0.5 - a.row(1 + k % (p - dependent - 1)) * 1.5;
        a.set_row(row, &combination);
    }
    a
}

proptest! {
    #[test]
    fn the_solution_is_the_pseudo_inverses_and_the_rank_that_of_the_rows(
        entries in prop::collection::vec(-1.0..1.0f64, 97),
        dependent in 0usize..3,
        sides in prop::collection::vec(-2.0..2.0f64, 8),
    ) {
        let (p, n) = (8, 11);
        let a = with_dependent_rows(&entries, p, n, dependent);
        // A consistent right-hand side: a times some x.
        let x = DMatrix::from_fn(n, 2, |i, j| sides[(i + 3 * j) % sides.len()]);
        let b = &a * &x;
        let factors = MinimumNormRows::new(&a, 1e-9).expect("finite");
        prop_assert_eq!(factors.rank(), p - dependent);
        let solution = factors.solve(&b);
        let expected = pseudo_inverse(a.clone(), 1e-9 * a.norm()).expect("finite") * &b;
        let scale = 1.0 + expected.amax();
        prop_assert!((&solution - &expected).amax() < 1e-11 * scale);
        prop_assert!((&a * &solution - &b).amax() < 1e-12 * (1.0 + b.amax()));
        // The rows found independent, kept for a nearby matrix (a's combinations kept): its
        // solution without pivoting is its own pivoted one.
        let nearby = with_dependent_rows(&entries.iter().map(|e| e * 1.001).collect::<Vec<_>>(), p, n, dependent);
        let b = &nearby * &x;
        let kept = MinimumNormRows::on_rows(&nearby, factors.independent_rows(), 1e-9)
            .expect("the same rows are independent");
        let pivoted = MinimumNormRows::new(&nearby, 1e-9).expect("finite");
        let scale = 1.0 + b.amax();
        prop_assert!((kept.solve(&b) - pivoted.solve(&b)).amax() < 1e-11 * scale);
    }
}

#[test]
fn rows_that_are_no_longer_independent_are_refused() {
    let a = DMatrix::from_row_slice(2, 3, &[1.0, 0.0, 0.0, 1.0, 1.0, 0.0]);
    assert!(MinimumNormRows::on_rows(&a, &[0, 1], 1e-9).is_some());
    let collapsed = DMatrix::from_row_slice(2, 3, &[1.0, 0.0, 0.0, 2.0, 0.0, 0.0]);
    assert!(MinimumNormRows::on_rows(&collapsed, &[0, 1], 1e-9).is_none());
}

#[test]
fn a_matrix_with_an_entry_not_finite_has_no_factorisation() {
    let mut a = DMatrix::from_element(2, 3, 1.0);
    a[(1, 2)] = f64::NAN;
    assert!(MinimumNormRows::new(&a, 1e-9).is_none());
}

#[test]
fn a_zero_matrix_has_rank_zero_and_the_zero_solution() {
    let a = DMatrix::zeros(3, 4);
    let factors = MinimumNormRows::new(&a, 1e-9).expect("finite");
    assert_eq!(factors.rank(), 0);
    assert_eq!(factors.solve(&DMatrix::zeros(3, 1)), DMatrix::zeros(4, 1));
}
