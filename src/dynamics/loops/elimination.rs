//! The sparse elimination (`crate::elimination`) on the loops' constraint Jacobian G: its rows
//! as sparse rows, and the closure's minimum-norm steps.

use nalgebra::DVector;

use super::basis::SOLVE_TOLERANCE;
use super::jacobian::ConstraintJacobian;
use crate::elimination::{pivoted, Sparse};

/// G's rows as sparse rows, each entry multiplied by `scale(row, column)`; exact zeros left out.
pub fn sparse_rows(
    jacobian: &ConstraintJacobian,
    scale: impl Fn(usize, usize) -> f64,
) -> Vec<Sparse> {
    (0..jacobian.nrows())
        .map(|r| {
            (jacobian.row(r))
                .filter(|&(_, value)| value != 0.0)
                .map(|(c, value)| (c, value * scale(r, c)))
                .collect()
        })
        .collect()
}

/// The minimum-norm correction δ of the residual r of every row of G (G δ = −r on the rows
/// independent at `SOLVE_TOLERANCE`, picked by pivoted Gram–Schmidt): the step of the closure's
/// Gauss–Newton iteration, as the pseudo-inverse of a singular value decomposition gives it
/// when the rows left out are implied by the others.
pub fn minimum_norm_step(jacobian: &ConstraintJacobian, residual: &DVector<f64>) -> DVector<f64> {
    let rows = sparse_rows(jacobian, |_, _| 1.0);
    let every: Vec<usize> = (0..jacobian.nrows()).collect();
    let elimination = pivoted(rows, jacobian.ncols(), &every, SOLVE_TOLERANCE);
    elimination.minimum_norm_correction(elimination.picked().len(), residual.as_slice())
}
