//! Jacobians by central differences refined by Richardson extrapolation, with an estimate of
//! their error, for the derivatives the model does not give exactly.
//!
//! Each column j is the central difference D(h) = (f(x + h eⱼ) − f(x − h eⱼ)) / 2h at the steps
//! h, h/2, h/4, h/8, whose error is a series in h², extrapolated in Neville's tableau
//! T(i, k) = (4ᵏ T(i, k−1) − T(i−1, k−1)) / (4ᵏ − 1): T(3, 3) is exact to O(h⁸). Its truncation
//! error is estimated as in Ridders' method (C. J. F. Ridders, "Accurate computation of F′(x)
//! and F′(x) F″(x)", Adv. Eng. Software 4(2), 1982; Numerical Recipes, 3rd ed., §5.7) by the
//! larger of its distances to the extrapolation of one order less (T(3, 2)) and to the best
//! one of the steps before (T(2, 2)). Rounding is not seen by those distances where f is near
//! zero while the terms it sums are not (at an equilibrium); it is bounded apart, assuming
//! each value of f is computed to `ROUNDING` ε max(1, |f|): a central difference at the
//! smallest step h/8 divides that by h/8.

use nalgebra::DMatrix;

/// The first step along a coordinate, relative to max(1, |xⱼ|): O(h⁸) truncation is then near
/// 1e-16 of the derivative's scale, and the smallest step (h/8) multiplies the rounding of f
/// by 800. Measured on the pendulum and the four-bar against their closed forms: errors of
/// 3e-13 and 2e-12 (with 1e-3 and three steps, 2e-12 and 2e-13; with 1e-2 and three steps,
/// 1e-13 and 2e-13, but truncation estimates of 2e-10 and 2e-7).
pub const RELATIVE_STEP: f64 = 1e-2;

/// How many ε of max(1, |f|) each value of f is assumed to be off by, for the rounding bound.
pub const ROUNDING: f64 = 16.0;

/// Steps halved this many times after the first.
const HALVINGS: usize = 3;

/// A Jacobian and, entry by entry, the estimate of its error.
#[derive(Clone, Debug)]
pub struct Estimated {
    pub value: DMatrix<f64>,
    pub error: DMatrix<f64>,
}

/// ∂f/∂x at `x` for the coordinates `columns` of x (one column each, in that order), f giving
/// `rows` values.
pub fn jacobian<E>(
    x: &[f64],
    columns: &[usize],
    rows: usize,
    mut f: impl FnMut(&[f64]) -> Result<Vec<f64>, E>,
) -> Result<Estimated, E> {
    let mut value = DMatrix::zeros(rows, columns.len());
    let mut error = DMatrix::zeros(rows, columns.len());
    let mut moved = x.to_vec();
    for (c, &j) in columns.iter().enumerate() {
        let first = RELATIVE_STEP * x[j].abs().max(1.0);
        let mut magnitudes = vec![0.0_f64; rows];
        // tableau[i][k] for one row of f at a time would repeat the evaluations: keep every
        // difference, one vector per step.
        let mut differences: Vec<Vec<f64>> = Vec::with_capacity(HALVINGS + 1);
        for level in 0..=HALVINGS {
            let h = first / f64::powi(2.0, level as i32);
            moved[j] = x[j] + h;
            let ahead = f(&moved)?;
            moved[j] = x[j] - h;
            let behind = f(&moved)?;
            for (m, (a, b)) in magnitudes.iter_mut().zip(ahead.iter().zip(&behind)) {
                *m = m.max(a.abs()).max(b.abs());
            }
            moved[j] = x[j];
            // The steps actually represented, so that rounding of x ± h does not bias the
            // quotient.
            let span = (x[j] + h) - (x[j] - h);
            differences.push(
                ahead
                    .iter()
                    .zip(&behind)
                    .map(|(a, b)| (a - b) / span)
                    .collect(),
            );
        }
        let smallest = first / f64::powi(2.0, HALVINGS as i32);
        for r in 0..rows {
            let column: Vec<f64> = differences.iter().map(|d| d[r]).collect();
            let (best, truncation) = extrapolate(&column);
            let size = magnitudes[r].max(1.0);
            value[(r, c)] = best;
            error[(r, c)] = truncation + ROUNDING * f64::EPSILON * size / smallest;
        }
    }
    Ok(Estimated { value, error })
}

/// Richardson's extrapolation of central differences at steps halved one after the other (an
/// error series in h²): the best value and the estimate of its error (see the module's note).
fn extrapolate(differences: &[f64]) -> (f64, f64) {
    let mut tableau: Vec<Vec<f64>> = Vec::with_capacity(differences.len());
    for (i, &d) in differences.iter().enumerate() {
        let mut row = vec![d];
        for k in 1..=i {
            let factor = f64::powi(4.0, k as i32);
            let refined = (factor * row[k - 1] - tableau[i - 1][k - 1]) / (factor - 1.0);
            row.push(refined);
        }
        tableau.push(row);
    }
    let last = tableau.len() - 1;
    if last == 0 {
        return (tableau[0][0], f64::INFINITY);
    }
    let best = tableau[last][last];
    let estimate = (best - tableau[last][last - 1])
        .abs()
        .max((best - tableau[last - 1][last - 1]).abs());
    (best, estimate)
}
