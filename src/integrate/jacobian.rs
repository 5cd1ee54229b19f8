//! The Jacobian ∂f/∂y along the state's leading components, for the implicit methods: the
//! system's own when it gives one ([`OdeSystem::jacobian`](super::OdeSystem::jacobian)),
//! forward differences of f otherwise.

use nalgebra::DMatrix;

use super::evaluator::{Evaluator, Halt};

/// The first `count` columns of ∂f/∂y at (t, y), where `derivative` = f(t, y); `scratch` (of
/// the state's length) receives the perturbed right-hand sides.
pub(super) fn leading_columns(
    eval: &mut Evaluator,
    t: f64,
    y: &[f64],
    derivative: &[f64],
    count: usize,
    scratch: &mut [f64],
) -> Result<DMatrix<f64>, Halt> {
    let n = y.len();
    let mut full = DMatrix::zeros(n, n);
    if eval.jacobian(t, y, derivative, &mut full)? {
        return Ok(full.columns(0, count).into_owned());
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
