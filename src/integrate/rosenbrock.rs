//! Two Rosenbrock methods, both stiffly accurate and L-stable, stepping through one code
//! ([`Scheme`]):
//! - ROS34PW2, a Rosenbrock-W method of order 3 with four stages and an embedded order-2 error
//!   estimate (J. Rang and L. Angermann, "New Rosenbrock W-methods of order 3 for partial
//!   differential algebraic equations of index 1", BIT Numer. Math. 45, 2005);
//! - RODAS4, of order 4 with six stages and an embedded order-3 estimate (Hairer and Wanner,
//!   *Solving ODEs II*, VI.4), the stiff method of the implicit integrator: at equal error on a
//!   stiff flyball governor it takes about a quarter of ROS34PW2's time (`BENCHMARKS.md`).
//!
//! Each stage solves a linear system with W = I / (h γ) − J instead of iterating Newton's method.
//! A *W*-method keeps its order whatever the matrix J is (Hairer and Wanner, *Solving ODEs II*,
//! IV.7): J only decides how stiff a problem the steps stay stable on. So ROS34PW2 does not form
//! J at every step but keeps it across steps, and forms it again after a step is rejected with a
//! Jacobian formed at an earlier point, or after `JACOBIAN_AGE` accepted steps; only the small
//! factorisation that depends on h is redone at each attempt. RODAS4's order needs the Jacobian
//! at each step's start: it forms J at every step.
//!
//! J is kept as the product U Tᵀ of its action U = J T on a basis T of the directions the state
//! moves along ([`OdeSystem::tangent_basis`](super::OdeSystem::tangent_basis)): on a mechanism with loops, the allowed motions of
//! positions and velocities, 2 columns for a mechanism of mobility 1 whatever its size. Each
//! column of U is one forward difference of f along that direction, and W is solved through the
//! m × m matrix I / (h γ) − TᵀU (Sherman–Morrison–Woodbury): what is left out is the Jacobian
//! across the constraint manifold, along which the projection after each step, not the dynamics,
//! decides the motion. A system without such a basis gives its Jacobian itself
//! ([`OdeSystem::jacobian`](super::OdeSystem::jacobian)), or is differentiated along each of
//! the components the error control watches (a full Jacobian of those).
//!
//! Dense output is the cubic Hermite interpolant through the step's ends, whose end slope is free
//! because it is the next step's first stage.

use std::cell::Cell;

use nalgebra::{DMatrix, DVector, Dyn, LU};

use super::control::{error_norm, Gains, StepController};
use super::driver::AdaptiveStepper;
use super::evaluator::{all_finite, Evaluator, Halt};
use super::hermite::HermiteSegment;
use super::jacobian::{leading_columns, orthonormal};
use super::settings::Settings;

/// ROS34PW2's number of stages.
pub const STAGES: usize = 4;

/// The diagonal of Γ, the same for every stage so that one factorisation serves all of them.
pub const GAMMA: f64 = 4.358_665_215_084_59e-1;

/// The method in its standard form (Hairer and Wanner, IV.7, (7.4)):
///   (I − h γ J) k_i = h f(t + α_i h, y + Σ_j α_ij k_j) + h J Σ_{j<i} γ_ij k_j + γ_i h² ∂f/∂t,
///   y₁ = y + Σ b_i k_i, with α_i = Σ_j α_ij and γ_i = Σ_j γ_ij (diagonal included).
/// The weights α_ij of earlier stages in each stage's state.
pub const ALPHA: [[f64; STAGES]; STAGES] = [
    [0.0; 4],
    [8.717_330_430_169_18e-1, 0.0, 0.0, 0.0],
    [
        8.445_706_001_536_942e-1,
        -1.129_906_423_648_418_5e-1,
        0.0,
        0.0,
    ],
    [0.0, 0.0, 1.0, 0.0],
];
/// Γ, lower triangular with γ on its diagonal.
pub const GAMMA_MATRIX: [[f64; STAGES]; STAGES] = [
    [GAMMA, 0.0, 0.0, 0.0],
    [-8.717_330_430_169_18e-1, GAMMA, 0.0, 0.0],
    [
        -9.033_805_701_304_408e-1,
        5.418_067_238_809_533e-2,
        GAMMA,
        0.0,
    ],
    [
        2.421_238_070_609_534_6e-1,
        -1.223_250_583_904_514_7,
        5.452_602_553_351_021e-1,
        GAMMA,
    ],
];
/// Weights of the order-3 solution.
pub const B: [f64; STAGES] = [
    2.421_238_070_609_534_6e-1,
    -1.223_250_583_904_514_7,
    1.545_260_255_335_102,
    GAMMA,
];
/// Weights of the embedded order-2 solution.
pub const B_EMBEDDED: [f64; STAGES] = [
    3.781_090_314_581_937e-1,
    -9.604_229_221_242_318e-2,
    0.5,
    2.179_332_607_542_295e-1,
];

