//! Assembly: from the user's starting values, solve the closure equations for a consistent
//! configuration, keeping the `fixed` coordinates at their values (Levenberg–Marquardt on the
//! exact closure Jacobian; near the solution it takes Gauss–Newton steps and converges
//! quadratically).

use nalgebra::{DMatrix, DVector};

use super::closure::{closure, Closure};
use super::eval::EvalError;
use super::model::KinematicModel;
use crate::corrector::{correct, Acceptance, Correction, Damping, Progress, Settings, Stop};

#[derive(Clone, Debug)]
pub struct AssemblyOptions {
    /// Largest residual component accepted (metres for positions, ≈ radians for rotations).
    pub tolerance: f64,
    pub max_iterations: usize,
}

impl Default for AssemblyOptions {
    fn default() -> Self {
        AssemblyOptions {
            tolerance: 1e-12,
            max_iterations: 200,
        }
    }
}

#[derive(Clone, Debug)]
pub struct Assembled {
    pub q: Vec<f64>,
    pub iterations: usize,
    /// Largest residual component at the solution.
    pub residual: f64,
    /// The given values assembly had to change (empty from [`assemble`], which moves every
    /// coordinate not held).
    pub moved: Vec<Moved>,
}

/// How assembly treats a coordinate's starting value.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Hold {
    /// Marked `fixed`: never moved.
    Fixed,
    /// Given by the program: held when a closed configuration holding every given value exists,
    /// otherwise changed as little as possible, and reported.
    Given,
    /// Not given: a starting guess that assembly moves freely.
    Free,
}

/// Which coordinates are held (`fixed`).
pub fn held(holds: &[Hold]) -> Vec<bool> {
    holds.iter().map(|&h| h == Hold::Fixed).collect()
}

/// A given value that no closed configuration holds, and the value assembly chose for it.
#[derive(Clone, Debug, PartialEq)]
pub struct Moved {
    pub coordinate: usize,
    pub given: f64,
    pub assembled: f64,
}

#[derive(Clone, Debug)]
pub enum AssemblyError {
    Evaluation(EvalError),
    /// No configuration closes the loops from these starting values: the best found, and the
    /// position and rotation errors left in each loop.
    NoAssembly {
        q: Vec<f64>,
        loop_errors: Vec<(f64, f64)>,
    },
}

impl From<EvalError> for AssemblyError {
    fn from(e: EvalError) -> Self {
        AssemblyError::Evaluation(e)
    }
}

/// Solves the closure from `start`; if that stalls (a start on a stationary point, such as a
/// mechanism stretched flat), retries from a few deterministic perturbations of the free
/// coordinates before giving up.
pub fn assemble(
    model: &KinematicModel,
    start: &[f64],
    fixed: &[bool],
    options: &AssemblyOptions,
) -> Result<Assembled, AssemblyError> {
    let mut failure = match solve(model, start, fixed, options) {
        Ok(assembled) => return Ok(assembled),
        Err(e @ AssemblyError::Evaluation(_)) => return Err(e),
        Err(e) => e,
    };
    for attempt in 1..=RESTARTS {
        let perturbed: Vec<f64> = start
            .iter()
            .enumerate()
            .map(|(i, &x)| {
                if fixed[i] {
                    x
                } else {
                    x + 0.5 * jitter(attempt, i)
                }
            })
            .collect();
        match solve(model, &perturbed, fixed, options) {
            Ok(assembled) => return Ok(assembled),
            Err(e @ AssemblyError::Evaluation(_)) => return Err(e),
            Err(e) => {
                if total_error(&e) < total_error(&failure) {
                    failure = e;
                }
            }
        }
    }
    Err(failure)
}

const RESTARTS: usize = 4;

