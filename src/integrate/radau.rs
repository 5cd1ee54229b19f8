//! Radau IIA of order 5 (three stages, stage order 3), the implicit Runge–Kutta method of Hairer
//! and Wanner's RADAU5 (*Solving ODEs II*, IV.8), for stiff problems.
//!
//! Each step solves the collocation equations Z_i = h Σ_j a_ij f(t + c_j h, y + Z_j) for the
//! stage increments Z by a simplified Newton iteration, whose matrix I ⊗ I − h A ⊗ J is
//! split by the eigenvalues of A⁻¹ (one real γ, one complex pair α ± iβ) into one real and one
//! complex system of the state's size: (γ/h − J) and ((α + iβ)/h − J). Unlike a Rosenbrock
//! method the iteration converges to the same solution whatever J is, so one Jacobian serves as
//! many steps as the iteration converges quickly with it (its rate θ at most `JACOBIAN_RATE`):
//! on the flyball governor the Jacobian is formed once every few steps, where RODAS4 forms it at
//! each. It is formed inside the step, where the last step's polynomial predicts the state
//! (`JACOBIAN_NODE`), not at its start: the stiff directions turn over a step. Its stage order
//! 3 keeps the order near 5 on stiff mechanical problems, where RODAS4's stage order 1 lowers
//! it (`BENCHMARKS.md`).
//!
//! The error estimate is RADAU5's (γ/h − J)⁻¹ (f(t, y) + Σ e_i Z_i / h), of order 3, which
//! damps the stiff components; its f(t, y) is the last step's end slope, carried over from
//! the iteration rather than evaluated (`Radau5::end_slope`). The collocation polynomial of degree 3 gives the next step's
//! first guess of Z, and the dense output of the stiff components; the others' dense output
//! is the quintic through the last three step ends (`radau/hermite.rs`).

use nalgebra::{Complex, DMatrix, DVector, Dyn, LU};

use super::control::{error_norm, Gains, StepController};
use super::driver::AdaptiveStepper;
use super::evaluator::{all_finite, Evaluator, Halt};
use super::jacobian::leading_columns;
use super::settings::Settings;
use hermite::Hermite;

pub mod hermite;

const SQRT6: f64 = 2.449_489_742_783_178;
/// The nodes c_i.
const NODES: [f64; 3] = [(4.0 - SQRT6) / 10.0, (4.0 + SQRT6) / 10.0, 1.0];
/// The weights of Σ e_i Z_i / h in the error estimate.
const ERROR_WEIGHTS: [f64; 3] = [
    (-13.0 - 7.0 * SQRT6) / 3.0,
    (-13.0 + 7.0 * SQRT6) / 3.0,
    -1.0 / 3.0,
];
/// T, whose columns are eigenvectors of A⁻¹ (the real one, then the real and imaginary parts
/// of a complex one), and T⁻¹ (the coefficients of scipy's `radau.py`, checked by
/// `tests/suite/unit_integrate.rs`).
pub const TRANSFORM: [[f64; 3]; 3] = [
    [
        0.094_438_762_488_975_24,
        -0.1412552950209542,
        0.030_029_194_105_147_42,
    ],
    [
        0.2502131229653333,
        0.204_129_352_293_799_94,
        -0.3829421127572619,
    ],
    [1.0, 1.0, 0.0],
];
pub const TRANSFORM_INVERSE: [[f64; 3]; 3] = [
    [
        4.178_718_591_551_904,
        0.327_682_820_761_062_37,
        0.523_376_445_499_449_5,
    ],
    [
        -4.178_718_591_551_904,
        -0.327_682_820_761_062_37,
        0.476_623_554_500_550_44,
    ],
    [
        0.502_872_634_945_786_8,
        -2.571_926_949_855_605,
        0.596_039_204_828_224_9,
    ],
];
/// Coefficients of the collocation polynomial: y(t + x h) = y + Σ_k (Σ_i Z_i P[i][k]) x^(k+1).
const DENSE: [[f64; 3]; 3] = [
    [
        13.0 / 3.0 + 7.0 * SQRT6 / 3.0,
        -23.0 / 3.0 - 22.0 * SQRT6 / 3.0,
        10.0 / 3.0 + 5.0 * SQRT6,
    ],
    [
        13.0 / 3.0 - 7.0 * SQRT6 / 3.0,
        -23.0 / 3.0 + 22.0 * SQRT6 / 3.0,
        10.0 / 3.0 - 5.0 * SQRT6,
    ],
    [1.0 / 3.0, -8.0 / 3.0, 10.0 / 3.0],
];

