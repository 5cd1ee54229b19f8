//! Singular value decompositions sorted largest first, and what the models read from them:
//! the k-th value, the weakest motion, the pseudo-inverse and the condition number.

use nalgebra::{DMatrix, DVector};

use crate::dynamics::loops;

/// Relative size of a singular value counted as zero (the idle motions set aside, the
/// pseudo-inverses, the condition numbers).
pub(super) const RANK_TOLERANCE: f64 = 1e-9;

/// Singular values (largest first) and right singular vectors (columns, same order).
pub(crate) struct Singular {
    pub values: Vec<f64>,
    pub right: DMatrix<f64>,
    pub left: DMatrix<f64>,
}

pub(crate) fn singular(m: &DMatrix<f64>) -> Singular {
    let (rows, columns) = m.shape();
    let mut values = Vec::new();
    let (mut left, mut right) = (DMatrix::zeros(rows, 0), DMatrix::zeros(columns, 0));
    if rows > 0 && columns > 0 {
        if let Some(svd) = crate::linalg::svd(m.clone(), true, true) {
            let (u, v_t) = (svd.u.expect("asked for"), svd.v_t.expect("asked for"));
            let mut order: Vec<usize> = (0..svd.singular_values.len()).collect();
            order.sort_by(|&a, &b| svd.singular_values[b].total_cmp(&svd.singular_values[a]));
            values = order.iter().map(|&k| svd.singular_values[k]).collect();
            right = DMatrix::from_fn(columns, order.len(), |r, c| v_t[(order[c], r)]);
            left = DMatrix::from_fn(rows, order.len(), |r, c| u[(r, order[c])]);
        } else {
            values = vec![f64::NAN; rows.min(columns)];
        }
    }
    Singular {
        values,
        right,
        left,
    }
}

/// The k-th singular value (largest first; 0 when there are fewer than k, 1 for k = 0: a
/// mechanism without motions is singular in no way).
pub(crate) fn kth(values: &[f64], k: usize) -> f64 {
    match k {
        0 => 1.0,
        _ => values.get(k - 1).copied().unwrap_or(0.0),
    }
}

/// The right singular vector of `m`'s `motions`-th singular value, or, when `m` has fewer
/// singular values (fewer rows than motions), a vector of its null space.
pub(super) fn weakest(m: &DMatrix<f64>, svd: &Singular, motions: usize) -> DVector<f64> {
    let k = motions.saturating_sub(1);
    if k < svd.values.len() {
        return svd.right.column(k).into_owned();
    }
    loops::decompose(m).null_space.column(0).into_owned()
}

/// The pseudo-inverse from the decomposition, singular values below the rank tolerance dropped.
pub(super) fn pseudo_inverse(m: &DMatrix<f64>, svd: &Singular) -> DMatrix<f64> {
    let mut inverse = DMatrix::zeros(m.ncols(), m.nrows());
    let largest = svd.values.first().copied().unwrap_or(0.0);
    for (k, &s) in svd.values.iter().enumerate() {
        if s > RANK_TOLERANCE * largest && s > 0.0 {
            inverse += svd.right.column(k) * svd.left.column(k).transpose() / s;
        }
    }
    inverse
}

/// σ_max/σ_min over the smaller dimension; `None` when infinite.
pub(super) fn condition(m: &DMatrix<f64>) -> Option<f64> {
    let svd = singular(m);
    let smallest = svd.values.get(m.nrows().min(m.ncols()).checked_sub(1)?)?;
    let value = svd.values[0] / smallest;
    (value.is_finite() && *smallest > RANK_TOLERANCE * svd.values[0]).then_some(value)
}