/// Assembles from the program's values, respecting them: the `fixed` ones are held; the given
/// ones are held too when the loops close with the free coordinates alone; otherwise the given
/// values change as little as possible (the closed configuration nearest to them in the given
/// coordinates, the free ones moving as they must) and each one changed is listed in `moved`.
pub fn assemble_respecting(
    model: &KinematicModel,
    start: &[f64],
    holds: &[Hold],
    options: &AssemblyOptions,
) -> Result<Assembled, AssemblyError> {
    let fixed = held(holds);
    if !holds.contains(&Hold::Given) {
        return assemble(model, start, &fixed, options);
    }
    let holding_given: Vec<bool> = holds.iter().map(|&h| h != Hold::Free).collect();
    let nearest_open = match assemble(model, start, &holding_given, options) {
        Ok(assembled) => return Ok(assembled),
        Err(e @ AssemblyError::Evaluation(_)) => return Err(e),
        Err(AssemblyError::NoAssembly { q, .. }) => q,
    };
    // The nearest closed configuration is searched locally from three places: the loops
    // closed as far as the free coordinates alone can, the given values themselves, and
    // wherever the plain assembly closes the loops; the nearest found wins.
    // Angles that turn are compared, and brought, within half a turn of their given values:
    // the pose is the same a full turn away.
    let turning = model.turning();
    let nearest_turn = |mut candidate: Assembled| {
        for (i, q) in candidate.q.iter_mut().enumerate() {
            if turning[i] && holds[i] != Hold::Fixed {
                *q = start[i] + within_half_turn(*q - start[i]);
            }
        }
        candidate
    };
    let closed = assemble(model, start, &fixed, options)?;
    let mut best = Some(nearest_turn(closed.clone()));
    for from in [&nearest_open, start, &closed.q] {
        let Some(candidate) = nearest_closed(model, start, holds, from, options)? else {
            continue;
        };
        let candidate = nearest_turn(candidate);
        let nearer = best.as_ref().is_none_or(|b| {
            given_distance(start, &candidate.q, holds) < given_distance(start, &b.q, holds)
        });
        if nearer {
            best = Some(candidate);
        }
    }
    let mut assembled = best.expect("the plain assembly is a candidate");
    assembled.moved = holds
        .iter()
        .enumerate()
        .filter(|&(i, &h)| {
            let change = (assembled.q[i] - start[i]).abs();
            h == Hold::Given && change > MOVED_ABOVE * start[i].abs().max(1.0)
        })
        .map(|(i, _)| Moved {
            coordinate: i,
            given: start[i],
            assembled: assembled.q[i],
        })
        .collect();
    Ok(assembled)
}

/// An angle's change brought within half a turn, (−π, π], by whole turns.
pub(crate) fn within_half_turn(change: f64) -> f64 {
    let turn = std::f64::consts::TAU;
    let wrapped = change - turn * (change / turn).round();
    if wrapped <= -std::f64::consts::PI {
        wrapped + turn
    } else {
        wrapped
    }
}

/// A given value changed by less than this (relative to it, or absolute below 1) is reported
/// as held: assembly closes the loops to 1e-12, so smaller changes are its round-off.
const MOVED_ABOVE: f64 = 1e-10;

/// Squared distance from the given values, the quantity [`nearest_closed`] minimises.
fn given_distance(start: &[f64], q: &[f64], holds: &[Hold]) -> f64 {
    (0..q.len())
        .filter(|&i| holds[i] == Hold::Given)
        .map(|i| (q[i] - start[i]).powi(2))
        .sum()
}

/// From `q`, the closed configuration nearest to the given values of `start`: Gauss–Newton on
/// the optimality conditions (`corrector`, [`NearestSteps`]), then closed again at the assembly
/// tolerance; `None` when the iteration does not settle.
fn nearest_closed(
    model: &KinematicModel,
    start: &[f64],
    holds: &[Hold],
    q: &[f64],
    options: &AssemblyOptions,
) -> Result<Option<Assembled>, AssemblyError> {
    let mut steps = NearestSteps {
        model,
        start,
        given: (0..q.len()).filter(|&i| holds[i] == Hold::Given).collect(),
        free: (0..q.len()).filter(|&i| holds[i] == Hold::Free).collect(),
        q: q.to_vec(),
        current: None,
        step: Vec::new(),
        change: f64::INFINITY,
    };
    let outcome = correct(&mut steps, &NEAREST)?;
    if outcome.stop == Stop::NoStep || steps.change > NEAREST_SETTLED {
        return Ok(None);
    }
    let fixed = held(holds);
    match solve(model, &steps.q, &fixed, options) {
        Ok(assembled) => Ok(Some(assembled)),
        Err(AssemblyError::NoAssembly { .. }) => Ok(None),
        Err(e) => Err(e),
    }
}

/// The nearest configuration's iteration: every Gauss–Newton step is kept (each one solves the
/// linearised optimality conditions, which no one merit measures), until the step is at the
/// coordinates' round-off (1e-13 of the largest, or of 1) or 50 steps are taken.
const NEAREST: Settings = Settings {
    iterations: 50,
    damping: Damping::None,
    acceptance: Acceptance::EveryStep,
    progress: Progress::Any,
};

