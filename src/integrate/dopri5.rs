//! The explicit Runge–Kutta pair of Dormand and Prince, order 5 with an embedded order-4 error
//! estimate, "first same as last" (the last stage is dy/dt at the new point, reused as the next
//! step's first stage), and Dormand and Prince's continuous extension of order 4 for dense output.
//! Coefficients from Hairer, Nørsett and Wanner, Solving ODEs I, II.5 (Table 5.2) and II.6.

use super::control::{error_norm, Gains, StepController};
use super::driver::AdaptiveStepper;
use super::evaluator::{Evaluator, Halt};
use super::hermite::hermite_part_into;
use super::settings::Settings;

const STAGES: usize = 7;

/// |h λ| at the boundary of the method's stability region on the negative real axis.
pub const STABILITY_LIMIT: f64 = 3.3;

/// Fractions of the step at which the stages are evaluated.
pub const C: [f64; STAGES] = [0.0, 1.0 / 5.0, 3.0 / 10.0, 4.0 / 5.0, 8.0 / 9.0, 1.0, 1.0];

/// Weights of earlier stages in each stage's state (row i has i entries).
pub const A: [&[f64]; STAGES] = [
    &[],
    &[1.0 / 5.0],
    &[3.0 / 40.0, 9.0 / 40.0],
    &[44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0],
    &[
        19372.0 / 6561.0,
        -25360.0 / 2187.0,
        64448.0 / 6561.0,
        -212.0 / 729.0,
    ],
    &[
        9017.0 / 3168.0,
        -355.0 / 33.0,
        46732.0 / 5247.0,
        49.0 / 176.0,
        -5103.0 / 18656.0,
    ],
    // The fifth-order solution itself: its derivative is the last stage.
    &[
        35.0 / 384.0,
        0.0,
        500.0 / 1113.0,
        125.0 / 192.0,
        -2187.0 / 6784.0,
        11.0 / 84.0,
    ],
];

/// Fifth-order minus fourth-order weights: the local error estimate.
pub const ERROR: [f64; STAGES] = [
    71.0 / 57600.0,
    0.0,
    -71.0 / 16695.0,
    71.0 / 1920.0,
    -17253.0 / 339200.0,
    22.0 / 525.0,
    -1.0 / 40.0,
];

/// Weights of the stages in the last coefficient of the order-4 continuous extension.
pub const DENSE: [f64; STAGES] = [
    -12715105075.0 / 11282082432.0,
    0.0,
    87487479700.0 / 32700410799.0,
    -10690763975.0 / 1880347072.0,
    701980252875.0 / 199316789632.0,
    -1453857185.0 / 822651844.0,
    69997945.0 / 29380423.0,
];

pub(super) struct DormandPrince {
    /// Stage derivatives of the current attempt; `stages[0]` is dy/dt at the current point.
    stages: [Vec<f64>; STAGES],
    stage_state: Vec<f64>,
    error: Vec<f64>,
    /// Coefficients of the interpolating polynomial over the last accepted step, formed only
    /// for a step whose interpolant is read (`interpolation_wanted`).
    dense: [Vec<f64>; 5],
    /// Whether the attempt about to be accepted is interpolated (an output inside it, or
    /// events to locate: `prepare_interpolation`). Most steps of a run whose outputs are far
    /// apart are not.
    interpolation_wanted: bool,
    dense_start: f64,
    dense_step: f64,
    rtol: f64,
    /// Components of the state the error control watches (the leading ones).
    controlled: usize,
    atol: f64,
    /// h |λ| of the last attempt, λ the stiffest eigenvalue's estimate (`stiffness`).
    stiffness: f64,
}

impl DormandPrince {
    pub(super) fn new(dimension: usize, settings: &Settings) -> Self {
        let zeros = vec![0.0; dimension];
        DormandPrince {
            stages: std::array::from_fn(|_| zeros.clone()),
            stage_state: zeros.clone(),
            error: zeros.clone(),
            dense: std::array::from_fn(|_| zeros.clone()),
            interpolation_wanted: false,
            dense_start: 0.0,
            dense_step: 0.0,
            rtol: settings.rtol,
            controlled: settings.controlled_len(dimension),
            atol: settings.atol,
            stiffness: 0.0,
        }
    }

    /// h |λ| over the last attempt, with λ estimated as ‖k₇ − k₆‖ / ‖y₇ − y₆‖ from its last two
    /// stages, which share their time (Hairer and Wanner, *Solving ODEs II*, IV.2, as in their
    /// DOPRI5): about 3.3 or more when the step was held at the method's stability boundary by
    /// a stiff component.
    pub(super) fn stiffness(&self) -> f64 {
        self.stiffness
    }

    /// The coefficients of the continuous extension over the step of size `h` from (t, y) to
    /// `y_new` just attempted (Hairer, Nørsett and Wanner, II.6).
    fn form_interpolant(&mut self, t: f64, y: &[f64], h: f64, y_new: &[f64]) {
        let [first, .., last] = &self.stages;
        let [r0, r1, r2, r3, r4] = &mut self.dense;
        hermite_part_into(h, (y, y_new), (first, last), [r0, r1, r2, r3]);
        for i in 0..y.len() {
            r4[i] = h * DENSE
                .iter()
                .zip(&self.stages)
                .map(|(d, k)| d * k[i])
                .sum::<f64>();
        }
        self.dense_start = t;
        self.dense_step = h;
    }