/// The real eigenvalue γ of A⁻¹.
pub fn real_eigenvalue() -> f64 {
    3.0 + 3f64.powf(2.0 / 3.0) - 3f64.cbrt()
}

/// The complex eigenvalue α − iβ of A⁻¹ that goes with [`TRANSFORM_INVERSE`]'s rows 2 and 3.
pub fn complex_eigenvalue() -> Complex<f64> {
    Complex::new(
        3.0 + 0.5 * (3f64.cbrt() - 3f64.powf(2.0 / 3.0)),
        -0.5 * (3f64.powf(5.0 / 6.0) + 3f64.powf(7.0 / 6.0)),
    )
}

/// Newton iterations per attempt before it counts as failed (RADAU5's default).
const NEWTON_ITERATIONS: usize = 7;
/// The rate of convergence θ of the last step's iteration above which the Jacobian is formed
/// again at the next step. Measured on the governor at 3e-10 (instructions of the whole run,
/// Newton iterations, Jacobians): 0.001 (RADAU5's default for small systems) 245 M, 2,511,
/// 670; 0.01 231 M, 2,606, 483; 0.04 224 M, 3,020, 215; 0.1 (its advice where the Jacobian
/// is costly) 242 M, 3,597, 98. A Jacobian there costs about six right-hand sides, an
/// iteration three.
const JACOBIAN_RATE: f64 = 0.04;
/// Where in the step the Jacobian is formed, as a fraction of the step, once a step was
/// accepted: at the state the last step's collocation polynomial predicts there. The simplified
/// iteration's rate grows with how far its Jacobian is from the stages': on the governor at
/// 3e-9, with the Jacobian at the step's start exact to 1e-5 of each row (against central
/// differences), the first rate was 0.1 to 0.33 and a step took 4 to 5 iterations, the stiff
/// springs' directions turning by 1 to 3 % of their stiffness over a step of h |λ| ≈ 100. The
/// stages are at 0.155, 0.645 and 1 of the step; from 0.6 the farthest is 0.45 of a step away
/// instead of 1. Measured there (iterations, evaluations, with an evaluation of f at the
/// predicted state for the accelerations the tree Jacobian differentiates at): at the start
/// 1,785, 5,841; at 0.5 1,722, 5,790; at 0.6 1,692, 5,696. The polynomial's own slope there
/// instead of that evaluation: 5,583 evaluations (a Jacobian from differences of f still
/// evaluates it, `leading_columns`).
const JACOBIAN_NODE: f64 = 0.6;
/// The error an attempt reports when its iteration did not converge: the controller then
/// retries with 0.7 of the step (0.9 · 2.73^(-1/4)).
const NEWTON_FAILED: f64 = 2.73;
/// The fraction of a step on which the iteration failed (with a fresh Jacobian) that the steps
/// after are limited to, and how much that limit grows with each accepted step, so that a
/// run does not try again and again the steps its iteration cannot converge on. (On the
/// governor, most failures came from judging the iteration on its first rate, `hopeless`:
/// without that, 152 steps at 1e-6 instead of 271. Without the limit too, the rejections rose
/// from 26 to 56.)
const NEWTON_LIMIT: f64 = 0.7;
const NEWTON_LIMIT_GROWTH: f64 = 1.1;

type Lu<T> = LU<T, Dyn, Dyn>;

/// The two matrices of the iteration, factored for one step size.
struct Factors {
    step: f64,
    real: Lu<f64>,
    complex: Lu<Complex<f64>>,
}

/// The collocation polynomial of the last accepted step.
struct Collocation {
    t: f64,
    h: f64,
    y: Vec<f64>,
    /// Σ_i Z_i P[i][k], for k = 0, 1, 2.
    coefficients: [Vec<f64>; 3],
}

impl Collocation {
    fn new(dimension: usize) -> Self {
        Collocation {
            t: 0.0,
            h: 0.0,
            y: vec![0.0; dimension],
            coefficients: std::array::from_fn(|_| vec![0.0; dimension]),
        }
    }