/// The last step of the nearest configuration's iteration must be below this for its result to
/// be closed again and taken: a larger one has not settled on the optimality conditions.
const NEAREST_SETTLED: f64 = 1e-8;

/// The steps towards the closed configuration nearest to the given values, for the corrector.
/// Each changes the given coordinates g by the least that brings them nearest to their values
/// while closing the linearised loops, the free coordinates f taking what they must: with P
/// the projection away from what the free coordinates can do (the range of J_f), g moves to the
/// least-norm solution of P J_g (g' − g₀) = P (J_g (g − g₀) − r), then f by the least-norm
/// solution of J_f Δf = −r − J_g Δg.
struct NearestSteps<'a> {
    model: &'a KinematicModel,
    start: &'a [f64],
    given: Vec<usize>,
    free: Vec<usize>,
    q: Vec<f64>,
    /// The closure at `q` (`linearise`).
    current: Option<Closure>,
    /// The step formed, over every coordinate.
    step: Vec<f64>,
    /// The largest component of the last step taken.
    change: f64,
}

impl Correction for NearestSteps<'_> {
    type Error = AssemblyError;

    fn settled(&self) -> bool {
        let size = self.q.iter().fold(1.0_f64, |m, x| m.max(x.abs()));
        self.change < 1e-13 * size
    }

    fn merit(&self) -> f64 {
        self.change
    }

    fn linearise(&mut self) -> Result<(), AssemblyError> {
        self.current = Some(closure(self.model, &self.q)?);
        Ok(())
    }

    fn step(&mut self, _damping: f64) -> Result<Option<f64>, AssemblyError> {
        let current = self.current.as_ref().expect("linearised");
        let (given, free) = (&self.given, &self.free);
        let (j_given, j_free) = (
            current.jacobian.select_columns(given),
            current.jacobian.select_columns(free),
        );
        let away_from_free = |m: &DMatrix<f64>| -> DMatrix<f64> {
            match free_range(&j_free) {
                Some(u) => m - &u * (u.transpose() * m),
                None => m.clone(),
            }
        };
        let offset = DVector::from_iterator(
            given.len(),
            given.iter().map(|&i| self.q[i] - self.start[i]),
        );
        let a = away_from_free(&j_given);
        let b = away_from_free(&DMatrix::from_column_slice(
            current.residual.len(),
            1,
            (&j_given * &offset - &current.residual).as_slice(),
        ));
        let Some(next_offset) = least_norm(a, &b.column(0).into_owned()) else {
            return Ok(None);
        };
        let given_step = &next_offset - &offset;
        let free_step = match least_norm(j_free, &(-&current.residual - &j_given * &given_step)) {
            Some(step) => step,
            None => DVector::zeros(free.len()),
        };
        let change = given_step.amax().max(free_step.amax());
        if !change.is_finite() {
            return Ok(None);
        }
        self.step.clear();
        self.step.resize(self.q.len(), 0.0);
        for (k, &i) in given.iter().enumerate() {
            self.step[i] = given_step[k];
        }
        for (k, &i) in free.iter().enumerate() {
            self.step[i] = free_step[k];
        }
        self.change = change;
        Ok(Some(change))
    }

    fn try_step(&mut self) -> Result<f64, AssemblyError> {
        Ok(self.change)
    }

    fn accept(&mut self) {
        for (q, step) in self.q.iter_mut().zip(&self.step) {
            *q += step;
        }
    }
}

/// An orthonormal basis of the range of `m` (singular values above 1e-10 of the largest), or
/// `None` when it is empty.
fn free_range(m: &DMatrix<f64>) -> Option<DMatrix<f64>> {
    if m.ncols() == 0 || m.nrows() == 0 {
        return None;
    }
    let svd = crate::linalg::svd(m.clone(), true, false)?;
    let u = svd.u?;
    let largest = svd.singular_values.max();
    let kept: Vec<usize> = (0..svd.singular_values.len())
        .filter(|&k| svd.singular_values[k] > 1e-10 * largest)
        .collect();
    if kept.is_empty() {
        return None;
    }
    Some(u.select_columns(&kept))
}

