//! The dense solves in reusable storage (`dynamics::dense`): Gaussian elimination against a
//! known solution, with and without a needed row exchange, and the Cholesky factor against
//! nalgebra's.

use lsdc::dynamics::dense::{solve_in_place, Factor};
use nalgebra::{DMatrix, DVector};

#[test]
fn elimination_solves_a_system_that_needs_pivoting() {
    // A zero in the first pivot: without row exchanges the elimination would divide by it.
    let a = DMatrix::from_row_slice(3, 3, &[0.0, 2.0, 1.0, 1.0, 1.0, 0.0, 3.0, 0.0, 4.0]);
    let x = DVector::from_vec(vec![1.0, -2.0, 0.5]);
    let mut b = &a * &x;
    let mut work = a.clone();
    solve_in_place(&mut work, &mut b).unwrap();
    assert!((b - x).norm() < 1e-14);
    let singular = DMatrix::from_row_slice(2, 2, &[1.0, 2.0, 2.0, 4.0]);
    let mut b = DVector::from_vec(vec![1.0, 1.0]);
    assert_eq!(solve_in_place(&mut singular.clone(), &mut b), Err(1));
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