    /// The polynomial of the step of size `h` from (t, y) whose stage increments are `z`.
    fn fill(&mut self, t: f64, y: &[f64], h: f64, z: &[Vec<f64>; 3]) {
        self.t = t;
        self.h = h;
        self.y.copy_from_slice(y);
        for (k, coefficients) in self.coefficients.iter_mut().enumerate() {
            for (i, c) in coefficients.iter_mut().enumerate() {
                *c = DENSE[0][k] * z[0][i] + DENSE[1][k] * z[1][i] + DENSE[2][k] * z[2][i];
            }
        }
    }

    /// The polynomial's derivative in t.
    fn slope(&self, t: f64, out: &mut [f64]) {
        let x = (t - self.t) / self.h;
        let [c1, c2, c3] = &self.coefficients;
        for i in 0..out.len() {
            out[i] = (c1[i] + x * (2.0 * c2[i] + 3.0 * x * c3[i])) / self.h;
        }
    }

    fn evaluate(&self, t: f64, out: &mut [f64]) {
        let x = (t - self.t) / self.h;
        let [c1, c2, c3] = &self.coefficients;
        for i in 0..out.len() {
            out[i] = self.y[i] + x * (c1[i] + x * (c2[i] + x * c3[i]));
        }
    }
}

/// How the Newton iteration ended.
enum Newton {
    Converged,
    Failed,
}

pub(super) struct Radau5 {
    rtol: f64,
    atol: f64,
    /// Components of the state the error control watches (the leading ones).
    controlled: usize,
    /// The iteration's stopping threshold, relative to the tolerances.
    newton_tolerance: f64,
    /// The state the last step's polynomial predicts at `JACOBIAN_NODE` of the next step, and
    /// dy/dt there.
    predicted: Vec<f64>,
    predicted_derivative: Vec<f64>,
    /// dy/dt at the current point, and at the end of the last acceptable attempt.
    derivative: Vec<f64>,
    end_derivative: Vec<f64>,
    /// Whether `derivative` was evaluated, not carried over from the last step's iteration
    /// (`end_slope`).
    derivative_evaluated: bool,
    jacobian: Option<DMatrix<f64>>,
    /// Whether the Jacobian was formed for the current point's step.
    fresh: bool,
    /// Whether the next attempt forms the Jacobian again.
    stale: bool,
    factors: Option<Factors>,
    /// The stage increments of the last attempt.
    increments: [Vec<f64>; 3],
    /// The accepted step's polynomial; `None` after a start at a point it did not reach.
    collocation: Option<Collocation>,
    /// θ / (1 − θ) of the last iteration, which lets the next converge in one iteration; 1
    /// after a start (RADAU5's FACCON), where no rate is known yet.
    contraction: f64,
    /// The rate θ of the last iteration.
    rate: f64,
    /// The longest step the iteration is expected to converge on (`NEWTON_LIMIT`).
    newton_limit: f64,
    /// Whether the last attempt was rejected, and whether no step was accepted yet.
    rejected: bool,
    first: bool,
    stage_state: Vec<f64>,
    stage_derivatives: [Vec<f64>; 3],
    /// The iteration's work space, allocated once: the increments transformed by T⁻¹ (W), the
    /// stage derivatives transformed likewise, and the right-hand sides of the real and the
    /// complex system (also the error estimate's).
    transformed: [Vec<f64>; 3],
    transformed_derivatives: [Vec<f64>; 3],
    real_rhs: DVector<f64>,
    complex_rhs: DVector<Complex<f64>>,
    /// The last correction of the third stage's increment, Z₃ (the step's end, c₃ = 1), in the
    /// iteration that converged (`end_slope`).
    end_correction: Vec<f64>,
    /// The quintic through the last three step ends, and the components it serves (boxed, so
    /// that the implicit integrator's two stiff methods take about the same room).
    dense: Box<Hermite>,
}

impl Radau5 {
    pub(super) fn new(dimension: usize, settings: &Settings) -> Self {
        let zeros = vec![0.0; dimension];
        let triple = || [zeros.clone(), zeros.clone(), zeros.clone()];
        let rtol = settings.rtol.max(f64::EPSILON);
        Radau5 {
            rtol: settings.rtol,
            atol: settings.atol,
            controlled: settings.controlled_len(dimension),
            newton_tolerance: (10.0 * f64::EPSILON / rtol).max(0.03f64.min(rtol.sqrt())),
            predicted: zeros.clone(),
            predicted_derivative: zeros.clone(),
            derivative: zeros.clone(),
            end_derivative: zeros.clone(),
            derivative_evaluated: false,
            jacobian: None,
            fresh: false,
            stale: true,
            factors: None,
            increments: triple(),
            collocation: None,
            contraction: 1.0,
            rate: 0.0,
            newton_limit: f64::INFINITY,
            rejected: false,
            first: true,
            stage_state: zeros.clone(),
            stage_derivatives: triple(),
            transformed: triple(),
            transformed_derivatives: triple(),
            real_rhs: DVector::zeros(dimension),
            complex_rhs: DVector::zeros(dimension),
            end_correction: zeros.clone(),
            dense: Box::new(Hermite::new(dimension)),
        }
    }

