//! The singular points of the inverse geometric model (`lsdc kinematics --find-singular`): the
//! positions of a frame's origin where holding it leaves an actuated coordinate free to move
//! through a finite motion, so that the inverse geometric model has no value there (the Delta
//! seed's six points in z = 0, where the point projects onto an arm's pivot and the arm turns
//! round with the nacelle held: notes on the Delta seed, §3.3 and table T7).
//!
//! Type 1 singular configurations (the inverse velocity model loses rank, see
//! `kinematic_models`) are not isolated: for a Delta they fill the surfaces where an arm and
//! its rods fold, the workspace's boundary, and there the actuator's motion with the point held
//! exists to first order only (the inverse geometric model folds: its two branches meet). A
//! singular point of the inverse model is a type 1 configuration where that motion holds the
//! point to second order as well. With B the frame's motion on the non-idle motions (in the
//! mechanism's units), σ its smallest singular value, ξ and w its right and left singular
//! vectors, the two conditions are
//! - σ = wᵀ B ξ = 0 (type 1), and
//! - wᵀ a(ξ) = 0, a(ξ) the frame's acceleration when the mechanism moves along ξ at unit rate
//!   with the loops closed (`kinematic_models::second_order`): the part of it that no motion
//!   can cancel vanishes, so the motion continues with the point held.
//!
//! They are two equations on the configuration manifold: for a Delta, their solutions are the
//! circles an arm turns through over each of the six points. The search (Gauss–Newton with
//! the least-norm step and a backtracking line search, Nocedal & Wright, *Numerical
//! Optimization*, 2nd ed., §10.3 and §3.1, as an extended system for singular points: Griewank
//! & Reddien, "Characterization and computation of generalized turning points", SIAM J.
//! Numer. Anal. 21(1), 1984) moves on the manifold from a seed: steps along an orthonormal
//! basis of the closure's null space (in the mechanism's units), each closed again by assembly
//! (the one position corrector), the longest that reduces the conditions' norm, the
//! derivatives of both conditions by central differences along that basis with the signs of ξ
//! and w kept continuous (aligned with the iteration's base). The manifold is smooth where the
//! actuated coordinates or the point alone would not be coordinates of it (at the Delta's
//! points the direct model is singular too: two elbows meet on the axis), so the search
//! reaches configurations both models miss.

use nalgebra::{DMatrix, DVector};
use serde::Serialize;

use super::configurations::{point_of, Declared};
use super::kinematic_models::{
    models_at, motion_basis, second_order, Actuation, KinematicsError, Output, SingularKind,
    SingularMotion,
};
use crate::dynamics::loops;
use crate::kinematics::assembly::{assemble, AssemblyOptions};
use crate::kinematics::drag::linearise;
use crate::prepare::Prepared;

/// Both conditions below this (dimensionless) is a singular point.
pub const SEARCH_TOLERANCE: f64 = 1e-10;
/// Iterations at most per seed.
const ITERATIONS: usize = 60;
/// The central differences' step along a unit direction of the manifold (dimensionless: radians,
/// or lengths in L): the closure's round-off (1e-12) over it stays below 1e-7 of a derivative.
const DIFFERENCE: f64 = 1e-5;
/// The largest motion of the point along the conditions' curve at a singular point (lengths in
/// L per unit motion): there it is the actuators' motion holding the point, 0 but for the
/// differences' error (at most 9e-9 on the Delta's points; 7e-5 and more on the curves refused).
pub const CURVE_DRIFT: f64 = 1e-6;
/// The longest step of one iteration (dimensionless), a trust region for far seeds.
const LONGEST_STEP: f64 = 0.2;

/// A singular point found.
#[derive(Clone, Debug, Serialize)]
pub struct SingularPoint {
    /// The frame's origin (fixed axes).
    pub point: [f64; 3],
    /// The actuated coordinates there (one configuration of those the point holds).
    pub actuated: Vec<f64>,
    /// How the kinematic models classify the configuration.
    pub kind: Option<SingularKind>,
    pub type1_measure: f64,
    pub type2_measure: f64,
    /// wᵀ a(ξ) (module comment), dimensionless: 0 at a singular point.
    pub second_order: f64,
    /// B's next singular value (above the tolerance: one motion of the actuators holds the
    /// point, not two).
    pub next_measure: f64,
    /// The point's motion along the curve where both conditions hold (lengths in L per unit
    /// motion): at most [`CURVE_DRIFT`], the differences' error.
    pub curve_drift: f64,
    /// The motion of the actuators that leaves the point held.
    pub motion: Option<SingularMotion>,
    pub iterations: usize,
}