/// The most accepted steps a Jacobian serves before it is formed again. A W-method needs no
/// exact Jacobian for its order, but the stiff components' damping depends on how close it is:
/// on a flyball governor, whose stiff springs turn with the arms, a Jacobian kept 3 steps
/// tripled the steps (and rejected a third of them) against one formed at every step. So how
/// many steps one serves adapts to how much it changed between two formations
/// (`REUSE_CHANGE`): from one, doubling while it changes little, up to this.
const JACOBIAN_AGE: usize = 32;

/// A method's coefficients in the transformed form where the unknowns are u_i = Σ_j γ_ij k_j
/// (Hairer and Wanner, IV.7, (7.25)), which needs no product with J:
///   (I / (h γ) − J) u_i = f(t + α_i h, y + Σ_j a_ij u_j) + Σ_j c_ij u_j / h + γ_i h ∂f/∂t,
///   y₁ = y + Σ m_i u_i.
#[derive(Clone, Debug)]
pub struct Transformed {
    /// The diagonal γ of Γ, the same for every stage.
    pub diagonal: f64,
    /// a = α Γ⁻¹ (row i: the weights of the earlier stages in stage i's state).
    pub a: Vec<Vec<f64>>,
    /// c = diag(1/γ) − Γ⁻¹ (row i: the weights of the earlier stages in stage i's equation).
    pub c: Vec<Vec<f64>>,
    /// m = bᵀ Γ⁻¹.
    pub m: Vec<f64>,
    /// The weights of the error estimate: (b − b̂)ᵀ Γ⁻¹.
    pub e: Vec<f64>,
    /// Fractions of the step at which the stages evaluate f (row sums of α).
    pub alpha: Vec<f64>,
    /// Weights of h ∂f/∂t in each stage (row sums of Γ).
    pub gamma: Vec<f64>,
}

impl Transformed {
    /// ROS34PW2's coefficients, transformed from its standard form above.
    #[allow(clippy::needless_range_loop)]
    pub fn new() -> Transformed {
        // Γ⁻¹ by forward substitution, column by column.
        let mut inverse = [[0.0; STAGES]; STAGES];
        for column in 0..STAGES {
            for i in 0..STAGES {
                let identity = if i == column { 1.0 } else { 0.0 };
                let known: f64 = (0..i)
                    .map(|j| GAMMA_MATRIX[i][j] * inverse[j][column])
                    .sum();
                inverse[i][column] = (identity - known) / GAMMA_MATRIX[i][i];
            }
        }
        let times = |row: &[f64; STAGES], j: usize| -> f64 {
            (0..STAGES).map(|k| row[k] * inverse[k][j]).sum()
        };
        let difference: [f64; STAGES] = std::array::from_fn(|i| B[i] - B_EMBEDDED[i]);
        Transformed {
            diagonal: GAMMA,
            a: (0..STAGES)
                .map(|i| (0..STAGES).map(|j| times(&ALPHA[i], j)).collect())
                .collect(),
            c: (0..STAGES)
                .map(|i| {
                    (0..STAGES)
                        .map(|j| {
                            let diagonal = if i == j {
                                1.0 / GAMMA_MATRIX[i][i]
                            } else {
                                0.0
                            };
                            diagonal - inverse[i][j]
                        })
                        .collect()
                })
                .collect(),
            m: (0..STAGES).map(|j| times(&B, j)).collect(),
            e: (0..STAGES).map(|j| times(&difference, j)).collect(),
            alpha: ALPHA.iter().map(|row| row.iter().sum()).collect(),
            gamma: GAMMA_MATRIX.iter().map(|row| row.iter().sum()).collect(),
        }
    }

