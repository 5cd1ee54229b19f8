//! The accelerations' rows of A and B's columns of generalised forces of a mechanism with
//! loops, exact: the derivatives of the constrained dynamics in the chart's independent
//! coordinates (`dynamics::loops::derivatives`: the differentiated saddle point, ∂z̈/∂z,
//! ∂z̈/∂ż and ∂z̈/∂τ), instead of central differences through the chart.
//!
//! Those derivatives hold the generalised forces and the bodies' external forces fixed: they
//! apply where nothing but gravity and the inputs acts (the program declares no effort and no
//! state), and where the constrained equations have unique derivatives (no motion without
//! mass, no row closing only at second order, joints the tree's derivatives cover). Elsewhere
//! the linearisation differences, and says why (`Refusal`).

use nalgebra::DMatrix;

use super::evaluator::Evaluator;
use crate::dynamics::loops::derivatives::ConstrainedDerivatives;
use crate::spatial::Force;

/// How far (relative to max(1, |z̈|)) the saddle point's accelerations may lie from the run's
/// right-hand side's before the derivatives are taken as those of another equation: the two
/// solves differ by round-off, a few 1e-15 on the examples.
const SAME_ACCELERATIONS: f64 = 1e-9;

/// The exact parts of the linear model.
pub(super) struct ExactRows {
    /// ∂z̈/∂(z, ż): A's accelerations' rows, n × 2n.
    pub by_state: DMatrix<f64>,
    /// ∂z̈/∂τ along each effort input's velocity: B's accelerations' rows, n × inputs.
    pub by_effort: DMatrix<f64>,
}

/// Why the accelerations' rows are differenced instead, for the report.
pub(super) type Refusal = String;

/// A's accelerations' rows and B's effort columns at the chart's state x, under the efforts
/// `efforts` along the inputs' velocities, where `rates` are the right-hand side's
/// accelerations there; the reason they are not exact otherwise.
pub(super) fn loop_rows(
    evaluator: &mut Evaluator,
    x: &[f64],
    efforts: &[f64],
    rates: &[f64],
) -> Result<ExactRows, Refusal> {
    let model = evaluator.system.model;
    let (q, v) = (evaluator.state(x, &[])).map_err(|e| e.to_string())?;
    let mut tau = vec![0.0; model.velocities()];
    for (&velocity, &effort) in evaluator.inputs.efforts.iter().zip(efforts) {
        tau[velocity] += effort;
    }
    let external = vec![Force::zeros(); model.body_count() + 1];
    let mut derivatives = ConstrainedDerivatives::new(model);
    let scratch = &mut *evaluator.system.scratch;
    let structure = &scratch.loops.structure;
    (derivatives.compute(model, &mut scratch.data, structure, &q, &v, &tau, &external))
        .map_err(|e| e.to_string())?;
    // After the derivatives' own refusals, which say more of the mechanism.
    if model.has_efforts() {
        return Err(
            "the program's efforts (forces, springs, dampers, actuators, states) \
                    may depend on the state, and their derivatives are not computed with loops"
                .to_string(),
        );
    }
    let independent = &evaluator.chart.independent;
    let n = independent.len();
    let solved: Vec<f64> = independent
        .iter()
        .map(|&i| derivatives.acceleration[i])
        .collect();
    let scale = rates[..n].iter().fold(1.0_f64, |m, a| m.max(a.abs()));
    let apart = (solved.iter().zip(rates))
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    if apart > SAME_ACCELERATIONS * scale {
        return Err(format!(
            "the saddle point's accelerations lie {apart:.1e} from the right-hand side's: \
             the run solves other equations here"
        ));
    }
    let chart = (derivatives.in_independent_coordinates(independent)).map_err(|e| e.to_string())?;
    let mut by_state = DMatrix::zeros(n, 2 * n);
    by_state
        .columns_mut(0, n)
        .copy_from(&chart.dacceleration_dz);
    (by_state.columns_mut(n, n)).copy_from(&chart.dacceleration_drates);
    let by_effort = chart
        .dacceleration_dtau
        .select_columns(&evaluator.inputs.efforts);
    Ok(ExactRows {
        by_state,
        by_effort,
    })
}
