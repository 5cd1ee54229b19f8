//! The Jacobian ∂f/∂y along the state's leading components, for the implicit methods: the
//! system's own when it gives one ([`OdeSystem::jacobian`](super::OdeSystem::jacobian)),
//! forward differences of f otherwise; an orthonormal basis of the directions a system moves
//! along.

use nalgebra::{DMatrix, DVector};

use super::evaluator::{Evaluator, Halt};

/// The first `count` columns of ∂f/∂y at (t, y), where `derivative` = f(t, y), `evaluated`
/// saying whether it was evaluated there or carried over from an earlier step (Radau IIA's
/// `end_slope`): close enough for the system's own Jacobian, which reads it as the point to
/// differentiate at, but not for differences of f, whose quotients would magnify its error
/// by 1/δ, so it is evaluated first (and `evaluated` set). `scratch` (of the state's length)
/// receives the perturbed right-hand sides.
pub(super) fn leading_columns(
    eval: &mut Evaluator,
    t: f64,
    y: &[f64],
    (derivative, evaluated): (&mut [f64], &mut bool),
    count: usize,
    scratch: &mut [f64],
) -> Result<DMatrix<f64>, Halt> {
    let n = y.len();
    let mut full = DMatrix::zeros(n, n);
    if eval.jacobian(t, y, derivative, &mut full)? {
        return Ok(full.columns(0, count).into_owned());
    }
    if !*evaluated {
        eval.rhs(t, y, derivative)?;
        *evaluated = true;
    }
    // Increments that balance truncation against rounding (as in Hairer and Wanner's RODAS).
    let mut image = DMatrix::zeros(n, count);
    let mut perturbed = y.to_vec();
    for j in 0..count {
        perturbed[j] = y[j] + (f64::EPSILON * y[j].abs().max(1e-5)).sqrt();
        // The increment actually represented, so that rounding of y + δ does not bias the
        // quotient.
        let delta = perturbed[j] - y[j];
        eval.rhs(t, &perturbed, scratch)?;
        for i in 0..n {
            image[(i, j)] = (scratch[i] - derivative[i]) / delta;
        }
        perturbed[j] = y[j];
    }
    Ok(image)
}

/// An orthonormal basis of the span of `spanning`'s columns, padded with zero rows to `rows`
/// (the components past the system's own, such as a quadrature carried along).
pub(super) fn orthonormal(spanning: DMatrix<f64>, rows: usize) -> DMatrix<f64> {
    let mut padded = DMatrix::zeros(rows, spanning.ncols());
    let height = spanning.nrows().min(rows);
    padded
        .rows_mut(0, height)
        .copy_from(&spanning.rows(0, height));
    if padded.ncols() == 0 {
        return padded;
    }
    // Modified Gram–Schmidt, dropping the columns the others already span.
    let mut kept: Vec<DVector<f64>> = Vec::new();
    let largest = padded
        .column_iter()
        .map(|c| c.norm())
        .fold(0.0, f64::max)
        .max(f64::MIN_POSITIVE);
    for column in padded.column_iter() {
        let mut v = column.into_owned();
        for u in &kept {
            let along = u.dot(&v);
            v.axpy(-along, u, 1.0);
        }
        let norm = v.norm();
        if norm > 1e-10 * largest {
            kept.push(v / norm);
        }
    }
    DMatrix::from_columns(&kept).resize(rows, kept.len(), 0.0)
}