    /// RODAS4 (Hairer and Wanner, *Solving ODEs II*, VI.4, Table 4.3; their code `rodas.f`,
    /// METH = 1), published in this transformed form: order 4, six stages, stiffly accurate
    /// and L-stable, with an embedded solution of order 3 (the fifth stage's state, itself
    /// stiffly accurate), so that the error estimate is the last stage's unknown u₆.
    pub fn rodas4() -> Transformed {
        let a5 = [
            1.221_224_509_226_641,
            6.019_134_481_288_629,
            12.537_083_329_320_87,
            -0.687_886_036_105_895,
        ];
        let a = vec![
            vec![],
            vec![1.544],
            vec![0.946_678_528_081_582_6, 0.255_701_169_898_328_4],
            vec![
                3.314_825_187_068_521,
                2.896_124_015_972_201,
                0.998_641_913_997_781_7,
            ],
            a5.to_vec(),
            [&a5[..], &[1.0]].concat(),
        ];
        let c = vec![
            vec![],
            vec![-5.6688],
            vec![-2.430_093_356_833_875, -0.206_359_915_709_191_5],
            vec![
                -0.107_352_905_815_137_5,
                -9.594_562_251_023_355,
                -20.470_286_148_096_16,
            ],
            vec![
                7.496_443_313_967_647,
                -10.246_804_314_643_52,
                -33.999_903_528_199_05,
                11.708_908_932_061_6,
            ],
            vec![
                8.083_246_795_921_522,
                -7.981_132_988_064_893,
                -31.521_594_328_743_71,
                16.319_305_431_231_36,
                -6.058_818_238_834_054,
            ],
        ];
        Transformed {
            diagonal: 0.25,
            m: [&a5[..], &[1.0, 1.0]].concat(),
            e: vec![0.0, 0.0, 0.0, 0.0, 0.0, 1.0],
            alpha: vec![0.0, 0.386, 0.21, 0.63, 1.0, 1.0],
            gamma: vec![0.25, -0.1043, 0.1035, -0.036_200_000_000_000_23, 0.0, 0.0],
            a,
            c,
        }
    }

    fn stages(&self) -> usize {
        self.m.len()
    }
}

impl Default for Transformed {
    fn default() -> Self {
        Transformed::new()
    }
}

/// The change of J T between two formations, times the step (h ‖ΔJ T‖, which is what enters the
/// stages' increments), below which the next one serves twice as many steps; above it, one. On
/// the governor a change of 1 % of J (h ‖ΔJ‖ about 1) already doubled the steps.
const REUSE_CHANGE: f64 = 0.05;

type Lu = LU<f64, Dyn, Dyn>;

/// The directions the Jacobian is known along: the leading components one by one, or the
/// orthonormal columns of a basis.
#[derive(Clone, Debug)]
enum Directions {
    Leading(usize),
    Basis(DMatrix<f64>),
}

impl Directions {
    /// Tᵀ x.
    fn project(&self, x: &[f64]) -> DVector<f64> {
        match self {
            Directions::Leading(count) => DVector::from_column_slice(&x[..*count]),
            Directions::Basis(basis) => basis.tr_mul(&DVector::from_column_slice(x)),
        }
    }
}

/// J ≈ U Tᵀ, ∂f/∂t, and the factorisation of I / (h γ) − TᵀU for the step it was taken at.
struct Jacobian {
    directions: Directions,
    /// U = J T.
    image: DMatrix<f64>,
    /// TᵀU.
    reduced: DMatrix<f64>,
    time_derivative: Vec<f64>,
    /// The spectral radius of U Tᵀ (that of TᵀU): how fast its stiffest component moves;
    /// computed when first asked for.
    spectral_radius: Cell<Option<f64>>,
    /// Whether it was formed at the current point of the solution.
    fresh: bool,
    /// Accepted steps since it was formed.
    age: usize,
    factor: Option<(f64, Lu)>,
}

/// Which Rosenbrock method steps.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Scheme {
    /// ROS34PW2: order 3, a W-method, its Jacobian kept across steps.
    Ros34pw2,
    /// RODAS4: order 4, its Jacobian formed at every step (its order needs the exact one).
    Rodas4,
}

