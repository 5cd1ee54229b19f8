//! An orthonormal basis of the motions the kept rows allow, by the loops' sparse factorisation
//! (`Factored`) instead of a dense QR factorisation of the rows: for `project_momentum` near a
//! singular configuration, where the outputs' velocities need a basis exact to round-off.
//!
//! The free coordinates' allowed motions (`Damped::allowed_motions_into`) solve on the normal
//! matrix A = GₛGₛᵀ: the part of each motion left across the rows is ε/σ² of it at a
//! conditioning σ. Each motion is corrected by the same projection applied to that part
//! (iterative refinement on the semi-normal equations, Björck, *Numerical Methods for Least
//! Squares Problems*, SIAM 1996, §2.3.3; corrected semi-normal equations, §6.6.5): each pass
//! multiplies what is left by about ε/σ², down to the round-off of evaluating Gₛx, about ε/σ
//! of the motion, the accuracy of the dense QR basis. The corrected motions are then made
//! orthonormal by a thin QR factorisation of n × (n − r), so the reduced mass matrix NᵀMN is
//! as well conditioned as M. The cost is a few sparse solves per allowed motion and
//! O(n (n − r)²), against O(n³) for the dense basis (a row of 100 four-bars, n = 301, r = 300:
//! 539 M instructions for the dense basis).

use nalgebra::DMatrix;

use super::factored::{Damped, Factored};

/// Corrections applied to the allowed motions: the first takes what the solves left across the
/// rows (ε/σ²) to (ε/σ²)², below round-off down to σ = 1e-5, where the outputs stop projecting;
/// the second is for the damping's share on the firm rows (μ²/σ², μ = `DAMPING`).
const CORRECTIONS: usize = 2;

/// An orthonormal basis (columns, of G's columns) of the motions the rows of `factored` allow,
/// from the allowed motions of the free coordinates `free`, which must parametrise them
/// (`Structure` chooses them so): one column per free coordinate.
pub fn orthonormal_allowed_motions(
    factored: &Factored,
    damped: &Damped<'_>,
    free: &[usize],
) -> DMatrix<f64> {
    let mut basis = DMatrix::zeros(factored.columns(), free.len());
    if free.is_empty() {
        return basis;
    }
    let mut rows = Vec::new();
    damped.allowed_motions_into(free, &mut rows, &mut basis, 0);
    let mut across = vec![0.0; factored.columns()];
    for mut motion in basis.column_iter_mut() {
        for _ in 0..CORRECTIONS {
            // x − Gₛᵀ(A + μ²E)⁻¹Gₛx: the motion without what is left of it across the rows.
            damped.allowed_part_into(motion.as_slice(), &mut rows, &mut across);
            motion.copy_from_slice(&across);
        }
    }
    basis.qr().q()
}