    /// Takes `derivative` as dy/dt at the current point (computed by another method); the
    /// Jacobian and the first guess are formed anew.
    pub(super) fn adopt(&mut self, derivative: &[f64]) {
        self.derivative.copy_from_slice(derivative);
        self.derivative_evaluated = true;
        self.restart();
    }

    fn restart(&mut self) {
        // The last rate belongs to another point (or to none): the first iteration is judged on
        // its correction alone. With 0 there (as before), the first step after dopri5 handed
        // over took the first iterate as converged, and its error (in the fast transient, up to
        // 1e4 times the tolerance in the end slope) stayed in the slow motion: on the governor
        // the position error at 1e-8 was 1.6e-10, now 6.8e-11, at 1.5e-9 2.4e-11, now 5.2e-12.
        self.contraction = 1.0;
        self.newton_limit = f64::INFINITY;
        self.stale = true;
        self.fresh = false;
        self.collocation = None;
        self.dense.forget();
    }

    /// Whether the spectral radius of the Jacobian last formed is below `limit` (`false` before
    /// the first); the bound |trace| / n ≤ ρ says no without the eigenvalues where the stiff
    /// eigenvalues make the trace.
    pub(super) fn spectral_radius_below(&self, limit: f64) -> bool {
        let Some(jacobian) = &self.jacobian else {
            return false;
        };
        let m = jacobian.nrows();
        if m > 0 && jacobian.trace().abs() / m as f64 >= limit {
            return false;
        }
        super::rosenbrock::spectral_radius(jacobian) < limit
    }

    /// Forms the Jacobian for the step of size `h` from (t, y): at `JACOBIAN_NODE` of the step
    /// on the last step's polynomial, at (t, y) where there is none.
    fn form_jacobian(
        &mut self,
        eval: &mut Evaluator,
        t: f64,
        y: &[f64],
        h: f64,
    ) -> Result<(), Halt> {
        eval.stats.jacobian_evaluations += 1;
        let n = y.len();
        let columns = match &self.collocation {
            Some(previous) => {
                let at = t + JACOBIAN_NODE * h;
                previous.evaluate(at, &mut self.predicted);
                previous.slope(at, &mut self.predicted_derivative);
                leading_columns(
                    eval,
                    at,
                    &self.predicted,
                    (&mut self.predicted_derivative, &mut false),
                    self.controlled,
                    &mut self.stage_state,
                )?
            }
            None => leading_columns(
                eval,
                t,
                y,
                (&mut self.derivative, &mut self.derivative_evaluated),
                self.controlled,
                &mut self.stage_state,
            )?,
        };
        // The components past the controlled ones (a quadrature) do not act on f.
        let mut jacobian = DMatrix::zeros(n, n);
        jacobian.columns_mut(0, self.controlled).copy_from(&columns);
        self.jacobian = Some(jacobian);
        self.fresh = true;
        self.stale = false;
        self.factors = None;
        Ok(())
    }

    /// The matrices γ/h − J and (α + iβ)/h − J factored for `h`, or `None` when singular.
    fn factor(&mut self, eval: &mut Evaluator, h: f64) -> bool {
        if matches!(&self.factors, Some(f) if f.step == h) {
            return true;
        }
        eval.stats.lu_decompositions += 1;
        let jacobian = self.jacobian.as_ref().expect("formed before factoring");
        let n = jacobian.nrows();
        let mut real = -jacobian;
        let mut complex = jacobian.map(|x| Complex::new(-x, 0.0));
        let shift = complex_eigenvalue() / h;
        for i in 0..n {
            real[(i, i)] += real_eigenvalue() / h;
            complex[(i, i)] += shift;
        }
        let (real, complex) = (real.lu(), complex.lu());
        let invertible = real.is_invertible() && complex.is_invertible();
        self.factors = invertible.then_some(Factors {
            step: h,
            real,
            complex,
        });
        invertible
    }