    /// Takes `derivative` as dy/dt at the current point (computed by another method).
    pub(super) fn adopt(&mut self, derivative: &[f64]) {
        self.stages[0].copy_from_slice(derivative);
    }
}

/// y + h * (the stages before `stage`, weighted by its row of A), into `out`. The weighted
/// sum is gathered in `out` a stage at a time, in the order of the stages (the same sums as
/// term by term within each component): loops over the components that the compiler
/// vectorises, where a sum over the stages per component was a loop of a few iterations each.
fn stage_state_into(stages: &[Vec<f64>], stage: usize, y: &[f64], h: f64, out: &mut [f64]) {
    weighted_sum_into(A[stage], stages, out);
    for (value, y) in out.iter_mut().zip(y) {
        *value = y + h * *value;
    }
}

/// Σ weights[j] · stages[j] into `out`, the terms added in the order of j.
fn weighted_sum_into(weights: &[f64], stages: &[Vec<f64>], out: &mut [f64]) {
    let (first, rest) = (weights[0], &weights[1..]);
    for (value, k) in out.iter_mut().zip(&stages[0]) {
        *value = first * k;
    }
    for (&weight, k) in rest.iter().zip(&stages[1..]) {
        for (value, k) in out.iter_mut().zip(k) {
            *value += weight * k;
        }
    }
}

impl AdaptiveStepper for DormandPrince {
    fn order(&self) -> u32 {
        5
    }

    fn stability_limit(&self) -> Option<f64> {
        Some(STABILITY_LIMIT)
    }

    fn controller(&self) -> StepController {
        // The error estimate is that of the order-4 solution. Gustafsson's PI.3.4 integral gain
        // and a predictive limit that anticipates an accelerating error constant: on the spatial
        // linkages at most 6.9 % of the attempts are rejected at any tolerance from 1e-4 to 1e-12
        // (up to 19 % with Hairer's β = 0.04 and the plain predictive limit), and about 4 % less
        // work at equal error on the examples (`docs/commands.md`, *Integrators*).
        StepController::new(
            4,
            Gains {
                beta: 0.08,
                safety: 0.93,
                max_factor: 10.0,
                rise_power: 2.5,
            },
        )
    }

    fn start(&mut self, eval: &mut Evaluator, t: f64, y: &[f64]) -> Result<(), Halt> {
        eval.rhs(t, y, &mut self.stages[0])
    }

    fn derivative(&self) -> &[f64] {
        &self.stages[0]
    }

    fn attempt(
        &mut self,
        eval: &mut Evaluator,
        t: f64,
        y: &[f64],
        h: f64,
        y_new: &mut [f64],
    ) -> Result<f64, Halt> {
        for (stage, fraction) in C.iter().enumerate().take(STAGES - 1).skip(1) {
            stage_state_into(&self.stages, stage, y, h, &mut self.stage_state);
            eval.rhs(t + fraction * h, &self.stage_state, &mut self.stages[stage])?;
        }
        stage_state_into(&self.stages, STAGES - 1, y, h, y_new);
        eval.rhs(t + h, y_new, &mut self.stages[STAGES - 1])?;
        let n = self.controlled;
        let [.., before_last, last] = &self.stages;
        let slopes: f64 = (last[..n].iter().zip(&before_last[..n]))
            .map(|(a, b)| (a - b).powi(2))
            .sum();
        let states: f64 = (y_new[..n].iter().zip(&self.stage_state[..n]))
            .map(|(a, b)| (a - b).powi(2))
            .sum();
        self.stiffness = if states > 0.0 {
            h * (slopes / states).sqrt()
        } else {
            0.0
        };
        weighted_sum_into(&ERROR, &self.stages, &mut self.error);
        self.error.iter_mut().for_each(|error| *error *= h);
        Ok(error_norm(
            &self.error[..self.controlled],
            &y[..self.controlled],
            &y_new[..self.controlled],
            self.rtol,
            self.atol,
        ))
    }

    /// Nothing to evaluate: says that the step's interpolant is read, so that `accept` forms it.
    fn prepare_interpolation(
        &mut self,
        _eval: &mut Evaluator,
        _t: f64,
        _y: &[f64],
        _h: f64,
    ) -> Result<(), Halt> {
        self.interpolation_wanted = true;
        Ok(())
    }

    fn accept(&mut self, t: f64, y: &[f64], h: f64, y_new: &[f64]) {
        if std::mem::take(&mut self.interpolation_wanted) {
            self.form_interpolant(t, y, h, y_new);
        }
        // First same as last: dy/dt at the new point starts the next step.
        self.stages.swap(0, STAGES - 1);
    }

    fn interpolate(&self, t: f64, out: &mut [f64]) {
        let theta = (t - self.dense_start) / self.dense_step;
        let rest = 1.0 - theta;
        let [r0, r1, r2, r3, r4] = &self.dense;
        for i in 0..out.len() {
            out[i] = r0[i] + theta * (r1[i] + rest * (r2[i] + theta * (r3[i] + rest * r4[i])));
        }
    }
}
