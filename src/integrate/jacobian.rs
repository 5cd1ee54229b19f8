//! The Jacobian ∂f/∂y along the state's leading components, for the implicit methods: the
//! system's own when it gives one ([`OdeSystem::jacobian`](super::OdeSystem::jacobian)),
//! forward differences of f otherwise.

use nalgebra::DMatrix;

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
