//! The response of a mechanism with loops to generalised forces: what other constraints on its
//! motion (mimic couplings, joints held by their friction) need to be solved together with the
//! loops' rows.
//!
//! With N the allowed motions of the last solve (`LoopScratch::solved_motions`), the
//! accelerations are a = a₀ + N z with (NᵀMN) z = Nᵀ(f − Ma₀), and a₀ does not depend on f:
//! a generalised force F changes them by P F with P = N (NᵀMN)⁻¹ Nᵀ. P F keeps the loops' rows
//! (G P = 0), so further rows E solved on P (E P Eᵀ λ = −E a, a ← a + P Eᵀ λ) hold together
//! with the loops', and a step of the state along P Eᵀ moves along the loops to first order.

use nalgebra::{DMatrix, DMatrixView};

/// P F = N (NᵀMN)⁻¹ Nᵀ F for the allowed motions `motions` (over the state's velocities, the
/// tree's first) and the tree's mass matrix `mass` (the complementary coordinates carry no
/// inertia). `None` where NᵀMN is not positive definite (an allowed motion without mass).
pub fn constrained_response(
    mass: &DMatrix<f64>,
    motions: DMatrixView<'_, f64>,
    forces: &DMatrix<f64>,
) -> Option<DMatrix<f64>> {
    let tree = motions.rows(0, mass.nrows());
    let reduced = tree.transpose() * mass * tree;
    let cholesky = reduced.cholesky()?;
    Some(motions * cholesky.solve(&(motions.transpose() * forces)))
}