    /// The first guess of the stage increments: the last step's polynomial carried on, or zero.
    fn guess(&mut self, t: f64, y: &[f64], h: f64) {
        for (stage, node) in NODES.iter().enumerate() {
            let z = &mut self.increments[stage];
            match &self.collocation {
                Some(previous) => {
                    previous.evaluate(t + node * h, z);
                    z.iter_mut().zip(y).for_each(|(z, y)| *z -= y);
                }
                None => z.fill(0.0),
            }
        }
    }

    /// The scaled root-mean-square of the controlled components of the correction, the real
    /// system's solution and the real and imaginary parts of the complex one's.
    fn correction_size(&self, y: &[f64]) -> f64 {
        let m = self.controlled;
        let sum: f64 = (0..m)
            .map(|i| {
                let (real, complex) = (self.real_rhs[i], self.complex_rhs[i]);
                let squares = real * real + complex.re * complex.re + complex.im * complex.im;
                squares / (self.atol + self.rtol * y[i].abs()).powi(2)
            })
            .sum();
        (sum / (3 * m).max(1) as f64).sqrt()
    }

    /// Solves the collocation equations from the guess in `increments`.
    fn iterate(&mut self, eval: &mut Evaluator, t: f64, y: &[f64], h: f64) -> Result<Newton, Halt> {
        let factors = self.factors.take().expect("factored before iterating");
        let outcome = self.iterate_with(&factors, eval, t, y, h);
        self.factors = Some(factors);
        outcome
    }

    fn iterate_with(
        &mut self,
        factors: &Factors,
        eval: &mut Evaluator,
        t: f64,
        y: &[f64],
        h: f64,
    ) -> Result<Newton, Halt> {
        transform_into(&TRANSFORM_INVERSE, &self.increments, &mut self.transformed);
        let mut contraction = self.contraction.max(f64::EPSILON).powf(0.8);
        let mut previous: Option<f64> = None;
        // The last ratio of successive corrections' sizes.
        let mut last_ratio = 0.0;
        for iteration in 0..NEWTON_ITERATIONS {
            self.stage_derivatives_at(eval, t, y, h)?;
            self.solve_correction(factors, h);
            let size = self.correction_size(y);
            if let Some(before) = previous {
                // The rate θ: from the third iteration on the geometric mean of the last two
                // ratios, as RADAU5 takes it. The ratios alternate (on the governor 0.11,
                // 0.006, 0.09, 0.01 with a fresh Jacobian, the complex pair's and the real
                // eigenvalue's parts converging unevenly), and the last one alone
                // overstates or understates what is left.
                let ratio = size / before;
                let theta = match iteration {
                    1 => ratio,
                    _ => (ratio * last_ratio).sqrt(),
                };
                last_ratio = ratio;
                self.rate = theta;
                if theta >= 0.99 {
                    return Ok(Newton::Failed);
                }
                contraction = theta / (1.0 - theta);
                if iteration >= 2 && self.hopeless(size, theta, iteration) {
                    return Ok(Newton::Failed);
                }
            }
            self.apply_correction();
            if !self.increments.iter().all(|z| all_finite(z)) {
                return Ok(Newton::Failed);
            }
            if contraction * size <= self.newton_tolerance {
                self.keep_end_correction();
                self.contraction = contraction;
                return Ok(Newton::Converged);
            }
            previous = Some(size);
        }
        Ok(Newton::Failed)
    }

    /// f at the three stages y + Z_i, into `stage_derivatives`.
    fn stage_derivatives_at(
        &mut self,
        eval: &mut Evaluator,
        t: f64,
        y: &[f64],
        h: f64,
    ) -> Result<(), Halt> {
        for (stage, node) in NODES.iter().enumerate() {
            for ((state, y), z) in self
                .stage_state
                .iter_mut()
                .zip(y)
                .zip(&self.increments[stage])
            {
                *state = y + z;
            }
            eval.rhs(
                t + node * h,
                &self.stage_state,
                &mut self.stage_derivatives[stage],
            )?;
        }
        Ok(())
    }

