//! A singular value decomposition of the constraint Jacobian, for the decisions taken once
//! (closing the initial state, completing its rates, holding a configuration statically): it
//! gives the rank, a pseudo-inverse and an orthonormal basis of the allowed motions whatever the
//! rank. The equations of motion never use it: they solve on the rows `Structure` selected
//! (`solve`), at the cost of a QR factorisation.

use nalgebra::{DMatrix, DVector};

/// For the decisions on G: singular values at round-off level are dropped, those of rows that
/// act only at second order (about 1e-8 of the largest at a configuration closed to 1e-15, as in
/// maille1 and maille2) are kept, so those rows are still enforced at first order.
pub const SOLVE_TOLERANCE: f64 = 1e-9;

/// A singular value decomposition of G: its rank, the pseudo-inverse and a basis of its null
/// space (the motions the loops allow).
pub struct Decomposition {
    pub rank: usize,
    pub pseudo_inverse: DMatrix<f64>,
    pub null_space: DMatrix<f64>,
    /// Singular values, largest first (read by the tests, which check ranks against them).
    #[cfg_attr(not(lsdc_internals), allow(dead_code))]
    pub singular_values: Vec<f64>,
}

pub fn decompose(g: &DMatrix<f64>) -> Decomposition {
    decompose_with(g, SOLVE_TOLERANCE)
}

/// `decompose` with another relative tolerance for the rank.
pub fn decompose_with(g: &DMatrix<f64>, tolerance: f64) -> Decomposition {
    let (m, n) = g.shape();
    // Pad to at least square so the decomposition returns the whole null space.
    let rows = m.max(n);
    let mut square = DMatrix::zeros(rows, n);
    square.rows_mut(0, m).copy_from(g);
    let Some(svd) = crate::linalg::svd(square, true, true) else {
        return not_finite(m, n);
    };
    let (u, v_t) = (svd.u.expect("asked for"), svd.v_t.expect("asked for"));
    let mut order: Vec<usize> = (0..svd.singular_values.len()).collect();
    order.sort_by(|&a, &b| svd.singular_values[b].total_cmp(&svd.singular_values[a]));
    let singular_values: Vec<f64> = order.iter().map(|&k| svd.singular_values[k]).collect();
    let largest = singular_values.first().copied().unwrap_or(0.0);
    let rank = singular_values
        .iter()
        .take_while(|&&s| s > tolerance * largest && s > 0.0)
        .count();
    let mut pseudo_inverse = DMatrix::zeros(n, m);
    for &k in &order[..rank] {
        pseudo_inverse +=
            v_t.row(k).transpose() * u.column(k).rows(0, m).transpose() / svd.singular_values[k];
    }
    let null: Vec<DVector<f64>> = order[rank..]
        .iter()
        .map(|&k| v_t.row(k).transpose())
        .collect();
    let null_space = if null.is_empty() {
        DMatrix::zeros(n, 0)
    } else {
        DMatrix::from_columns(&null)
    };
    Decomposition {
        rank,
        pseudo_inverse,
        null_space,
        singular_values,
    }
}

/// The decomposition of a G with a non-finite entry: every number NaN, so that whatever uses it
/// fails on a non-finite value rather than deciding on a rank that was never computed.
fn not_finite(m: usize, n: usize) -> Decomposition {
    Decomposition {
        rank: 0,
        pseudo_inverse: DMatrix::from_element(n, m, f64::NAN),
        null_space: DMatrix::from_element(n, n, f64::NAN),
        singular_values: vec![f64::NAN; m.min(n)],
    }
}