/// What one seed gave.
#[derive(Clone, Debug, Serialize)]
#[serde(tag = "outcome", rename_all = "snake_case")]
pub enum SearchOutcome {
    Found {
        seed: usize,
        singular: SingularPoint,
    },
    NotFound {
        seed: usize,
        reason: String,
        /// The conditions where it stopped (when it got that far).
        type1_measure: Option<f64>,
        second_order: Option<f64>,
    },
}

/// The searches from every seed, and the distinct points found.
#[derive(Clone, Debug, Serialize)]
pub struct SingularPoints {
    pub actuated: Vec<String>,
    pub point: String,
    pub tolerance: f64,
    /// The points found, each once (two within 10⁻⁶ L are one), in the order found.
    pub points: Vec<SingularPoint>,
    pub searches: Vec<SearchOutcome>,
}

/// Searches from each seed (closed configurations, or configurations to close) and gathers
/// the distinct points; `tolerance` classifies the configurations found as `models_at` does.
pub fn find(
    prepared: &Prepared,
    actuation: &Actuation,
    output: &Output,
    seeds: &[Result<Declared, String>],
    tolerance: f64,
) -> SingularPoints {
    let mut points: Vec<SingularPoint> = Vec::new();
    let mut searches = Vec::new();
    for (seed, start) in seeds.iter().enumerate() {
        let outcome = match start {
            Err(reason) => SearchOutcome::NotFound {
                seed,
                reason: reason.clone(),
                type1_measure: None,
                second_order: None,
            },
            Ok(start) => match search(prepared, actuation, output, &start.coordinates, tolerance) {
                Ok(singular) => SearchOutcome::Found { seed, singular },
                Err(stopped) => SearchOutcome::NotFound {
                    seed,
                    reason: stopped.reason,
                    type1_measure: stopped.conditions.map(|c| c[0]),
                    second_order: stopped.conditions.map(|c| c[1]),
                },
            },
        };
        if let SearchOutcome::Found { singular, .. } = &outcome {
            let length = characteristic_length(prepared, actuation, output);
            let known = points
                .iter()
                .any(|p| distance(p.point, singular.point) < 1e-6 * length);
            if !known {
                points.push(singular.clone());
            }
        }
        searches.push(outcome);
    }
    SingularPoints {
        actuated: actuation.names.clone(),
        point: output.frame.name.clone(),
        tolerance,
        points,
        searches,
    }
}

