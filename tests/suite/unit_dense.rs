//! The dense solves in reusable storage (`dynamics::dense`): Gaussian elimination against a
//! known solution, with and without a needed row exchange, and the Cholesky factor against
//! nalgebra's.

use lsdc::dynamics::dense::{inverse_power_of_two, solve_in_place, Factor, Pivoted};
use nalgebra::{DMatrix, DVector};

#[test]
fn elimination_solves_a_system_that_needs_pivoting() {
    // A zero in the first pivot: without row exchanges the elimination would divide by it.
    let a = DMatrix::from_row_slice(3, 3, &[0.0, 2.0, 1.0, 1.0, 1.0, 0.0, 3.0, 0.0, 4.0]);
    let x = DVector::from_vec(vec![1.0, -2.0, 0.5]);
    let mut b = &a * &x;
    let mut work = a.clone();
    solve_in_place(&mut work, b.as_mut_slice()).unwrap();
    assert!((b - x).norm() < 1e-14);
    let singular = DMatrix::from_row_slice(2, 2, &[1.0, 2.0, 2.0, 4.0]);
    let mut b = DVector::from_vec(vec![1.0, 1.0]);
    assert_eq!(
        solve_in_place(&mut singular.clone(), b.as_mut_slice()),
        Err(1)
    );
}

#[test]
fn the_factor_solves_as_nalgebra_does() {
    let m = DMatrix::from_row_slice(3, 3, &[4.0, 1.0, 0.5, 1.0, 3.0, 0.2, 0.5, 0.2, 2.0]);
    let mut factor = Factor::new(3);
    assert!(factor.factor(&m));
    let mut b = DMatrix::from_row_slice(3, 2, &[1.0, 0.0, 2.0, 1.0, -1.0, 3.0]);
    let expected = m.clone().cholesky().unwrap().solve(&b);
    factor.solve_mut(&mut b);
    assert!((b - expected).norm() < 1e-14);
    assert!(!factor.factor(&-m));
}

/// The scale brings a largest entry into [1, 2) exactly (a power of two), across the range of
/// normal numbers and below it, and leaves zero, infinite and NaN entries' rows alone.
#[test]
fn the_inverse_power_of_two_brings_the_largest_entry_into_one_to_two() {
    for largest in [
        1.0,
        1.5,
        2.0,
        3.0,
        0.3,
        1e-13,
        7e12,
        1e300,
        f64::MIN_POSITIVE,
    ] {
        let scaled = largest * inverse_power_of_two(largest);
        assert!((1.0..2.0).contains(&scaled), "{largest}: {scaled}");
    }
    let subnormal = 1e-320 * inverse_power_of_two(1e-320);
    assert!(subnormal.is_finite() && subnormal > 0.0, "{subnormal}");
    let largest = f64::MAX * inverse_power_of_two(f64::MAX);
    assert!((2.0..4.0).contains(&largest), "{largest}");
    for odd in [0.0, f64::INFINITY, f64::NAN] {
        assert_eq!(inverse_power_of_two(odd), 1.0);
    }
}

/// Rows of entries fifteen orders apart, independent: both solved, where a cutoff relative to
/// the largest entry alone would take the small row as dependent; a row repeated is still found
/// dependent (rank 2 of 3) and the system's solution kept.
#[test]
fn the_pivoted_solve_keeps_small_independent_rows_and_finds_dependent_ones() {
    let mut a = DMatrix::from_row_slice(2, 2, &[1e10, 0.0, 0.0, 1e-3]);
    let mut b = DVector::from_vec(vec![2e10, -3e-3]);
    let rank = Pivoted::default().solve(&mut a, &mut b, 1e-12);
    assert_eq!(rank, 2);
    assert!(
        (b[0] - 2.0).abs() < 1e-15 && (b[1] + 3.0).abs() < 1e-15,
        "{b}"
    );
    let original = DMatrix::from_row_slice(3, 3, &[2.0, 1.0, 0.0, 1.0, 3.0, 1e-6, 2.0, 1.0, 0.0]);
    let rhs = DVector::from_vec(vec![3.0, 4.0, 3.0]);
    let (mut a, mut x) = (original.clone(), rhs.clone());
    let rank = Pivoted::default().solve(&mut a, &mut x, 1e-12);
    assert_eq!(rank, 2);
    let residual = (&original * &x - &rhs).amax();
    assert!(residual < 1e-14, "residual {residual:e}");
}