    /// The Newton correction of W: the real system's solution into `real_rhs`, the complex
    /// one's into `complex_rhs`.
    fn solve_correction(&mut self, factors: &Factors, h: f64) {
        transform_into(
            &TRANSFORM_INVERSE,
            &self.stage_derivatives,
            &mut self.transformed_derivatives,
        );
        let gamma = real_eigenvalue() / h;
        let sigma = complex_eigenvalue() / h;
        let [f0, f1, f2] = &self.transformed_derivatives;
        let [w0, w1, w2] = &self.transformed;
        for i in 0..f0.len() {
            self.real_rhs[i] = f0[i] - gamma * w0[i];
            self.complex_rhs[i] = Complex::new(f1[i], f2[i]) - sigma * Complex::new(w1[i], w2[i]);
        }
        factors.real.solve_mut(&mut self.real_rhs);
        factors.complex.solve_mut(&mut self.complex_rhs);
    }

    /// The correction of Z₃ just applied: row 3 of T is (1, 1, 0), so it is the real system's
    /// solution plus the real part of the complex one's.
    fn keep_end_correction(&mut self) {
        for (i, correction) in self.end_correction.iter_mut().enumerate() {
            *correction = self.real_rhs[i] + self.complex_rhs[i].re;
        }
    }

    /// f at the step's end y + Z₃ into `end_derivative`, without evaluating it: the last
    /// iteration evaluated f at y + Z₃ − δ (the third stage, before its last correction δ), and
    /// f(y + Z₃) = f(y + Z₃ − δ) + J δ up to (J − ∂f/∂y) δ and second order in δ, which the
    /// iteration's stopping test keeps small. On the governor at 1e-8 the two differ by at most
    /// 0.3 of the tolerance's scale on most steps (more on the first steps of the fast
    /// transient); on a mechanism the coordinates' slopes (the rates, linear in y) are exact.
    /// One evaluation of f saved per step, of about 15.
    fn end_slope(&mut self) {
        let jacobian = self.jacobian.as_ref().expect("formed before a step");
        let stage = &self.stage_derivatives[2];
        for (i, slope) in self.end_derivative.iter_mut().enumerate() {
            let row = jacobian.row(i);
            let change: f64 = row
                .iter()
                .zip(&self.end_correction)
                .map(|(j, d)| j * d)
                .sum();
            *slope = stage[i] + change;
        }
    }

    /// W plus the correction, and Z = T W.
    fn apply_correction(&mut self) {
        let [w0, w1, w2] = &mut self.transformed;
        for i in 0..w0.len() {
            let complex = self.complex_rhs[i];
            w0[i] += self.real_rhs[i];
            w1[i] += complex.re;
            w2[i] += complex.im;
        }
        transform_into(&TRANSFORM, &self.transformed, &mut self.increments);
    }

    /// Whether the iteration, at its correction `size` after `iteration` iterations and rate
    /// θ, cannot reach the threshold within the iterations left if it goes on at that rate
    /// (RADAU5's test). Not asked of the first rate (`iteration` 1), which overstates the
    /// rest: the first correction carries the first guess's error, and on the governor the
    /// next corrections shrink faster than at a fixed rate (sizes 2.43, 0.49, then about 0.02:
    /// the rates 0.2 and 0.04 with a fresh Jacobian). Judged on the first rate, 63 of 336
    /// attempts failed at 1e-6 and the failures held the steps to 0.7 of the failed ones.
    fn hopeless(&self, size: f64, theta: f64, iteration: usize) -> bool {
        let remaining = (NEWTON_ITERATIONS - 1 - iteration) as i32;
        theta / (1.0 - theta) * size * theta.powi(remaining) > self.newton_tolerance
    }

    /// The error estimate (γ/h − J)⁻¹ (f₀ + Σ e_i Z_i / h) into `real_rhs`, f₀ = f(t, y) or,
    /// for a second estimate after a rejection, f at y plus the first estimate.
    fn error_estimate(&mut self, h: f64, f0: &[f64]) {
        let [z0, z1, z2] = &self.increments;
        for (i, f0) in f0.iter().enumerate() {
            let weighted =
                ERROR_WEIGHTS[0] * z0[i] + ERROR_WEIGHTS[1] * z1[i] + ERROR_WEIGHTS[2] * z2[i];
            self.real_rhs[i] = f0 + weighted / h;
        }
        let factors = self.factors.as_ref().expect("factored before estimating");
        factors.real.solve_mut(&mut self.real_rhs);
    }

    /// The error norm of the estimate in `real_rhs`, over the controlled components.
    fn estimate_norm(&self, y: &[f64], y_new: &[f64]) -> f64 {
        let m = self.controlled;
        error_norm(
            &self.real_rhs.as_slice()[..m],
            &y[..m],
            &y_new[..m],
            self.rtol,
            self.atol,
        )
    }

