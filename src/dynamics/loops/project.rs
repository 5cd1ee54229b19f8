//! Moving a state back onto the loops: Gauss–Newton steps on the positions with minimum-norm
//! corrections (the free motions are not disturbed), then the orthogonal projection of the
//! velocities onto G v = 0. Along a run the steps use the rows the `Structure` keeps and their
//! sparse factorisation (`Factored`); before the structure is known (closing the initial configuration, looking
//! at its neighbours), they use every row through a singular value decomposition.

use nalgebra::{DMatrix, DVector};

use super::basis::decompose;
use super::factored::{free_quality, Envelope, Factored, RowChoice, DAMPING, PROJECTION_DAMPING};
use super::rows::{constraints, constraints_into, seat_ball_angles, Constraints};
use crate::dynamics::algorithms::{forward_kinematics, Data};
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

/// What a projection keeps from one call to the next, so that it allocates nothing once sized:
/// the constraints at the current and the trial positions, the kept rows' factorisation, and
/// the vectors of the steps.
pub struct ProjectionScratch {
    pub current: Constraints,
    trial: Constraints,
    pub factored: Factored,
    factor: Envelope,
    /// Whether `factor` holds the `PROJECTION_DAMPING` factor of the rows in `factored`.
    factor_valid: bool,
    /// Whether `factor` holds the `DAMPING` factor `conditioning` took.
    quality_factor: bool,
    kept: Vec<f64>,
    correction: Vec<f64>,
    trial_q: Vec<f64>,
    rest: Vec<f64>,
    /// The allowed motions of the free coordinates, and their block's factor (`free_quality`).
    motions: DMatrix<f64>,
    block: DMatrix<f64>,
}

impl ProjectionScratch {
    pub fn new(model: &Model) -> ProjectionScratch {
        let current = Constraints::new(model);
        ProjectionScratch {
            trial: Constraints::new(model),
            factored: Factored::new(&current.jacobian, &RowChoice::NONE),
            current,
            factor: Envelope::default(),
            factor_valid: false,
            quality_factor: false,
            kept: Vec::new(),
            correction: vec![0.0; model.velocities()],
            trial_q: Vec::new(),
            rest: vec![0.0; model.velocities()],
            motions: DMatrix::zeros(0, 0),
            block: DMatrix::zeros(0, 0),
        }
    }
}

/// Moves (q, v) onto the kept rows of the constraints.
pub fn project(
    model: &Model,
    data: &mut Data,
    choice: &RowChoice,
    q: &mut [f64],
    v: &mut [f64],
) -> Result<Projection, EvalError> {
    let mut scratch = ProjectionScratch::new(model);
    forward_kinematics(model, data, q, v)?;
    constraints_into(model, data, q, v, false, &mut scratch.current)?;
    project_from(model, data, choice, q, v, &mut scratch)
}

/// `project` from the constraints at (q, v) already in `scratch.current`: Gauss–Newton on the
/// positions, each step with the kept rows factored where it starts, then the velocities'
/// projection with the factor at the final positions (the last accepted step's). A factor
/// taken once and kept along the steps would cost less, but where rows close their loop only
/// at second order (the meshes) their independence is about 1e-8, the rows turn fast against
/// it, and the minimum-norm corrections of an older factor move the state along the closed set
/// (maille2's error at 1e-10 grew tenfold so). Nothing is allocated once `scratch` is sized.
pub fn project_from(
    model: &Model,
    data: &mut Data,
    choice: &RowChoice,
    q: &mut [f64],
    v: &mut [f64],
    scratch: &mut ProjectionScratch,
) -> Result<Projection, EvalError> {
    let before = Residuals {
        position: scratch.current.residual.amax(),
        velocity: scratch.current.velocity.amax(),
    };
    let mut factored = scratch.refactor(choice);
    let mut error = before.position;
    for _ in 0..NEWTON_ITERATIONS {
        if error == 0.0 || !factored {
            break;
        }
        let trial_error = scratch.trial_step(model, data, q)?;
        // A NaN residual (infinite here) is no improvement either.
        if trial_error >= error {
            break;
        }
        let converging = trial_error < 0.25 * error;
        q.copy_from_slice(&scratch.trial_q);
        std::mem::swap(&mut scratch.current, &mut scratch.trial);
        error = trial_error;
        factored = scratch.refactor(choice);
        if !converging {
            break;
        }
    }
    let velocity = scratch.project_velocities(v);
    seat_ball_angles(model, data, q, v, false)?;
    let current = &scratch.current;
    Ok(Projection {
        before,
        after: Residuals {
            position: current.residual.amax(),
            velocity,
        },
        left: largest_kept(&scratch.factored, &current.residual, choice),
    })
}