pub(super) struct RosenbrockW {
    scheme: Scheme,
    coefficients: Transformed,
    rtol: f64,
    /// Components of the state the error control watches (the leading ones).
    controlled: usize,
    atol: f64,
    /// dy/dt at the current point.
    derivative: Vec<f64>,
    jacobian: Option<Jacobian>,
    /// How many accepted steps the current Jacobian serves.
    reuse: usize,
    /// Whether the last attempt was rejected.
    rejected: bool,
    increments: Vec<DVector<f64>>,
    stage_state: Vec<f64>,
    stage_derivative: Vec<f64>,
    /// dy/dt at the end of the last attempt, evaluated only when the attempt is acceptable.
    end_derivative: Vec<f64>,
    error: Vec<f64>,
    segment: HermiteSegment,
}

impl RosenbrockW {
    pub(super) fn new(scheme: Scheme, dimension: usize, settings: &Settings) -> Self {
        let zeros = vec![0.0; dimension];
        let coefficients = match scheme {
            Scheme::Ros34pw2 => Transformed::new(),
            Scheme::Rodas4 => Transformed::rodas4(),
        };
        RosenbrockW {
            scheme,
            increments: vec![DVector::zeros(dimension); coefficients.stages()],
            coefficients,
            rtol: settings.rtol,
            controlled: settings.controlled_len(dimension),
            atol: settings.atol,
            derivative: zeros.clone(),
            jacobian: None,
            reuse: 1,
            rejected: false,
            stage_state: zeros.clone(),
            stage_derivative: zeros.clone(),
            end_derivative: zeros.clone(),
            error: zeros,
            segment: HermiteSegment::new(dimension),
        }
    }

    /// J T and ∂f/∂t at the current point: J from the system when it gives it, by forward
    /// differences otherwise ([`RosenbrockW::differenced_image`]); ∂f/∂t zero when f does not
    /// depend on t, a forward difference otherwise.
    fn form_jacobian(
        &mut self,
        eval: &mut Evaluator,
        t: f64,
        y: &[f64],
        h: f64,
    ) -> Result<(), Halt> {
        eval.stats.jacobian_evaluations += 1;
        let n = y.len();
        let directions = match eval.tangent_basis(t, y)? {
            Some(spanning) => Directions::Basis(orthonormal(spanning, n)),
            None => Directions::Leading(self.controlled),
        };
        let image = match &directions {
            Directions::Leading(count) => {
                let slope = (self.derivative.as_mut_slice(), &mut true);
                leading_columns(eval, t, y, slope, *count, &mut self.stage_derivative)?
            }
            Directions::Basis(basis) => self.differenced_image(eval, t, y, basis)?,
        };
        let time_derivative = match eval.autonomous() {
            true => vec![0.0; n],
            false => {
                let dt = (t + (f64::EPSILON * t.abs().max(1e-5)).sqrt()) - t;
                eval.rhs(t + dt, y, &mut self.stage_derivative)?;
                (0..n)
                    .map(|i| (self.stage_derivative[i] - self.derivative[i]) / dt)
                    .collect()
            }
        };
        let reduced = match &directions {
            Directions::Leading(count) => image.rows(0, *count).into_owned(),
            Directions::Basis(basis) => basis.tr_mul(&image),
        };
        if let Some(old) = &self.jacobian {
            self.reuse = match h * change(old, &directions, &image) < REUSE_CHANGE {
                true => (2 * self.reuse).min(JACOBIAN_AGE),
                false => 1,
            };
        }
        self.jacobian = Some(Jacobian {
            directions,
            image,
            reduced,
            time_derivative,
            spectral_radius: Cell::new(None),
            fresh: true,
            age: 0,
            factor: None,
        });
        Ok(())
    }

    /// U = J T by forward differences of f along the basis's columns, with increments that
    /// balance truncation against rounding (as in Hairer and Wanner's RODAS).
    fn differenced_image(
        &mut self,
        eval: &mut Evaluator,
        t: f64,
        y: &[f64],
        basis: &DMatrix<f64>,
    ) -> Result<DMatrix<f64>, Halt> {
        let n = y.len();
        let mut image = DMatrix::zeros(n, basis.ncols());
        let mut perturbed = y.to_vec();
        for (j, direction) in basis.column_iter().enumerate() {
            let size: f64 = (0..n).map(|i| (direction[i] * y[i]).abs()).sum();
            let delta = (f64::EPSILON * size.max(1e-5)).sqrt();
            for i in 0..n {
                perturbed[i] = y[i] + delta * direction[i];
            }
            eval.rhs(t, &perturbed, &mut self.stage_derivative)?;
            for i in 0..n {
                image[(i, j)] = (self.stage_derivative[i] - self.derivative[i]) / delta;
            }
        }
        Ok(image)
    }

