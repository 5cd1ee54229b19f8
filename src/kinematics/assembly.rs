//! Assembly: from the user's starting values, solve the closure equations for a consistent
//! configuration, keeping the `fixed` coordinates at their values (Levenberg–Marquardt on the
//! exact closure Jacobian; near the solution it takes Gauss–Newton steps and converges
//! quadratically).

use nalgebra::{DMatrix, DVector};

use super::closure::closure;
use super::eval::EvalError;
use super::model::KinematicModel;

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

fn total_error(error: &AssemblyError) -> f64 {
    match error {
        AssemblyError::NoAssembly { loop_errors, .. } => {
            loop_errors.iter().map(|(p, r)| p + r).sum()
        }
        AssemblyError::Evaluation(_) => f64::INFINITY,
    }
}

fn solve(
    model: &KinematicModel,
    start: &[f64],
    fixed: &[bool],
    options: &AssemblyOptions,
) -> Result<Assembled, AssemblyError> {
    let free: Vec<usize> = (0..model.coordinate_count).filter(|&i| !fixed[i]).collect();
    let mut q = start.to_vec();
    let mut current = closure(model, &q)?;
    let mut cost = current.residual.norm_squared();
    let mut damping = 1e-6;
    for iteration in 0..options.max_iterations {
        if current.residual.amax() <= options.tolerance {
            let (q, residual) = polish(model, q, current.residual.norm(), &free)?;
            return Ok(Assembled {
                q,
                iterations: iteration,
                residual,
            });
        }
        let jacobian = DMatrix::from_fn(current.jacobian.nrows(), free.len(), |r, c| {
            current.jacobian[(r, free[c])]
        });
        let gradient = jacobian.transpose() * &current.residual;
        let normal = jacobian.transpose() * &jacobian;
        let mut improved = false;
        for _ in 0..30 {
            // Uniform (Levenberg) damping: as it vanishes the step tends to the minimum-norm
            // Gauss–Newton step, so the free motions of the mechanism are left where the user
            // put them instead of drifting along directions the constraints barely see.
            let scale = normal.diagonal().max().max(1e-12);
            let mut damped = normal.clone();
            for i in 0..free.len() {
                damped[(i, i)] += damping * scale;
            }
            let Some(step) = damped.cholesky().map(|c| c.solve(&(-&gradient))) else {
                damping *= 10.0;
                continue;
            };
            let mut trial = q.clone();
            for (i, &index) in free.iter().enumerate() {
                trial[index] += step[i];
            }
            let candidate = closure(model, &trial)?;
            let trial_cost = candidate.residual.norm_squared();
            if trial_cost < cost {
                q = trial;
                current = candidate;
                cost = trial_cost;
                damping = (damping / 10.0).max(1e-15);
                improved = true;
                break;
            }
            damping *= 10.0;
            if step.amax() < 1e-16 {
                break;
            }
        }
        if !improved {
            break;
        }
    }
    if current.residual.amax() <= options.tolerance {
        let residual = current.residual.amax();
        return Ok(Assembled {
            q,
            iterations: options.max_iterations,
            residual,
        });
    }
    let loop_errors = (0..model.complementary().len())
        .map(|k| current.loop_errors(k))
        .collect();
    Err(AssemblyError::NoAssembly { q, loop_errors })
}

/// A few more minimum-norm Gauss–Newton steps after convergence, while they reduce the residual:
/// where constraints act at second order, a residual of 1e-12 can leave the configuration 1e-6
/// from the closed set, and every halving of the residual matters to the rank computed there.
fn polish(
    model: &KinematicModel,
    mut q: Vec<f64>,
    mut norm: f64,
    free: &[usize],
) -> Result<(Vec<f64>, f64), AssemblyError> {
    if free.is_empty() || model.complementary().is_empty() {
        return Ok((q, norm));
    }
    for _ in 0..8 {
        let current = closure(model, &q)?;
        let jacobian = DMatrix::from_fn(current.jacobian.nrows(), free.len(), |r, c| {
            current.jacobian[(r, free[c])]
        });
        let Ok(step) = jacobian.svd(true, true).solve(&(-&current.residual), 1e-14) else {
            break;
        };
        let mut trial = q.clone();
        for (i, &index) in free.iter().enumerate() {
            trial[index] += step[i];
        }
        let trial_norm = closure(model, &trial)?.residual.norm();
        if trial_norm >= norm {
            break;
        }
        q = trial;
        norm = trial_norm;
    }
    let residual = closure(model, &q)?.residual.amax();
    Ok((q, residual))
}

/// Singular values of a matrix, largest first.
pub fn singular_values(m: &DMatrix<f64>) -> DVector<f64> {
    if m.nrows() == 0 || m.ncols() == 0 {
        return DVector::zeros(0);
    }
    let mut values = m.clone().svd(false, false).singular_values;
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