impl ProjectionScratch {
    /// How far the kept rows of the current constraints are from dependent
    /// (`Factored::conditioning`, damped by `DAMPING`).
    pub fn conditioning(&mut self, choice: &RowChoice) -> (f64, Option<usize>) {
        self.factored.refill(&self.current.jacobian, choice);
        self.factor_valid = false;
        let damped = self
            .factored
            .damped_in(DAMPING, std::mem::take(&mut self.factor));
        let conditioning = self.factored.conditioning_of(&damped);
        if let Ok(damped) = damped {
            self.factor = damped.into_storage();
            self.quality_factor = true;
        } else {
            self.quality_factor = false;
        }
        conditioning
    }

    /// How well the free coordinates `free` parametrise the allowed motions of the rows
    /// `conditioning` just factored (`Structure::free_quality_at`); None if they could not be.
    pub fn free_quality(&mut self, free: &[usize]) -> Option<f64> {
        if !self.quality_factor || free.is_empty() {
            return self.quality_factor.then_some(1.0);
        }
        if self.motions.shape() != (self.correction.len(), free.len()) {
            self.motions = DMatrix::zeros(self.correction.len(), free.len());
        }
        let damped = self.factored.with_factor(std::mem::take(&mut self.factor));
        damped.allowed_motions_into(free, &mut self.kept, &mut self.motions);
        self.factor = damped.into_storage();
        Some(free_quality(&self.motions, free, &mut self.block))
    }

    /// Factors the kept rows of the current constraints (damped by `PROJECTION_DAMPING`);
    /// whether they could be factored.
    fn refactor(&mut self, choice: &RowChoice) -> bool {
        self.factored.refill(&self.current.jacobian, choice);
        let storage = std::mem::take(&mut self.factor);
        self.factor_valid = match self.factored.damped_in(PROJECTION_DAMPING, storage) {
            Ok(damped) => {
                self.factor = damped.into_storage();
                true
            }
            Err(_) => false,
        };
        self.quality_factor = false;
        self.factor_valid
    }

    /// One position step from q with the factor held: the damped minimum-norm correction of
    /// the kept rows' residual; the trial positions and their constraints are left in
    /// `trial_q` and `trial`. Returns the trial's largest residual.
    fn trial_step(&mut self, model: &Model, data: &mut Data, q: &[f64]) -> Result<f64, EvalError> {
        let damped = self.factored.with_factor(std::mem::take(&mut self.factor));
        self.factored
            .kept_into(self.current.residual.as_slice(), &mut self.kept);
        self.kept.iter_mut().for_each(|x| *x = -*x);
        damped.least_norm_into(&mut self.kept, &mut self.correction);
        self.factor = damped.into_storage();
        self.trial_q.clear();
        self.trial_q.extend_from_slice(q);
        model.retract(&mut self.trial_q, &self.correction);
        forward_kinematics(model, data, &self.trial_q, &self.rest)?;
        constraints_into(
            model,
            data,
            &self.trial_q,
            &self.rest,
            false,
            &mut self.trial,
        )?;
        let error = self.trial.residual.amax();
        Ok(if error.is_nan() { f64::INFINITY } else { error })
    }

    /// The velocities' damped projection onto G v = 0 at the current positions, with the
    /// factor taken there: v − Gₛᵀ(A + μ²E)⁻¹Gₛv. Returns the largest velocity row left.
    fn project_velocities(&mut self, v: &mut [f64]) -> f64 {
        if !self.factor_valid {
            return velocity_rows(&self.current, v);
        }
        let damped = self.factored.with_factor(std::mem::take(&mut self.factor));
        self.factored.times_into(v, &mut self.kept);
        damped.least_norm_into(&mut self.kept, &mut self.correction);
        self.factor = damped.into_storage();
        for (x, c) in v.iter_mut().zip(&self.correction) {
            *x -= c;
        }
        velocity_rows(&self.current, v)
    }
}

/// The largest velocity row |G v| of the constraints `c`.
fn velocity_rows(c: &Constraints, v: &[f64]) -> f64 {
    (0..c.jacobian.nrows())
        .map(|r| {
            c.jacobian
                .row(r)
                .map(|(column, g)| g * v[column])
                .sum::<f64>()
                .abs()
        })
        .fold(0.0, f64::max)
}

fn largest_kept(
    factored: &Factored,
    residual: &DVector<f64>,
    choice: &RowChoice,
) -> (f64, Option<usize>) {
    factored
        .kept_rows()
        .map(|(r, scale)| (residual[r] * scale).abs())
        .enumerate()
        .fold((0.0, None), |(best, row), (k, value)| {
            if row.is_none() || value > best {
                (value, Some(choice.rows[k]))
            } else {
                (best, row)
            }
        })
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
