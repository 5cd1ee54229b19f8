//! RODAS3, a stiffly accurate Rosenbrock method of order 3 with four stages and an embedded
//! order-2 error estimate (Sandu, Verwer, Blom, Spee, Carmichael and Potra, "Benchmarking stiff
//! ODE solvers for atmospheric chemistry problems II: Rosenbrock solvers", Atmos. Environ. 1997).
//!
//! Each stage solves a linear system with W = I / (h γ) − J instead of iterating Newton's method,
//! which is why the method is L-stable on stiff problems at the cost of one LU decomposition per
//! attempt. The method needs the true Jacobian J (and ∂f/∂t), here by finite differences, formed
//! once per accepted step. Dense output is the cubic Hermite interpolant through the step's ends,
//! whose end slope is free because it is the next step's first stage.

use nalgebra::{DMatrix, DVector, Dyn, LU};

use super::control::{error_norm, Gains, StepController};
use super::driver::AdaptiveStepper;
use super::evaluator::{all_finite, Evaluator, Halt};
use super::hermite::HermiteSegment;
use super::settings::Settings;

/// The number of stages.
pub const STAGES: usize = 4;

type Lu = LU<f64, Dyn, Dyn>;

/// The diagonal of the method, the same for every stage so that one LU serves all of them.
pub const GAMMA: f64 = 0.5;

// The coefficients in the transformed form where the unknowns are the stage increments K_i:
//   (I / (h γ) − J) K_i = f(t + α_i h, y + Σ_j A_ij K_j) + Σ_j C_ij K_j / h + γ_i h ∂f/∂t.

/// Weights of earlier increments in each stage's state.
pub const A: [[f64; STAGES]; STAGES] = [
    [0.0; 4],
    [0.0; 4],
    [2.0, 0.0, 0.0, 0.0],
    [2.0, 0.0, 1.0, 0.0],
];
/// Weights of earlier increments (divided by h) in each stage's right-hand side.
pub const C: [[f64; STAGES]; STAGES] = [
    [0.0; 4],
    [4.0, 0.0, 0.0, 0.0],
    [1.0, -1.0, 0.0, 0.0],
    [1.0, -1.0, -8.0 / 3.0, 0.0],
];
/// Whether a stage evaluates f anew; the second stage's state and time equal the first's.
const NEW_F: [bool; STAGES] = [true, false, true, true];
/// Fractions of the step at which the stages evaluate f.
pub const ALPHA: [f64; STAGES] = [0.0, 0.0, 1.0, 1.0];
/// Weights of h ∂f/∂t in each stage (row sums of the method's Γ matrix).
pub const GAMMA_SUM: [f64; STAGES] = [0.5, 1.5, 0.0, 0.0];
/// Weights of the increments in the order-3 solution.
pub const M: [f64; STAGES] = [2.0, 0.0, 1.0, 1.0];
/// Weights of the increments in the difference between the order-3 and order-2 solutions.
pub const E: [f64; STAGES] = [0.0, 0.0, 0.0, 1.0];

pub(super) struct Rodas3 {
    rtol: f64,
    /// Components of the state the error control watches (the leading ones).
    controlled: usize,
    atol: f64,
    /// dy/dt at the current point.
    derivative: Vec<f64>,
    jacobian: DMatrix<f64>,
    time_derivative: Vec<f64>,
    jacobian_is_current: bool,
    increments: [DVector<f64>; STAGES],
    stage_state: Vec<f64>,
    stage_derivative: Vec<f64>,
    /// dy/dt at the end of the last attempt, evaluated only when the attempt is acceptable.
    end_derivative: Vec<f64>,
    error: Vec<f64>,
    segment: HermiteSegment,
}

impl Rodas3 {
    pub(super) fn new(dimension: usize, settings: &Settings) -> Self {
        let zeros = vec![0.0; dimension];
        Rodas3 {
            rtol: settings.rtol,
            controlled: settings.controlled_len(dimension),
            atol: settings.atol,
            derivative: zeros.clone(),
            jacobian: DMatrix::zeros(dimension, dimension),
            time_derivative: zeros.clone(),
            jacobian_is_current: false,
            increments: std::array::from_fn(|_| DVector::zeros(dimension)),
            stage_state: zeros.clone(),
            stage_derivative: zeros.clone(),
            end_derivative: zeros.clone(),
            error: zeros,
            segment: HermiteSegment::new(dimension),
        }
    }

