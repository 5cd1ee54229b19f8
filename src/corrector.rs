//! The position corrector: moves coordinates onto constraints (or towards a goal) by
//! Gauss–Newton steps, with a Levenberg–Marquardt fallback where a caller allows it (Nocedal &
//! Wright, *Numerical Optimization*, 2nd ed., §10.3 for both methods, §4 for the damping as a
//! trust region; Marquardt, "An algorithm for least-squares estimation of nonlinear
//! parameters", SIAM J. Appl. Math. 11(2), 1963, for the damping's tenfold updates). It serves
//! every position correction of the house (there is no other Gauss–Newton loop in the crate):
//!
//! | caller | merit a step must reduce | settled when | damping | iterations | a slow step |
//! |---|---|---|---|---|---|
//! | loops' projection (`dynamics::loops::project`) | largest row | 0, or kept rows at round-off (1e-13, well conditioned) | none | 8 | under fourfold ends it, unless an earlier factor served it (then a fresh one) |
//! | closing a configuration on every loop row (same file) | largest row | 0 | none | 8 | under fourfold ends it |
//! | the constraint stack's rows beyond the loops' (`simulate::system::stacked`): contacts' gaps, couplings, drives' laws, resting and impacting stops' bounds | none: every step is kept | every row at its round-off (a bound's: 4 ulps) | none | 4 | — |
//! | assembly (`kinematics::assembly`) | squared norm | largest row ≤ tolerance (1e-12) | LM from 1e-6, floor 1e-15, 30 tries | 200 | a rejected step under 1e-16 ends it |
//! | assembly's polish (same file) | norm | 0 | none | 8 | any reduction continues |
//! | the closed configuration nearest to the given values (same file) | none: every step is kept | step ≤ 1e-13 of the largest coordinate | none | 50 | — (a last step over 1e-8 refuses the result) |
//! | drag (`kinematics::drag`) | distance to the target | distance 0 | LM from 1e-6, floor 1e-15, 30 tries | 100 | progress ≤ 1e-15·max(distance, 1) ends it |
//!
//! What differs between them is what each caller supplies ([`Correction`]): its residual and
//! how it measures it, its linear solve (the loops' sparse factorisation with its own damping
//! and a factor kept along a projection; a dense singular value decomposition; the response X
//! of the constraint stack; Cholesky on damped normal equations), the coordinates it holds
//! (assembly's `fixed` ones: its steps leave them out; the stack's held rows: the drives' laws
//! and the resting stops' bounds) and how it moves a state (retraction on the joints'
//! manifolds, then, for the stacked rows, the loops' own projection). The iteration itself is
//! one, [`correct`]: from the current point, while it is not settled and iterations remain,
//! take the step at the current damping; keep it if it reduces the merit (or always, for
//! [`Acceptance::EveryStep`]); on rejection either stop (Gauss–Newton) or raise the damping
//! tenfold and take the step again (Levenberg–Marquardt, which lowers the damping tenfold after
//! a kept step). Every loop is bounded, a NaN merit is never an improvement, and the reason it
//! stopped is returned ([`Stop`]). The dense solve most callers need is
//! [`minimum_norm_step`]: rows scaled by powers of two (exact) and a singular value
//! decomposition that ends on any matrix (`linalg::svd`).
//!
//! The callers keep their own rules in the table because each was measured where it runs: the
//! projection's fourfold rule and round-off floor decide how a row of four-bars passes its flat
//! configurations (see `dynamics::loops::project`), assembly's small initial damping keeps the
//! free motions where the user put them, and the stacked rows' steps change the measure they
//! would be judged by. Gauss–Newton is the start of every correction (Levenberg–Marquardt with
//! a damping of 1e-6 of the normal matrix's scale is Gauss–Newton to that precision); the
//! damping grows only where a caller's start may be far (assembly, drag).

use nalgebra::{DMatrix, DVector};

use crate::linalg::{inverse_power_of_two, svd};

/// One correction problem: a current point, and a step from it that a trial evaluates.
pub trait Correction {
    type Error;
    /// Whether the current point needs no step (closed to the caller's tolerance, or at
    /// round-off).
    fn settled(&self) -> bool;
    /// The measure a kept step must reduce, at the current point.
    fn merit(&self) -> f64;
    /// Prepares the steps from the current point (a linearisation), once per iteration before
    /// the first step; nothing by default.
    fn linearise(&mut self) -> Result<(), Self::Error> {
        Ok(())
    }
    /// Forms the step from the current point for `damping` (0 without damping, relative to the
    /// caller's scale otherwise); its size (largest component), or None when no step can be
    /// formed at this damping.
    fn step(&mut self, damping: f64) -> Result<Option<f64>, Self::Error>;
    /// Evaluates the point the step leads to; its merit.
    fn try_step(&mut self) -> Result<f64, Self::Error>;
    /// Makes the point tried the current one.
    fn accept(&mut self);
    /// After a rejected or slow step: whether to go on with another iteration (the loops'
    /// projection then drops a factor kept from earlier positions); false by default.
    fn retry(&mut self) -> bool {
        false
    }
}

/// How a correction iterates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Settings {
    /// Iterations at most (each one forms and tries at least one step).
    pub iterations: usize,
    pub damping: Damping,
    pub acceptance: Acceptance,
    pub progress: Progress,
}