    /// Attempts the step with the Jacobian as it is.
    fn attempt_with_jacobian(
        &mut self,
        eval: &mut Evaluator,
        t: f64,
        y: &[f64],
        h: f64,
    ) -> Result<bool, Halt> {
        if !self.factor(eval, h) {
            return Ok(false);
        }
        self.guess(t, y, h);
        Ok(matches!(self.iterate(eval, t, y, h)?, Newton::Converged))
    }
}

/// out_i = Σ_j m[i][j] v_j for i = 0, 1, 2.
fn transform_into(m: &[[f64; 3]; 3], v: &[Vec<f64>; 3], out: &mut [Vec<f64>; 3]) {
    for (row, out) in m.iter().zip(out.iter_mut()) {
        for (k, out) in out.iter_mut().enumerate() {
            *out = row[0] * v[0][k] + row[1] * v[1][k] + row[2] * v[2][k];
        }
    }
}

impl AdaptiveStepper for Radau5 {
    fn order(&self) -> u32 {
        5
    }

    fn step_limit(&self) -> f64 {
        self.newton_limit
    }

    fn controller(&self) -> StepController {
        // The estimate is of order 3; RADAU5's growth limit of 8.
        StepController::new(3, Gains::elementary(8.0))
    }

    fn start(&mut self, eval: &mut Evaluator, t: f64, y: &[f64]) -> Result<(), Halt> {
        self.restart();
        self.derivative_evaluated = true;
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
        if self.jacobian.is_none() || (self.stale && !self.fresh) {
            self.form_jacobian(eval, t, y, h)?;
        }
        let after_rejection = self.rejected;
        // Until the attempt's error says otherwise.
        self.rejected = true;
        let mut converged = self.attempt_with_jacobian(eval, t, y, h)?;
        if !converged && !self.fresh {
            // A Jacobian from an earlier point may be what slows the iteration.
            self.form_jacobian(eval, t, y, h)?;
            converged = self.attempt_with_jacobian(eval, t, y, h)?;
        }
        if !converged {
            self.newton_limit = NEWTON_LIMIT * h;
            return Ok(NEWTON_FAILED);
        }
        for i in 0..y.len() {
            y_new[i] = y[i] + self.increments[2][i];
        }
        let derivative = std::mem::take(&mut self.derivative);
        self.error_estimate(h, &derivative);
        self.derivative = derivative;
        let mut error = self.estimate_norm(y, y_new);
        if error > 1.0 && (self.first || after_rejection) {
            // Hairer and Wanner's second estimate, which damps the stiff components' part of
            // the first (too pessimistic on them) by one more solve.
            for ((state, y), e) in self.stage_state.iter_mut().zip(y).zip(&self.real_rhs) {
                *state = y + e;
            }
            let mut f = std::mem::take(&mut self.end_derivative);
            let evaluated = eval.rhs(t, &self.stage_state, &mut f);
            if evaluated.is_ok() {
                self.error_estimate(h, &f);
                error = self.estimate_norm(y, y_new);
            }
            self.end_derivative = f;
            evaluated?;
        }
        if error <= 1.0 {
            self.end_slope();
        }
        self.rejected = error.is_nan() || error > 1.0;
        Ok(error)
    }

    fn accept(&mut self, t: f64, y: &[f64], h: f64, y_new: &[f64]) {
        let mut collocation = self
            .collocation
            .take()
            .unwrap_or_else(|| Collocation::new(y.len()));
        collocation.fill(t, y, h, &self.increments);
        let jacobian = self.jacobian.as_ref().expect("formed before a step");
        self.dense.add_step(
            jacobian,
            (t, y, &self.derivative),
            (h, y_new, &self.end_derivative),
        );
        self.collocation = Some(collocation);
        std::mem::swap(&mut self.derivative, &mut self.end_derivative);
        self.derivative_evaluated = false;
        self.stale = self.rate > JACOBIAN_RATE;
        self.newton_limit *= NEWTON_LIMIT_GROWTH;
        self.fresh = false;
        self.rate = 0.0;
        self.first = false;
        self.rejected = false;
    }

    fn interpolate(&self, t: f64, out: &mut [f64]) {
        if let Some(collocation) = &self.collocation {
            collocation.evaluate(t, out);
            self.dense.evaluate(t, out);
        }
    }
}