    /// How many accepted steps the current Jacobian serves: ROS34PW2 keeps its order with any
    /// matrix, RODAS4 needs the Jacobian at the step's start.
    fn steps_per_jacobian(&self) -> usize {
        match self.scheme {
            Scheme::Ros34pw2 => self.reuse,
            Scheme::Rodas4 => 1,
        }
    }

    /// Whether the spectral radius ρ of the Jacobian last formed is below `limit` (`false`
    /// before the first). The bound |trace| / m ≤ ρ, m the Jacobian's order, says no without
    /// the eigenvalues on a stiff stretch, where the dominant eigenvalues make the trace.
    pub(super) fn spectral_radius_below(&self, limit: f64) -> bool {
        let Some(jacobian) = &self.jacobian else {
            return false;
        };
        let m = jacobian.reduced.nrows();
        if m > 0 && jacobian.reduced.trace().abs() / m as f64 >= limit {
            return false;
        }
        jacobian.spectral_radius() < limit
    }

    /// Takes `derivative` as dy/dt at the current point (computed by another method), and
    /// forms the Jacobian anew at the next attempt.
    pub(super) fn adopt(&mut self, derivative: &[f64]) {
        self.derivative.copy_from_slice(derivative);
        if let Some(jacobian) = &mut self.jacobian {
            jacobian.fresh = false;
            jacobian.age = usize::MAX;
        }
    }

    /// Solves the stage's equation for its increment, in place.
    fn solve_w(jacobian: &Jacobian, lu: &Lu, c: f64, rhs: &mut DVector<f64>) {
        // (cI − U Tᵀ)⁻¹ b = (b + U (cI − TᵀU)⁻¹ Tᵀ b) / c, with c = 1 / (h γ).
        if jacobian.reduced.nrows() > 0 {
            let mut s = jacobian.directions.project(rhs.as_slice());
            lu.solve_mut(&mut s);
            rhs.gemv(1.0, &jacobian.image, &s, 1.0);
        }
        *rhs /= c;
    }

    /// Solves for the increment of one stage.
    #[allow(clippy::too_many_arguments)]
    fn solve_stage(
        &mut self,
        eval: &mut Evaluator,
        jacobian: &Jacobian,
        lu: &Lu,
        stage: usize,
        t: f64,
        y: &[f64],
        h: f64,
    ) -> Result<(), Halt> {
        let k = &self.coefficients;
        if stage == 0 {
            self.stage_derivative.copy_from_slice(&self.derivative);
        } else {
            for (i, state) in self.stage_state.iter_mut().enumerate() {
                *state = y[i]
                    + (0..stage)
                        .map(|j| k.a[stage][j] * self.increments[j][i])
                        .sum::<f64>();
            }
            eval.rhs(
                t + k.alpha[stage] * h,
                &self.stage_state,
                &mut self.stage_derivative,
            )?;
        }
        let mut rhs = DVector::from_fn(y.len(), |i, _| {
            let coupling: f64 = (0..stage)
                .map(|j| k.c[stage][j] * self.increments[j][i])
                .sum();
            self.stage_derivative[i]
                + coupling / h
                + k.gamma[stage] * h * jacobian.time_derivative[i]
        });
        Self::solve_w(jacobian, lu, 1.0 / (h * k.diagonal), &mut rhs);
        self.increments[stage] = rhs;
        Ok(())
    }
}

impl Jacobian {
    fn spectral_radius(&self) -> f64 {
        match self.spectral_radius.get() {
            Some(radius) => radius,
            None => {
                let radius = spectral_radius(&self.reduced);
                self.spectral_radius.set(Some(radius));
                radius
            }
        }
    }
}

/// The largest modulus of the eigenvalues of `matrix` (real Schur form), or its ∞-norm, which
/// bounds it, should the iterations not converge.
pub(super) fn spectral_radius(matrix: &DMatrix<f64>) -> f64 {
    if matrix.is_empty() {
        return 0.0;
    }
    match nalgebra::linalg::Schur::try_new(matrix.clone(), f64::EPSILON, 1000) {
        Some(schur) => schur
            .complex_eigenvalues()
            .iter()
            .map(|e| e.norm())
            .fold(0.0, f64::max),
        None => matrix
            .row_iter()
            .map(|r| r.iter().map(|x| x.abs()).sum::<f64>())
            .fold(0.0, f64::max),
    }
}

