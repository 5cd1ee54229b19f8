//! Moving a state back onto the loops: Gauss–Newton steps on the positions with minimum-norm
//! corrections (the free motions are not disturbed), then the orthogonal projection of the
//! velocities onto G v = 0. Along a run the steps use the rows the `Structure` keeps and their
//! sparse factorisation (`Factored`); before the structure is known (closing the initial configuration, looking
//! at its neighbours), they use every row through a singular value decomposition.

use nalgebra::DVector;

use super::basis::decompose;
use super::factored::{Factored, RowChoice, PROJECTION_DAMPING};
use super::rows::{constraints, seat_ball_angles, Constraints};
use crate::dynamics::algorithms::Data;
use crate::dynamics::model::Model;
use crate::kinematics::eval::EvalError;

/// Constraint residuals before and after a projection: largest position row (metres or
/// radians) and largest velocity row.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Residuals {
    pub position: f64,
    pub velocity: f64,
}

pub struct Projection {
    pub before: Residuals,
    pub after: Residuals,
    /// The largest kept row left after it, made dimensionless, and that row (among the 6 per
    /// loop).
    pub left: (f64, Option<usize>),
}

const NEWTON_ITERATIONS: usize = 8;

/// Moves (q, v) onto the kept rows of the constraints.
pub fn project(
    model: &Model,
    data: &mut Data,
    choice: &RowChoice,
    q: &mut [f64],
    v: &mut [f64],
) -> Result<Projection, EvalError> {
    let rest = vec![0.0; v.len()];
    let mut current = constraints(model, data, q, &rest, false)?;
    let before_position = current.residual.amax();
    newton(model, data, q, &mut current, |c| {
        let factored = Factored::new(&c.jacobian, choice);
        factored
            .damped_least_norm(&-factored.kept(&c.residual), PROJECTION_DAMPING)
            .ok()
    })?;
    let factored = Factored::new(&current.jacobian, choice);
    let velocity = current.jacobian.mul(v);
    let corrected = factored
        .damped_allowed_part(&DVector::from_column_slice(v), PROJECTION_DAMPING)
        .unwrap_or_else(|_| DVector::from_column_slice(v));
    let after_velocity = current.jacobian.mul(corrected.as_slice()).amax();
    v.copy_from_slice(corrected.as_slice());
    seat_ball_angles(model, data, q, v, false)?;
    Ok(Projection {
        before: Residuals {
            position: before_position,
            velocity: velocity.amax(),
        },
        after: Residuals {
            position: current.residual.amax(),
            velocity: after_velocity,
        },
        left: largest_kept(&factored, &current.residual, choice),
    })
}

fn largest_kept(
    factored: &Factored,
    residual: &DVector<f64>,
    choice: &RowChoice,
) -> (f64, Option<usize>) {
    let kept = factored.kept(residual).map(f64::abs);
    if kept.is_empty() {
        return (0.0, None);
    }
    let k = kept.imax();
    (kept[k], Some(choice.rows[k]))
}

/// Moves q onto every row of the constraints (minimum-norm steps on a singular value
/// decomposition, whatever the rank); returns the largest residual left.
pub fn close_configuration(
    model: &Model,
    data: &mut Data,
    q: &mut [f64],
) -> Result<f64, EvalError> {
    let rest = vec![0.0; model.velocities()];
    let mut current = constraints(model, data, q, &rest, false)?;
    newton(model, data, q, &mut current, |c| {
        Some(-(decompose(&c.jacobian.dense()).pseudo_inverse * &c.residual))
    })?;
    Ok(current.residual.amax())
}

/// Gauss–Newton on the positions: `step` gives the correction at the constraints `current`
/// (None to stop); stops when a step no longer reduces the largest residual, or reduces it less
/// than fourfold. Leaves q and `current` at the best configuration reached.
fn newton(
    model: &Model,
    data: &mut Data,
    q: &mut [f64],
    current: &mut Constraints,
    mut step: impl FnMut(&Constraints) -> Option<DVector<f64>>,
) -> Result<(), EvalError> {
    let rest = vec![0.0; model.velocities()];
    let mut error = current.residual.amax();
    for _ in 0..NEWTON_ITERATIONS {
        if error == 0.0 {
            break;
        }
        let Some(correction) = step(current) else {
            break;
        };
        let mut trial = q.to_vec();
        model.retract(&mut trial, correction.as_slice());
        let candidate = constraints(model, data, &trial, &rest, false)?;
        let trial_error = candidate.residual.amax();
        // A NaN residual is no improvement either.
        if trial_error.is_nan() || trial_error >= error {
            break;
        }
        let converging = trial_error < 0.25 * error;
        q.copy_from_slice(&trial);
        (*current, error) = (candidate, trial_error);
        if !converging {
            break;
        }
    }
    Ok(())
}