/// The least-norm least-squares solution of m x = b (singular values below 1e-12 of the
/// largest treated as zero); zero without rows (a tree's closure: nothing to solve).
pub(crate) fn least_norm(m: DMatrix<f64>, b: &DVector<f64>) -> Option<DVector<f64>> {
    if m.ncols() == 0 || m.nrows() == 0 {
        return Some(DVector::zeros(m.ncols()));
    }
    let svd = crate::linalg::svd(m, true, true)?;
    let floor = 1e-12 * svd.singular_values.max();
    svd.solve(b, floor).ok()
}

fn total_error(error: &AssemblyError) -> f64 {
    match error {
        AssemblyError::NoAssembly { loop_errors, .. } => {
            loop_errors.iter().map(|(p, r)| p + r).sum()
        }
        AssemblyError::Evaluation(_) => f64::INFINITY,
    }
}

/// Closes the loops from `start`, the coordinates `fixed` held: Levenberg–Marquardt on the
/// squared residual (`corrector`), then `polish` once the largest row is within the tolerance.
fn solve(
    model: &KinematicModel,
    start: &[f64],
    fixed: &[bool],
    options: &AssemblyOptions,
) -> Result<Assembled, AssemblyError> {
    let free: Vec<usize> = (0..model.coordinate_count).filter(|&i| !fixed[i]).collect();
    let current = closure(model, start)?;
    let mut steps = ClosingSteps {
        model,
        free: &free,
        tolerance: options.tolerance,
        q: start.to_vec(),
        cost: current.residual.norm_squared(),
        current,
        gradient: DVector::zeros(0),
        normal: DMatrix::zeros(0, 0),
        trial: Vec::new(),
        tried: None,
    };
    let settings = Settings {
        iterations: options.max_iterations,
        ..CLOSING
    };
    let outcome = correct(&mut steps, &settings)?;
    let ClosingSteps { q, current, .. } = steps;
    if outcome.stop == Stop::Settled {
        let (q, residual) = polish(model, q, current, &free)?;
        return Ok(Assembled {
            q,
            iterations: outcome.accepted,
            residual,
            moved: Vec::new(),
        });
    }
    let loop_errors = (0..model.complementary().len())
        .map(|k| current.loop_errors(k))
        .collect();
    Err(AssemblyError::NoAssembly { q, loop_errors })
}

/// Assembly's iteration: Levenberg–Marquardt from a small damping. Uniform (Levenberg) damping:
/// as it vanishes the step tends to the minimum-norm Gauss–Newton step, so the free motions of
/// the mechanism are left where the user put them instead of drifting along directions the
/// constraints barely see.
const CLOSING: Settings = Settings {
    iterations: 200,
    damping: Damping::Levenberg {
        initial: 1e-6,
        floor: 1e-15,
        tries: 30,
        smallest_step: 1e-16,
    },
    acceptance: Acceptance::Descent,
    progress: Progress::Any,
};

/// Assembly's steps on the free coordinates, for the corrector: the normal equations of the
/// closure's rows, damped relative to their largest diagonal term.
struct ClosingSteps<'a> {
    model: &'a KinematicModel,
    free: &'a [usize],
    tolerance: f64,
    q: Vec<f64>,
    current: Closure,
    /// The squared residual at `q`.
    cost: f64,
    gradient: DVector<f64>,
    normal: DMatrix<f64>,
    /// The coordinates the step leads to.
    trial: Vec<f64>,
    /// Their closure and its squared residual, once tried.
    tried: Option<(Closure, f64)>,
}

impl Correction for ClosingSteps<'_> {
    type Error = AssemblyError;

    fn settled(&self) -> bool {
        self.current.residual.amax() <= self.tolerance
    }

    fn merit(&self) -> f64 {
        self.cost
    }

    fn linearise(&mut self) -> Result<(), AssemblyError> {
        let jacobian = self.current.jacobian.select_columns(self.free);
        self.gradient = jacobian.transpose() * &self.current.residual;
        self.normal = jacobian.transpose() * &jacobian;
        Ok(())
    }

    fn step(&mut self, damping: f64) -> Result<Option<f64>, AssemblyError> {
        let scale = self.normal.diagonal().max().max(1e-12);
        let mut damped = self.normal.clone();
        for i in 0..self.free.len() {
            damped[(i, i)] += damping * scale;
        }
        let Some(step) = damped.cholesky().map(|c| c.solve(&(-&self.gradient))) else {
            return Ok(None);
        };
        let mut trial = self.q.clone();
        for (i, &index) in self.free.iter().enumerate() {
            trial[index] += step[i];
        }
        (self.trial, self.tried) = (trial, None);
        Ok(Some(step.amax()))
    }

    fn try_step(&mut self) -> Result<f64, AssemblyError> {
        let candidate = closure(self.model, &self.trial)?;
        let cost = candidate.residual.norm_squared();
        self.tried = Some((candidate, cost));
        Ok(cost)
    }

    fn accept(&mut self) {
        if let Some((current, cost)) = self.tried.take() {
            let q = std::mem::take(&mut self.trial);
            (self.q, self.current, self.cost) = (q, current, cost);
        }
    }
}