/// How much the Jacobian changed: ‖U − U₀ T₀ᵀ T‖ (Frobenius), with U = J T the new one's action
/// on its directions T and U₀ T₀ᵀ the old one.
fn change(old: &Jacobian, directions: &Directions, image: &DMatrix<f64>) -> f64 {
    let before = match (&old.directions, directions) {
        (Directions::Leading(a), Directions::Leading(b)) if a == b => old.image.clone(),
        (Directions::Basis(t0), Directions::Basis(t)) if t0.nrows() == t.nrows() => {
            &old.image * t0.tr_mul(t)
        }
        _ => return f64::INFINITY,
    };
    (image - before).norm()
}

impl AdaptiveStepper for RosenbrockW {
    fn order(&self) -> u32 {
        match self.scheme {
            Scheme::Ros34pw2 => 3,
            Scheme::Rodas4 => 4,
        }
    }

    fn controller(&self) -> StepController {
        // The estimate is the error of the order-2 solution. Elementary control with Hairer and
        // Wanner's growth limit for Rosenbrock methods.
        StepController::new(self.order() - 1, Gains::elementary(6.0))
    }

    fn start(&mut self, eval: &mut Evaluator, t: f64, y: &[f64]) -> Result<(), Halt> {
        if let Some(jacobian) = &mut self.jacobian {
            jacobian.fresh = false;
        }
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
        let stale = match &self.jacobian {
            None => true,
            Some(jacobian) => {
                (self.rejected && !jacobian.fresh) || jacobian.age >= self.steps_per_jacobian()
            }
        };
        if stale {
            self.form_jacobian(eval, t, y, h)?;
        }
        // Until the attempt's error says otherwise (a non-finite stage rejects it too).
        self.rejected = true;
        let mut jacobian = self.jacobian.take().expect("formed above");
        let factored = matches!(&jacobian.factor, Some((step, _)) if *step == h);
        if !factored {
            eval.stats.lu_decompositions += 1;
            let mut w = -&jacobian.reduced;
            for i in 0..w.nrows() {
                w[(i, i)] += 1.0 / (h * self.coefficients.diagonal);
            }
            let lu = w.lu();
            jacobian.factor = lu.is_invertible().then_some((h, lu));
        }
        let Some((_, lu)) = jacobian.factor.take() else {
            // A singular W is a property of this step size: reject it like a large error.
            self.jacobian = Some(jacobian);
            self.rejected = true;
            return Ok(f64::INFINITY);
        };
        let solved = (0..self.coefficients.stages())
            .try_for_each(|stage| self.solve_stage(eval, &jacobian, &lu, stage, t, y, h));
        jacobian.factor = Some((h, lu));
        self.jacobian = Some(jacobian);
        solved?;
        let k = &self.coefficients;
        for i in 0..y.len() {
            y_new[i] = y[i]
                + (0..k.stages())
                    .map(|s| k.m[s] * self.increments[s][i])
                    .sum::<f64>();
            self.error[i] = (0..k.stages())
                .map(|s| k.e[s] * self.increments[s][i])
                .sum::<f64>();
        }
        let error = error_norm(
            &self.error[..self.controlled],
            &y[..self.controlled],
            &y_new[..self.controlled],
            self.rtol,
            self.atol,
        );
        self.rejected = error.is_nan() || error > 1.0;
        if error <= 1.0 && all_finite(y_new) {
            eval.rhs(t + h, y_new, &mut self.end_derivative)?;
        }
        Ok(error)
    }

    fn accept(&mut self, t: f64, y: &[f64], h: f64, y_new: &[f64]) {
        self.segment
            .set(t, h, [y, &self.derivative, y_new, &self.end_derivative]);
        std::mem::swap(&mut self.derivative, &mut self.end_derivative);
        if let Some(jacobian) = &mut self.jacobian {
            jacobian.fresh = false;
            jacobian.age += 1;
        }
        self.rejected = false;
    }

    fn interpolate(&self, t: f64, out: &mut [f64]) {
        self.segment.evaluate(t, out);
    }
}