fn distance(a: [f64; 3], b: [f64; 3]) -> f64 {
    (0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>().sqrt()
}

fn characteristic_length(prepared: &Prepared, actuation: &Actuation, output: &Output) -> f64 {
    let declared = &prepared.coordinates;
    let rates = vec![0.0; declared.len()];
    (prepared.model.state_from_declared(declared, &rates).ok())
        .and_then(|(q, _)| motion_basis(&prepared.model, actuation, output, &q).ok())
        .map_or(1.0, |basis| basis.length)
}

/// Why a search stopped without a point.
struct Stopped {
    reason: String,
    conditions: Option<[f64; 2]>,
}

impl Stopped {
    fn at(reason: impl Into<String>, conditions: Option<[f64; 2]>) -> Stopped {
        Stopped {
            reason: reason.into(),
            conditions,
        }
    }
}

/// Both conditions at a configuration, with what fixes their signs.
struct Conditions {
    /// wᵀ B ξ and wᵀ a(ξ).
    values: [f64; 2],
    /// B's singular value before σ (infinite when σ is its only one).
    next: f64,
    /// ξ as dimensionless state velocities, and w.
    motion: DVector<f64>,
    direction: DVector<f64>,
}

/// The conditions at the declared coordinates `declared`, the signs of ξ and w those nearest
/// `base`'s (when given).
fn conditions(
    prepared: &Prepared,
    actuation: &Actuation,
    output: &Output,
    declared: &[f64],
    base: Option<&Conditions>,
) -> Result<Conditions, KinematicsError> {
    let model = &prepared.model;
    let (q, _) = model.state_from_declared(declared, &vec![0.0; declared.len()])?;
    let basis = motion_basis(model, actuation, output, &q)?;
    let k = basis.basis.ncols().min(output.rows());
    if k == 0 {
        return Err(KinematicsError::State {
            index: 0,
            message: "no motion of the mechanism moves the frame".to_string(),
        });
    }
    let xi = basis.b_svd.right.column(k - 1).into_owned();
    let mut w = basis.b_svd.left.column(k - 1).into_owned();
    let mut motion = &basis.basis * &xi;
    if let Some(base) = base {
        if motion.dot(&base.motion) < 0.0 {
            motion = -motion;
        }
        if w.dot(&base.direction) < 0.0 {
            w = -w;
        }
    }
    // ξ's sign as the motion's (B ξ = B Wᵀ (W ξ) for the orthonormal basis W).
    let xi_aligned = basis.basis.transpose() * &motion;
    let measure = w.dot(&(&basis.b * &xi_aligned));
    let v: Vec<f64> = (0..motion.len())
        .map(|c| motion[c] * basis.scales[c])
        .collect();
    let acceleration = second_order(model, output, &q, &v, &basis.scales, basis.length)?.frame;
    let second = (0..w.len())
        .map(|r| w[r] * acceleration[r] / basis.unit_rows[(r, 0)])
        .sum();
    let next = match k {
        1 => f64::INFINITY,
        _ => basis.b_svd.values[k - 2],
    };
    Ok(Conditions {
        values: [measure, second],
        next,
        motion,
        direction: w,
    })
}

/// The closed configuration nearest `start` (every coordinate free).
fn close(prepared: &Prepared, start: &[f64]) -> Option<Vec<f64>> {
    let free = vec![false; start.len()];
    assemble(
        &prepared.kinematics,
        start,
        &free,
        &AssemblyOptions::default(),
    )
    .ok()
    .map(|a| a.q)
}

/// An orthonormal basis of the motions the closure allows at `declared`, in the mechanism's
/// units (turning coordinates in radians, sliding ones and the loops' positions in lengths of
/// L), as displacements of the declared coordinates (columns). The idle ones (a rod spinning on
/// its axis) change neither condition: the least-norm steps leave them.
fn tangent_directions(
    prepared: &Prepared,
    output: &Output,
    declared: &[f64],
    length: f64,
) -> Result<DMatrix<f64>, KinematicsError> {
    let linear = linearise(&prepared.kinematics, &output.frame, declared)?;
    let turning = prepared.kinematics.turning();
    let column_scale = |c: usize| if turning[c] { 1.0 } else { length };
    let jacobian = &linear.closure_jacobian;
    let scaled = DMatrix::from_fn(jacobian.nrows(), jacobian.ncols(), |r, c| {
        let row = if r % 6 < 3 { 1.0 } else { 1.0 / length };
        jacobian[(r, c)] * row * column_scale(c)
    });
    let null = loops::decompose(&scaled).null_space;
    Ok(DMatrix::from_fn(null.nrows(), null.ncols(), |r, c| {
        null[(r, c)] * column_scale(r)
    }))
}

/// One search from the declared coordinates `start`: Gauss–Newton's least-norm step on both
/// conditions with a backtracking line search (Nocedal & Wright §3.1): the whole step first,
/// halved while it does not reduce the conditions' norm, down to an eighth of the trust
/// region's length ([`LONGEST_STEP`]); when none does, the step at the trust region's length
/// is taken anyway, as the undamped search took every step, so that a seed in a valley of the
/// norm moves on. Each trial is closed again by assembly (the house's corrector); the search
/// does not run on `corrector::correct`, whose steps are kept only where they descend: with
/// that rule (Levenberg–Marquardt) 26 of the Delta's 64 seeds stalled in such valleys and
/// 2 of the 6 points were missed.
fn search(
    prepared: &Prepared,
    actuation: &Actuation,
    output: &Output,
    start: &[f64],
    tolerance: f64,
) -> Result<SingularPoint, Stopped> {
    let evaluation = |e: KinematicsError| Stopped::at(e.to_string(), None);
    let mut q = close(prepared, start)
        .ok_or_else(|| Stopped::at("the loops do not close from this seed", None))?;
    let length = {
        let (state, _) = (prepared.model)
            .state_from_declared(&q, &vec![0.0; q.len()])
            .map_err(|e| evaluation(e.into()))?;
        motion_basis(&prepared.model, actuation, output, &state)
            .map_err(evaluation)?
            .length
    };
    let mut current = conditions(prepared, actuation, output, &q, None).map_err(evaluation)?;
    for iteration in 0..ITERATIONS {
        let (directions, jacobian) =
            derivatives(prepared, actuation, output, &q, &current, length)?;
        let decomposition = loops::decompose(&jacobian);
        if current.values.iter().all(|v| v.abs() <= SEARCH_TOLERANCE) {
            let curve = point_drift(
                prepared,
                output,
                &q,
                &directions,
                &decomposition.null_space,
                length,
            )
            .map_err(evaluation)?;
            return settle(
                prepared,
                actuation,
                output,
                &q,
                (&current, curve),
                iteration,
                tolerance,
            );
        }
        let residual = DVector::from_column_slice(&current.values);
        let step = -(decomposition.pseudo_inverse * &residual);
        let size = step.amax();
        if !size.is_finite() {
            return Err(Stopped::at(
                "the conditions' derivatives are not finite",
                Some(current.values),
            ));
        }
        let moved_by = |fraction: f64| -> Option<(Vec<f64>, Conditions)> {
            let moved = &directions * (&step * fraction);
            let trial: Vec<f64> = (0..q.len()).map(|i| q[i] + moved[i]).collect();
            let closed = close(prepared, &trial)?;
            let at = conditions(prepared, actuation, output, &closed, Some(&current)).ok()?;
            Some((closed, at))
        };
        let merit = norm(&current.values);
        let mut fraction = 1.0;
        let mut descent = None;
        while fraction * size >= LONGEST_STEP / 8.0 {
            if let Some((closed, at)) = moved_by(fraction) {
                if norm(&at.values) < merit {
                    descent = Some((closed, at));
                    break;
                }
            }
            fraction *= 0.5;
        }
        (q, current) = match descent {
            Some(found) => found,
            None => moved_by((LONGEST_STEP / size).min(1.0)).ok_or_else(|| {
                Stopped::at(
                    "the loops do not close after a step of the search",
                    Some(current.values),
                )
            })?,
        };
    }
    Err(Stopped::at(
        format!("no singular point within {ITERATIONS} iterations"),
        Some(current.values),
    ))
}

/// The conditions' Euclidean norm, which the line search reduces (it does not depend on the
/// signs of ξ and w).
fn norm(values: &[f64; 2]) -> f64 {
    values[0].hypot(values[1])
}

/// The directions of the manifold at `declared` and the derivatives of both conditions along
/// them (central differences, the signs of ξ and w aligned with `base`'s).
fn derivatives(
    prepared: &Prepared,
    actuation: &Actuation,
    output: &Output,
    declared: &[f64],
    base: &Conditions,
    length: f64,
) -> Result<(DMatrix<f64>, DMatrix<f64>), Stopped> {
    let evaluation = |e: KinematicsError| Stopped::at(e.to_string(), Some(base.values));
    let directions = tangent_directions(prepared, output, declared, length).map_err(evaluation)?;
    let mut jacobian = DMatrix::zeros(2, directions.ncols());
    for d in 0..directions.ncols() {
        let mut sides = [[0.0; 2]; 2];
        for (side, sign) in [1.0, -1.0].into_iter().enumerate() {
            let trial: Vec<f64> = (0..declared.len())
                .map(|i| declared[i] + sign * DIFFERENCE * directions[(i, d)])
                .collect();
            let closed = close(prepared, &trial).ok_or_else(|| {
                Stopped::at(
                    "the loops do not close next to this configuration",
                    Some(base.values),
                )
            })?;
            sides[side] = conditions(prepared, actuation, output, &closed, Some(base))
                .map_err(evaluation)?
                .values;
        }
        for r in 0..2 {
            jacobian[(r, d)] = (sides[0][r] - sides[1][r]) / (2.0 * DIFFERENCE);
        }
    }
    Ok((directions, jacobian))
}

/// Where both conditions hold: a singular point when B loses rank once. Where it loses rank
/// twice (two arms folded at once), ξ and w are any pair of a plane and the second condition
/// holds by accident: no singular point of the inverse model there.
///
/// Two conditions on a manifold of more dimensions hold along curves: at a singular point that
/// curve is the actuators' motion holding the point, elsewhere (where the measures' bases turn
/// over, for one) the point moves along it. `curve` is the point's motion (in L) along the
/// curve's unit tangent; above [`CURVE_DRIFT`] the configuration is refused.
fn settle(
    prepared: &Prepared,
    actuation: &Actuation,
    output: &Output,
    declared: &[f64],
    (conditions, curve): (&Conditions, f64),
    iterations: usize,
    tolerance: f64,
) -> Result<SingularPoint, Stopped> {
    if curve > CURVE_DRIFT {
        return Err(Stopped::at(
            format!(
                "both conditions hold, but along a curve on which the point moves ({curve:.1e} L per unit motion): not a singular point of the inverse model"
            ),
            Some(conditions.values),
        ));
    }
    if conditions.next <= tolerance {
        return Err(Stopped::at(
            format!(
                "the search ended where two motions of the actuators hold the point (singular values {:.1e} and {:.1e}): two folds at once, not a singular point of the inverse model",
                conditions.values[0].abs(),
                conditions.next
            ),
            Some(conditions.values),
        ));
    }
    let mut point = found(
        prepared, actuation, output, declared, conditions, iterations, tolerance,
    )
    .map_err(|e| Stopped::at(e.to_string(), Some(conditions.values)))?;
    point.curve_drift = curve;
    Ok(point)
}

/// The point's motion (lengths in L) along the curve where both conditions hold, per unit
/// motion: the norm of its motion over the null space of their derivatives (`null`, on
/// `directions`), the idle motions in it moving nothing.
fn point_drift(
    prepared: &Prepared,
    output: &Output,
    declared: &[f64],
    directions: &DMatrix<f64>,
    null: &DMatrix<f64>,
    length: f64,
) -> Result<f64, KinematicsError> {
    let linear = linearise(&prepared.kinematics, &output.frame, declared)?;
    let along = &linear.point_jacobian * directions * null;
    Ok(along.norm() / length)
}

/// The actuated coordinates' indices among the declared ones.
fn actuated_indices(prepared: &Prepared, actuation: &Actuation) -> Vec<usize> {
    (actuation.names.iter())
        .map(|name| {
            (prepared.coordinate_names.iter())
                .position(|n| n == name)
                .expect("an actuated coordinate is declared")
        })
        .collect()
}

fn found(
    prepared: &Prepared,
    actuation: &Actuation,
    output: &Output,
    declared: &[f64],
    conditions: &Conditions,
    iterations: usize,
    tolerance: f64,
) -> Result<SingularPoint, KinematicsError> {
    let model = &prepared.model;
    let (q, _) = model.state_from_declared(declared, &vec![0.0; declared.len()])?;
    let rates = vec![0.0; actuation.velocities.len()];
    let models = models_at(model, actuation, output, &q, &rates, tolerance)?;
    let actuated = (actuated_indices(prepared, actuation).iter())
        .map(|&index| declared[index])
        .collect();
    let s = models.singularity;
    Ok(SingularPoint {
        point: point_of(prepared, &output.frame, declared)?,
        actuated,
        kind: s.kind,
        type1_measure: s.type1_measure,
        type2_measure: s.type2_measure,
        second_order: conditions.values[1],
        next_measure: conditions.next,
        curve_drift: 0.0,
        motion: s.weakest_motions[0].clone(),
        iterations,
    })
}