/// A few more minimum-norm Gauss–Newton steps after convergence, while they reduce the residual:
/// where constraints act at second order, a residual of 1e-12 can leave the configuration 1e-6
/// from the closed set, and every halving of the residual matters to the rank computed there.
fn polish(
    model: &KinematicModel,
    q: Vec<f64>,
    current: Closure,
    free: &[usize],
) -> Result<(Vec<f64>, f64), AssemblyError> {
    let norm = current.residual.norm();
    if free.is_empty() || model.complementary().is_empty() {
        return Ok((q, norm));
    }
    let mut steps = PolishingSteps {
        model,
        free,
        q,
        norm,
        current,
        trial: None,
        tried: None,
    };
    correct(&mut steps, &POLISHING)?;
    let residual = steps.current.residual.amax();
    Ok((steps.q, residual))
}

/// The polish: Gauss–Newton, a step kept while it reduces the residual's norm.
const POLISHING: Settings = Settings {
    iterations: 8,
    damping: Damping::None,
    acceptance: Acceptance::Descent,
    progress: Progress::Any,
};

/// The polish's minimum-norm steps (singular values to 1e-14 kept), for the corrector.
struct PolishingSteps<'a> {
    model: &'a KinematicModel,
    free: &'a [usize],
    q: Vec<f64>,
    /// The residual's norm at `q`.
    norm: f64,
    current: Closure,
    trial: Option<Vec<f64>>,
    tried: Option<(Closure, f64)>,
}

impl Correction for PolishingSteps<'_> {
    type Error = AssemblyError;

    fn settled(&self) -> bool {
        false
    }

    fn merit(&self) -> f64 {
        self.norm
    }

    fn step(&mut self, _damping: f64) -> Result<Option<f64>, AssemblyError> {
        let jacobian = self.current.jacobian.select_columns(self.free);
        let Some(svd) = crate::linalg::svd(jacobian, true, true) else {
            return Ok(None);
        };
        let Ok(step) = svd.solve(&(-&self.current.residual), 1e-14) else {
            return Ok(None);
        };
        let mut trial = self.q.clone();
        for (i, &index) in self.free.iter().enumerate() {
            trial[index] += step[i];
        }
        self.trial = Some(trial);
        Ok(Some(step.amax()))
    }

    fn try_step(&mut self) -> Result<f64, AssemblyError> {
        let q = self.trial.as_ref().expect("a step was formed");
        let candidate = closure(self.model, q)?;
        let norm = candidate.residual.norm();
        self.tried = Some((candidate, norm));
        Ok(norm)
    }

    fn accept(&mut self) {
        if let (Some(q), Some((current, norm))) = (self.trial.take(), self.tried.take()) {
            (self.q, self.current, self.norm) = (q, current, norm);
        }
    }
}

/// Singular values of a matrix, largest first.
pub fn singular_values(m: &DMatrix<f64>) -> DVector<f64> {
    if m.nrows() == 0 || m.ncols() == 0 {
        return DVector::zeros(0);
    }
    let Some(svd) = crate::linalg::svd(m.clone(), false, false) else {
        // No decomposition of a non-finite matrix: values that no rank test accepts.
        return DVector::from_element(m.nrows().min(m.ncols()), f64::NAN);
    };
    let mut values = svd.singular_values;
    values.as_mut_slice().sort_by(|a, b| b.total_cmp(a));
    values
}

/// A deterministic pseudo-random number in [-1, 1] for sample `sample`, coordinate `i`
/// (SplitMix64 of the pair).
pub(crate) fn jitter(sample: usize, i: usize) -> f64 {
    let mut z = (sample as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
        ^ (i as u64).wrapping_add(0x632B_E59B_D9B4_E019);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    (z >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
}