    /// ∂f/∂y and ∂f/∂t at the current point by forward differences, with increments that balance
    /// truncation against rounding (as in Hairer and Wanner's RODAS).
    fn form_jacobian(&mut self, eval: &mut Evaluator, t: f64, y: &[f64]) -> Result<(), Halt> {
        eval.stats.jacobian_evaluations += 1;
        let mut perturbed = y.to_vec();
        for j in 0..y.len() {
            perturbed[j] = y[j] + (f64::EPSILON * y[j].abs().max(1e-5)).sqrt();
            // The increment actually represented, so that rounding of y + δ does not bias the quotient.
            let delta = perturbed[j] - y[j];
            eval.rhs(t, &perturbed, &mut self.stage_derivative)?;
            for i in 0..y.len() {
                self.jacobian[(i, j)] = (self.stage_derivative[i] - self.derivative[i]) / delta;
            }
            perturbed[j] = y[j];
        }
        let dt = (t + (f64::EPSILON * t.abs().max(1e-5)).sqrt()) - t;
        eval.rhs(t + dt, y, &mut self.stage_derivative)?;
        for i in 0..y.len() {
            self.time_derivative[i] = (self.stage_derivative[i] - self.derivative[i]) / dt;
        }
        Ok(())
    }

    /// LU decomposition of W = I / (h γ) − J, or `None` when W is singular.
    fn factorize(&self, eval: &mut Evaluator, h: f64) -> Option<Lu> {
        eval.stats.lu_decompositions += 1;
        let mut w = -&self.jacobian;
        for i in 0..w.nrows() {
            w[(i, i)] += 1.0 / (h * GAMMA);
        }
        let lu = w.lu();
        lu.is_invertible().then_some(lu)
    }

    /// Solves for the increment of one stage.
    fn solve_stage(
        &mut self,
        eval: &mut Evaluator,
        lu: &Lu,
        stage: usize,
        t: f64,
        y: &[f64],
        h: f64,
    ) -> Result<(), Halt> {
        if stage == 0 {
            self.stage_derivative.copy_from_slice(&self.derivative);
        } else if NEW_F[stage] {
            for (i, state) in self.stage_state.iter_mut().enumerate() {
                *state = y[i]
                    + (0..stage)
                        .map(|j| A[stage][j] * self.increments[j][i])
                        .sum::<f64>();
            }
            eval.rhs(
                t + ALPHA[stage] * h,
                &self.stage_state,
                &mut self.stage_derivative,
            )?;
        }
        let mut rhs = DVector::from_fn(y.len(), |i, _| {
            let coupling: f64 = (0..stage)
                .map(|j| C[stage][j] * self.increments[j][i])
                .sum();
            self.stage_derivative[i] + coupling / h + GAMMA_SUM[stage] * h * self.time_derivative[i]
        });
        // nalgebra's triangular solves do not accept an empty system.
        if !rhs.is_empty() {
            lu.solve_mut(&mut rhs);
        }
        self.increments[stage] = rhs;
        Ok(())
    }
}

impl AdaptiveStepper for Rodas3 {
    fn order(&self) -> u32 {
        3
    }

    fn controller(&self) -> StepController {
        // The estimate is the error of the order-2 solution. Elementary control with Hairer and
        // Wanner's growth limit for Rosenbrock methods: PI gains of 0.04 and 0.08 took 3–10 % more
        // steps on the test problems for a few fewer rejections.
        StepController::new(
            2,
            Gains {
                beta: 0.0,
                safety: 0.9,
                max_factor: 6.0,
                rise_power: 1.0,
            },
        )
    }

    fn start(&mut self, eval: &mut Evaluator, t: f64, y: &[f64]) -> Result<(), Halt> {
        eval.rhs(t, y, &mut self.derivative)
    }

    fn derivative(&self) -> &[f64] {
        &self.derivative
    }

    fn attempt(
        &mut self,
        eval: &mut Evaluator,
        t: f64,
        y: &[f64],
        h: f64,
        y_new: &mut [f64],
    ) -> Result<f64, Halt> {
        if !self.jacobian_is_current {
            self.form_jacobian(eval, t, y)?;
            self.jacobian_is_current = true;
        }
        let Some(lu) = self.factorize(eval, h) else {
            // A singular W is a property of this step size: reject it like a large error.
            return Ok(f64::INFINITY);
        };
        for stage in 0..STAGES {
            self.solve_stage(eval, &lu, stage, t, y, h)?;
        }
        for i in 0..y.len() {
            y_new[i] = y[i]
                + (0..STAGES)
                    .map(|s| M[s] * self.increments[s][i])
                    .sum::<f64>();
            self.error[i] = (0..STAGES)
                .map(|s| E[s] * self.increments[s][i])
                .sum::<f64>();
        }
        let error = error_norm(
            &self.error[..self.controlled],
            &y[..self.controlled],
            &y_new[..self.controlled],
            self.rtol,
            self.atol,
        );
        if error <= 1.0 && all_finite(y_new) {
            eval.rhs(t + h, y_new, &mut self.end_derivative)?;
        }
        Ok(error)
    }

    fn accept(&mut self, t: f64, y: &[f64], h: f64, y_new: &[f64]) {
        self.segment
            .set(t, h, [y, &self.derivative, y_new, &self.end_derivative]);
        std::mem::swap(&mut self.derivative, &mut self.end_derivative);
        self.jacobian_is_current = false;
    }

    fn interpolate(&self, t: f64, out: &mut [f64]) {
        self.segment.evaluate(t, out);
    }
}