/// The damping of the steps.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Damping {
    /// Gauss–Newton: a step that is rejected, or cannot be formed, ends the correction.
    None,
    /// Levenberg–Marquardt: a step rejected or not formed is formed again with a tenfold
    /// damping, `tries` times at most per iteration; a kept one lowers it tenfold, to `floor`.
    Levenberg {
        initial: f64,
        floor: f64,
        tries: usize,
        /// A rejected step smaller than this (largest component) ends the correction.
        smallest_step: f64,
    },
}

/// Which steps are kept.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Acceptance {
    /// Those that reduce the merit.
    Descent,
    /// Every one (a step that is not a descent on one measure, such as a solve along the
    /// response followed by the loops' own projection).
    EveryStep,
}

/// When a kept step ends the correction anyway.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Progress {
    /// Never: any reduction continues.
    Any,
    /// When it leaves more than this fraction of the merit (a Gauss–Newton step that no longer
    /// converges quadratically has reached round-off).
    Ratio(f64),
    /// When it reduces the merit by at most this times max(merit left, 1).
    Absolute(f64),
}

/// Why a correction stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stop {
    /// The caller's test says the point is settled.
    Settled,
    /// A step could not be formed (Gauss–Newton), or every damping tried failed to form one.
    NoStep,
    /// A step, or every damping tried, did not reduce the merit.
    NoDescent,
    /// A kept step reduced the merit too little (`Progress`).
    Slow,
    /// A rejected step was below the smallest one (`Damping::Levenberg`).
    Stalled,
    /// The iterations ran out.
    Exhausted,
}

/// How a correction ended.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Outcome {
    pub stop: Stop,
    /// Iterations begun.
    pub iterations: usize,
    /// Steps kept.
    pub accepted: usize,
}

/// Runs the correction `problem` under `settings` (see the module's documentation).
pub fn correct<C: Correction>(problem: &mut C, settings: &Settings) -> Result<Outcome, C::Error> {
    let (mut damping, tries) = match settings.damping {
        Damping::None => (0.0, 1),
        Damping::Levenberg { initial, tries, .. } => (initial, tries),
    };
    let mut outcome = Outcome {
        stop: Stop::Exhausted,
        iterations: 0,
        accepted: 0,
    };
    while outcome.iterations < settings.iterations {
        if problem.settled() {
            outcome.stop = Stop::Settled;
            return Ok(outcome);
        }
        outcome.iterations += 1;
        let merit = problem.merit();
        problem.linearise()?;
        let mut stop = Some(Stop::NoStep);
        for _ in 0..tries {
            let Some(size) = problem.step(damping)? else {
                damping *= 10.0;
                continue;
            };
            let trial = problem.try_step()?;
            // A NaN merit is no improvement either.
            let kept = settings.acceptance == Acceptance::EveryStep || trial < merit;
            if kept {
                problem.accept();
                outcome.accepted += 1;
                if let Damping::Levenberg { floor, .. } = settings.damping {
                    damping = (damping / 10.0).max(floor);
                }
                stop = slow(settings.progress, merit, trial).then_some(Stop::Slow);
                break;
            }
            stop = Some(Stop::NoDescent);
            damping *= 10.0;
            if let Damping::Levenberg { smallest_step, .. } = settings.damping {
                if size < smallest_step {
                    stop = Some(Stop::Stalled);
                    break;
                }
            }
        }
        if let Some(reason) = stop {
            if matches!(reason, Stop::NoDescent | Stop::Slow) && problem.retry() {
                continue;
            }
            outcome.stop = reason;
            return Ok(outcome);
        }
    }
    if problem.settled() {
        outcome.stop = Stop::Settled;
    }
    Ok(outcome)
}

/// Whether a kept step from `before` to `after` ends the correction as too slow.
fn slow(progress: Progress, before: f64, after: f64) -> bool {
    match progress {
        Progress::Any => false,
        Progress::Ratio(ratio) => after >= ratio * before,
        Progress::Absolute(floor) => before - after <= floor * after.max(1.0),
    }
}

/// The minimum-norm least-squares step x of J x = −r: each row of J (and r with it) scaled by
/// the power of two that brings its largest entry into [1, 2) (exact: rows of different units,
/// as a stop's coordinate beside a contact's gap, weigh alike, and consistent rows keep their
/// solutions), then a singular value decomposition that ends on any matrix, singular values up
/// to `tolerance` times the largest taken as zero. None when J has a non-finite entry or the
/// decomposition does not converge.
pub fn minimum_norm_step(
    jacobian: &DMatrix<f64>,
    residual: &DVector<f64>,
    tolerance: f64,
) -> Option<DVector<f64>> {
    if jacobian.nrows() == 0 || jacobian.ncols() == 0 {
        return Some(DVector::zeros(jacobian.ncols()));
    }
    let mut scaled = jacobian.clone();
    let mut right = -residual;
    for i in 0..scaled.nrows() {
        let scale = inverse_power_of_two(scaled.row(i).amax());
        scaled.row_mut(i).scale_mut(scale);
        right[i] *= scale;
    }
    let svd = svd(scaled, true, true)?;
    let floor = tolerance * svd.singular_values.max();
    svd.solve(&right, floor).ok()
}
