//! Which parameters a regression can identify: the base parameters (Khalil & Dombre, Modeling,
//! Identification and Control of Robots, 2002, ch. 12), found numerically from the regressor at
//! random states (Gautier, "Numerical calculation of the base inertial parameters of robots",
//! J. Robotic Systems 8(4), 1991). With W the stacked regressor, its columns scaled to unit
//! norm (parameters of different units), the QR decomposition with column pivoting
//! W P = Q [R₁ R₂] puts the independent columns first: a column whose norm is at most
//! [`RANK_TOLERANCE`] of the largest has no effect at all; past the rank r (the diagonal of R at
//! most [`RANK_TOLERANCE`] of its first entry) the columns are combinations of the first r,
//! with W₂ = W₁ R₁⁻¹ R₂. Then W π = W₁ π_b with the base parameters π_b = π₁ + β π₂ and
//! β = R₁⁻¹ R₂ rescaled to the parameters' units.

use nalgebra::DMatrix;

use crate::linalg::pivoted_qr;

/// The relative size below which a column has no effect, or a pivot is taken as zero. The
/// regressor's exact dependencies leave pivots of round-off size (1e-15 of the first); the
/// independent columns of a mechanism whose scales differ by 1e6 stay far above it.
pub const RANK_TOLERANCE: f64 = 1e-8;

/// Coefficients |β| at most this (relative to the dependent column's scale) are zero.
const COEFFICIENT_TOLERANCE: f64 = 1e-9;

/// The base parameters of the columns of a regressor.
#[derive(Clone, Debug, PartialEq)]
pub struct BaseParameters {
    /// The columns of the base parameters (the independent ones), in pivot order.
    pub independent: Vec<usize>,
    /// Per base parameter, the dependent columns folded into it and their coefficients:
    /// π_b = π_independent + Σ β π_dependent.
    pub combinations: Vec<Vec<(usize, f64)>>,
    /// The columns that are combinations of the independent ones.
    pub dependent: Vec<usize>,
    /// The columns that have no effect on the efforts at all.
    pub without_effect: Vec<usize>,
}

/// The base parameters of the columns of `w` (see the module's documentation).
pub fn base_parameters(w: &DMatrix<f64>) -> BaseParameters {
    let norms: Vec<f64> = w.column_iter().map(|c| c.norm()).collect();
    let largest = norms.iter().copied().fold(0.0, f64::max);
    let (effective, without_effect): (Vec<usize>, Vec<usize>) =
        (0..w.ncols()).partition(|&j| largest > 0.0 && norms[j] > RANK_TOLERANCE * largest);
    let scaled = DMatrix::from_fn(w.nrows(), effective.len(), |i, k| {
        w[(i, effective[k])] / norms[effective[k]]
    });
    let (r, order) = pivoted_qr(&scaled);
    let diagonal = r.nrows().min(r.ncols());
    let first = if diagonal > 0 { r[(0, 0)].abs() } else { 0.0 };
    let rank = (0..diagonal)
        .take_while(|&k| r[(k, k)].abs() > RANK_TOLERANCE * first)
        .count();
    let column = |k: usize| effective[order[k]];
    let independent: Vec<usize> = (0..rank).map(column).collect();
    let dependent: Vec<usize> = (rank..effective.len()).map(column).collect();
    let r1 = r.view((0, 0), (rank, rank)).into_owned();
    let r2 = r.view((0, rank), (rank, dependent.len())).into_owned();
    // R₁ is upper triangular with its diagonal above the tolerance: the solve exists.
    let beta = r1
        .solve_upper_triangular(&r2)
        .unwrap_or_else(|| DMatrix::zeros(rank, dependent.len()));
    let combinations = (0..rank)
        .map(|i| {
            (0..dependent.len())
                .filter(|&j| beta[(i, j)].abs() > COEFFICIENT_TOLERANCE)
                .map(|j| {
                    let (base, folded) = (independent[i], dependent[j]);
                    (folded, beta[(i, j)] * norms[folded] / norms[base])
                })
                .collect()
        })
        .collect();
    BaseParameters {
        independent,
        combinations,
        dependent,
        without_effect,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Columns a, 2a + b, b, 0 and c: one column without effect, one a combination of two.
    #[test]
    fn a_combination_and_a_column_without_effect_are_found() {
        let a = [1.0, 2.0, -1.0, 0.5, 3.0];
        let b = [0.0, 1.0, 4.0, -2.0, 1.0];
        let c = [2.0, -1.0, 0.0, 1.0, 1.0];
        let w = DMatrix::from_fn(5, 5, |i, j| match j {
            0 => a[i],
            1 => 2.0 * a[i] + b[i],
            2 => b[i],
            3 => 0.0,
            _ => c[i],
        });
        let base = base_parameters(&w);
        assert_eq!(base.without_effect, vec![3]);
        assert_eq!(base.independent.len(), 3);
        assert_eq!(base.dependent.len(), 1);
        // W π = W₁ π_b for any π.
        let pi = [0.3, -1.2, 0.7, 5.0, 2.0];
        let folded: Vec<f64> = (base.independent.iter().zip(&base.combinations))
            .map(|(&i, terms)| pi[i] + terms.iter().map(|&(j, beta)| beta * pi[j]).sum::<f64>())
            .collect();
        for row in 0..5 {
            let full: f64 = (0..5).map(|j| w[(row, j)] * pi[j]).sum();
            let base_sum: f64 = (base.independent.iter().zip(&folded))
                .map(|(&j, p)| w[(row, j)] * p)
                .sum();
            assert!(
                (full - base_sum).abs() < 1e-12,
                "row {row}: {full} {base_sum}"
            );
        }
    }
}
