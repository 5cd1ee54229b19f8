//! The minimum-norm solutions on a matrix's independent rows (`linalg::MinimumNormRows`) and
//! from the pseudo-inverse of the singular value decomposition (`linalg::svd`), each against
//! the solution on the rows known independent by construction from nalgebra's QR
//! decomposition, on wide matrices with rows that are combinations of others (as the loops'
//! redundant rows are), and on the rows found independent kept for a nearby matrix; the
//! decomposition on the matrices where nalgebra's own is wrong (its issue #1172), against
//! closed forms.

use lsdc::linalg::{jacobi_svd, pseudo_inverse, svd, MinimumNormRows};
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
        // The minimum-norm solution on the first rows, independent by construction: Q R⁻ᵀ b₁
        // from the QR decomposition of their transpose.
        let independent = p - dependent;
        let qr = a.rows(0, independent).transpose().qr();
        let on_first = qr.r().transpose().solve_lower_triangular(&b.rows(0, independent).into_owned());
        let expected = qr.q() * on_first.expect("independent rows");
        let scale = 1.0 + expected.amax();
        prop_assert!((&solution - &expected).amax() < 1e-11 * scale);
        let decomposed = pseudo_inverse(a.clone(), 1e-9 * a.norm()).expect("finite") * &b;
        prop_assert!((&decomposed - &expected).amax() < 1e-11 * scale);
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

/// A p × q matrix of ones is 1_p 1_qᵀ: one singular value √(pq), the others zero. nalgebra's
/// own decomposition returns 4.54 for the 3 × 5 one's √15 (its issue #1172).
#[test]
fn matrices_of_ones_have_their_one_singular_value() {
    for (p, q) in [(3, 5), (5, 3), (6, 21), (4, 4), (1, 7)] {
        let ones = DMatrix::from_element(p, q, 1.0);
        for decomposition in [
            svd(ones.clone(), true, true).expect("finite"),
            jacobi_svd(&ones),
        ] {
            let values = &decomposition.singular_values;
            let exact = ((p * q) as f64).sqrt();
            assert!(
                (values[0] - exact).abs() < 1e-14 * exact,
                "{p} x {q}: {values}"
            );
            assert!(
                values.iter().skip(1).all(|s| s.abs() < 1e-14 * exact),
                "{p} x {q}"
            );
            let (u, v_t) = (decomposition.u.unwrap(), decomposition.v_t.unwrap());
            let k = p.min(q);
            assert!((u.transpose() * &u - DMatrix::identity(k, k)).amax() < 1e-14);
            assert!((&v_t * v_t.transpose() - DMatrix::identity(k, k)).amax() < 1e-14);
            let rebuilt = u.column(0) * v_t.row(0) * values[0];
            assert!((rebuilt - &ones).amax() < 1e-14 * exact, "{p} x {q}");
        }
    }
}

/// One-sided Jacobi against a matrix built from its factors: U Σ Vᵀ with U, V from Givens
/// rotations and Σ spanning 12 decades, rank-deficient too.
#[test]
fn jacobi_rotations_find_the_singular_values_of_a_built_matrix() {
    let rotation = |n: usize, seed: f64| {
        let mut r = DMatrix::<f64>::identity(n, n);
        for i in 0..n {
            for j in i + 1..n {
                let angle = seed * (1.0 + i as f64) + 0.37 * j as f64;
                let (c, s) = (angle.cos(), angle.sin());
                for k in 0..n {
                    let (x, y) = (r[(k, i)], r[(k, j)]);
                    r[(k, i)] = c * x - s * y;
                    r[(k, j)] = s * x + c * y;
                }
            }
        }
        r
    };
    let (p, q) = (5, 8);
    for values in [[1e3, 10.0, 1.0, 1e-3, 1e-9], [4.0, 3.0, 2.0, 0.0, 0.0]] {
        let mut sigma = DMatrix::zeros(p, q);
        for (k, &s) in values.iter().enumerate() {
            sigma[(k, k)] = s;
        }
        let m = rotation(p, 0.3) * sigma * rotation(q, 0.7).transpose();
        for decomposition in [jacobi_svd(&m), svd(m.clone(), true, true).expect("finite")] {
            for (k, &s) in values.iter().enumerate() {
                let found = decomposition.singular_values[k];
                assert!(
                    (found - s).abs() < 1e-13 * values[0],
                    "{k}: {found} against {s}"
                );
            }
            let rebuilt = decomposition.recompose().expect("vectors");
            assert!((rebuilt - &m).amax() < 1e-13 * values[0]);
        }
    }
}
