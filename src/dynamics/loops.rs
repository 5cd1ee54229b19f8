//! Closed loops. Every complementary link `A @ a and B @ b with D(q)` is six constraint rows
//! between its two bodies: the chain's end frame E = pose(a)·A·D(q) must coincide with the target
//! frame T = pose(b)·B. The rows are written on the state's velocities (the tree's, then the
//! complementary links' own coordinates, which carry no inertia):
//!
//! - position: the rotation vector of E⁻¹T and the gap between their origins (fixed axes);
//! - velocity: `G v`, the difference of the two frames' angular velocities and of their
//!   velocities at the loop point (fixed axes), zero on a closed trajectory;
//! - acceleration: `G v̇ + γ = 0`, with γ from the bodies' velocity-product accelerations.
//!
//! The equations `M v̇ = f + Gᵀλ` are solved by the null-space method on a singular value
//! decomposition of G, so redundant rows (a planar loop of spatial revolutes) and configurations
//! where rows become dependent cost nothing special: the multipliers are then the minimum-norm
//! ones. Motions that move no mass (a rod's spin about its own axis) are left at rest.

use nalgebra::{DMatrix, DVector, Vector3};

use super::algorithms::{bias_accelerations, crba, forward_kinematics, Data};
use super::model::Model;
use super::spatial::{self, Force, Motion};
use crate::kinematics::eval::EvalError;
use crate::kinematics::spatial::{transform_twist, translation, Pose};

/// For the rank reported to people (redundant constraints, singular configurations): singular
/// values of G below this fraction of the largest count as zero, as in `lsdc tree`. It is far
/// above round-off because some closure conditions act only at second order (maille1, maille2):
/// at a configuration closed to 1e-15 the corresponding singular value is still about 1e-8.
pub const RANK_TOLERANCE: f64 = crate::kinematics::mobility::RANK_TOLERANCE;

/// For solving the equations: only singular values at round-off level are dropped. A row that
/// acts at second order is still enforced at first order near the closed set, which keeps the
/// velocities tangent to it (dropping it lets the motion drift off and the projection fight it).
pub const SOLVE_TOLERANCE: f64 = 1e-9;

/// Names of the six rows of a loop.
pub const ROW_NAMES: [&str; 6] = [
    "rotation about x",
    "rotation about y",
    "rotation about z",
    "translation along x",
    "translation along y",
    "translation along z",
];

/// The loops' constraint rows at a state.
pub struct Constraints {
    /// Position rows: 6 per loop.
    pub residual: DVector<f64>,
    /// ∂(rows' rates)/∂(velocities): 6 per loop, one column per state velocity.
    pub jacobian: DMatrix<f64>,
    /// `G v`: the velocity rows.
    pub velocity: DVector<f64>,
    /// γ = Ġ v (zero unless asked for).
    pub bias: DVector<f64>,
    /// Where each loop closes (origin of its chain's end), fixed axes.
    pub points: Vec<Vector3<f64>>,
}

/// The constraint rows at (q, v), both of the state's length. With `with_bias` γ is computed too.
/// Leaves the forward kinematics of (q, v) in `data`.
pub fn constraints(
    model: &Model,
    data: &mut Data,
    q: &[f64],
    v: &[f64],
    with_bias: bool,
) -> Result<Constraints, EvalError> {
    forward_kinematics(model, data, q, v)?;
    constraints_after_kinematics(model, data, q, v, with_bias)
}

/// `constraints` when `data` already holds the forward kinematics of (q, v) (after RNEA, say).
pub fn constraints_after_kinematics(
    model: &Model,
    data: &mut Data,
    q: &[f64],
    v: &[f64],
    with_bias: bool,
) -> Result<Constraints, EvalError> {
    if with_bias {
        bias_accelerations(model, data);
    }
    let rows = 6 * model.loops.len();
    let mut c = Constraints {
        residual: DVector::zeros(rows),
        jacobian: DMatrix::zeros(rows, model.velocities()),
        velocity: DVector::zeros(rows),
        bias: DVector::zeros(rows),
        points: Vec::with_capacity(model.loops.len()),
    };
    for k in 0..model.loops.len() {
        loop_rows(model, data, q, v, k, with_bias, &mut c)?;
    }
    c.velocity = &c.jacobian * DVector::from_column_slice(v);
    Ok(c)
}

fn loop_rows(
    model: &Model,
    data: &Data,
    q: &[f64],
    v: &[f64],
    k: usize,
    with_bias: bool,
    c: &mut Constraints,
) -> Result<(), EvalError> {
    let joint = &model.loops[k];
    let (offset, n) = (model.loop_offset(k), joint.coordinate_count());
    // A ball joint's rotation is free: only its centre is constrained, which its angles do not
    // move; its angle rates are left out.
    let ball = model.loop_balls[k].is_some();
    let no_rates = vec![0.0; n];
    let rates = if ball {
        &no_rates[..]
    } else {
        &v[model.nv + offset..model.nv + offset + n]
    };
    let chain = joint.chain_motion(
        &q[model.nq + offset..model.nq + offset + n],
        Some(rates),
        &model.unknowns,
    )?;
    let base = data.world[joint.first_body] * joint.first;
    let end = base * chain.pose;
    let target = data.world[joint.second_body] * joint.second;
    let point = end.translation.vector;
    let rotation = end.rotation * (end.rotation.inverse() * target.rotation).scaled_axis();
    let gap = target.translation.vector - point;
    let row = 6 * k;
    c.residual.rows_mut(row, 3).copy_from(&rotation);
    c.residual.rows_mut(row + 3, 3).copy_from(&gap);
    c.points.push(point);
    // Rates are taken at the loop point, in fixed axes: a motion seen from `at_point`.
    let at_point = translation(point);
    add_body_columns(
        model,
        data,
        joint.second_body,
        &at_point,
        1.0,
        row,
        &mut c.jacobian,
    );
    add_body_columns(
        model,
        data,
        joint.first_body,
        &at_point,
        -1.0,
        row,
        &mut c.jacobian,
    );
    for column in (0..n).filter(|_| !ball) {
        let twist = transform_twist(
            &base,
            &Motion::from_column_slice(chain.subspace.column(column).as_slice()),
        );
        let moved = spatial::motion_to_child(&at_point, &twist);
        let mut target_column = c
            .jacobian
            .view_mut((row, model.nv + offset + column), (6, 1));
        target_column -= moved;
    }
    if with_bias {
        // World-frame spatial accelerations are the derivatives of world-frame spatial twists, so
        // γ is the difference of the two frames' accelerations at zero joint accelerations.
        let world = |motions: &[Motion], body: usize| {
            spatial::motion_to_parent(&data.world[body], &motions[body])
        };
        let first_velocity = world(&data.velocity, joint.first_body);
        let chain_velocity = transform_twist(&base, &chain.velocity);
        let end_acceleration = world(&data.acceleration, joint.first_body)
            + spatial::cross_motion(&first_velocity, &chain_velocity)
            + transform_twist(&base, &chain.bias);
        let difference = world(&data.acceleration, joint.second_body) - end_acceleration;
        c.bias
            .rows_mut(row, 6)
            .copy_from(&spatial::motion_to_child(&at_point, &difference));
        if ball {
            // The point rows are the relative velocity at a moving point p: d/dt adds
            // (ω_T − ω_E) × ṗ, which vanishes when the rotation rows hold (ω_T = ω_E).
            let second_velocity = world(&data.velocity, joint.second_body);
            let relative_spin = (second_velocity - first_velocity)
                .fixed_rows::<3>(0)
                .into_owned();
            let point_velocity = spatial::motion_to_child(&at_point, &first_velocity)
                .fixed_rows::<3>(3)
                .into_owned();
            let mut linear = c.bias.rows_mut(row + 3, 3);
            linear += relative_spin.cross(&point_velocity);
        }
    }
    if ball {
        c.residual.rows_mut(row, 3).fill(0.0);
        c.jacobian.rows_mut(row, 3).fill(0.0);
        c.bias.rows_mut(row, 3).fill(0.0);
    }
    Ok(())
}

/// Whether each constraint row constrains anything: a ball joint's three rotation rows do not.
pub fn active_rows(model: &Model) -> Vec<bool> {
    model
        .loop_balls
        .iter()
        .flat_map(|ball| (0..6).map(move |r| ball.is_none() || r >= 3))
        .collect()
}

/// Recovers the angles of the complementary ball joints at (q, v), and their rates when
/// `with_rates` (for outputs); otherwise their rates are set to zero: the state the integrator
/// carries then holds them still between recoveries, instead of moving them with rates nothing
/// updates (which would only feed its error estimate). Returns whether there are any.
pub fn seat_ball_angles(
    model: &Model,
    data: &mut Data,
    q: &mut [f64],
    v: &mut [f64],
    with_rates: bool,
) -> Result<bool, EvalError> {
    if model.loop_balls.iter().all(Option::is_none) {
        return Ok(false);
    }
    forward_kinematics(model, data, q, v)?;
    seat_balls(model, data, q, v, with_rates)?;
    Ok(true)
}

/// Sets the angles of the complementary ball joints to those of the bodies' relative rotation
/// (continuing from their previous values) and their rates to match the relative angular
/// velocity; `data` must hold the forward kinematics of (q, v).
fn seat_balls(
    model: &Model,
    data: &Data,
    q: &mut [f64],
    v: &mut [f64],
    with_rates: bool,
) -> Result<(), EvalError> {
    for (k, axes) in model.loop_balls.iter().enumerate() {
        let Some(axes) = axes else { continue };
        let joint = &model.loops[k];
        let start = model.loop_offset(k);
        let base = data.world[joint.first_body] * joint.first;
        let target = data.world[joint.second_body] * joint.second;
        let relative = base.rotation.inverse() * target.rotation;
        let previous = [
            q[model.nq + start],
            q[model.nq + start + 1],
            q[model.nq + start + 2],
        ];
        let angles = super::angles::angles_from_rotation(axes, &relative, &previous);
        q[model.nq + start..model.nq + start + 3].copy_from_slice(&angles);
        if !with_rates {
            v[model.nv + start..model.nv + start + 3].fill(0.0);
            continue;
        }
        // Relative angular velocity in the first frame, then the angle rates that give it.
        let world =
            |body: usize| spatial::motion_to_parent(&data.world[body], &data.velocity[body]);
        let omega = base.rotation.inverse()
            * (world(joint.second_body) - world(joint.first_body)).fixed_rows::<3>(0);
        let subspace = joint.chain(&angles, &model.unknowns)?.1;
        let rates = subspace
            .rows(0, 3)
            .into_owned()
            .pseudo_inverse(1e-12)
            .map(|p| p * omega)
            .unwrap_or_else(|_| DVector::zeros(3));
        v[model.nv + start..model.nv + start + 3].copy_from_slice(rates.as_slice());
    }
    Ok(())
}

/// Adds `sign` times the rates of `body`'s frame per velocity of the joints between it and earth.
fn add_body_columns(
    model: &Model,
    data: &Data,
    body: usize,
    at_point: &Pose,
    sign: f64,
    row: usize,
    jacobian: &mut DMatrix<f64>,
) {
    let mut current = body;
    while current != 0 {
        let joint = &model.joints[current - 1];
        let subspace = &data.states[current - 1].subspace;
        for column in 0..joint.nv() {
            let world = spatial::motion_to_parent(
                &data.world[current],
                &Motion::from_column_slice(subspace.column(column).as_slice()),
            );
            let moved = spatial::motion_to_child(at_point, &world);
            let mut target = jacobian.view_mut((row, joint.v_offset + column), (6, 1));
            target += sign * moved;
        }
        current = joint.parent;
    }
}

/// A singular value decomposition of G: its rank, the pseudo-inverse and a basis of its null
/// space (the motions the loops allow).
pub struct Decomposition {
    pub rank: usize,
    pub pseudo_inverse: DMatrix<f64>,
    pub null_space: DMatrix<f64>,
    /// Singular values, largest first.
    pub singular_values: Vec<f64>,
    /// Left singular vectors in the same order (columns).
    pub left: DMatrix<f64>,
}

pub fn decompose(g: &DMatrix<f64>) -> Decomposition {
    decompose_with(g, SOLVE_TOLERANCE)
}

/// `decompose` with another relative tolerance for the rank.
pub fn decompose_with(g: &DMatrix<f64>, tolerance: f64) -> Decomposition {
    let (m, n) = g.shape();
    // Pad to at least square so the decomposition returns the whole null space.
    let rows = m.max(n);
    let mut square = DMatrix::zeros(rows, n);
    square.rows_mut(0, m).copy_from(g);
    let svd = square.svd(true, true);
    let (u, v_t) = (svd.u.expect("asked for"), svd.v_t.expect("asked for"));
    let mut order: Vec<usize> = (0..svd.singular_values.len()).collect();
    order.sort_by(|&a, &b| svd.singular_values[b].total_cmp(&svd.singular_values[a]));
    let singular_values: Vec<f64> = order.iter().map(|&k| svd.singular_values[k]).collect();
    let largest = singular_values.first().copied().unwrap_or(0.0);
    let rank = singular_values
        .iter()
        .take_while(|&&s| s > tolerance * largest && s > 0.0)
        .count();
    let mut pseudo_inverse = DMatrix::zeros(n, m);
    for &k in &order[..rank] {
        pseudo_inverse +=
            v_t.row(k).transpose() * u.column(k).rows(0, m).transpose() / svd.singular_values[k];
    }
    let null: Vec<DVector<f64>> = order[rank..]
        .iter()
        .map(|&k| v_t.row(k).transpose())
        .collect();
    let null_space = if null.is_empty() {
        DMatrix::zeros(n, 0)
    } else {
        DMatrix::from_columns(&null)
    };
    let left = DMatrix::from_fn(m, order.len().min(m), |r, c| u[(r, order[c])]);
    Decomposition {
        rank,
        pseudo_inverse,
        null_space,
        singular_values,
        left,
    }
}

/// How the constraints are kept: by projecting the state after each step (exact), by Baumgarte's
/// feedback in the accelerations (with this rate, in 1/s, critically damped), by the integrator's
/// own equations (the symplectic integrator's RATTLE steps), or not at all.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Stabilisation {
    Projection,
    Baumgarte(f64),
    Integrator,
    None,
}

pub struct Solution {
    /// Accelerations of every state velocity.
    pub accelerations: DVector<f64>,
    /// Constraint wrench of each loop on its second body, at the loop point in fixed axes:
    /// moment, then force (6 per loop).
    pub multipliers: DVector<f64>,
    pub rank: usize,
}

#[derive(Clone, Debug, PartialEq)]
pub enum LoopError {
    /// An effort acts on a motion that moves no mass: its acceleration would be infinite. The
    /// state velocity that motion moves most.
    MasslessMotion { velocity: usize },
}

/// Solves `M v̇ = f + Gᵀλ`, `G v̇ + γ = 0` (γ with Baumgarte's terms when asked for); `mass` is
/// the tree's mass matrix, `force` has the state's length, `massless` the mechanism's number of
/// allowed motions without mass (`massless_count`).
pub fn solve(
    mass: &DMatrix<f64>,
    force: &DVector<f64>,
    c: &Constraints,
    stabilisation: Stabilisation,
    massless: usize,
) -> Result<Solution, LoopError> {
    let n = force.len();
    let nt = mass.nrows();
    let mut full_mass = DMatrix::zeros(n, n);
    full_mass.view_mut((0, 0), (nt, nt)).copy_from(mass);
    let mut gamma = c.bias.clone();
    if let Stabilisation::Baumgarte(rate) = stabilisation {
        gamma += 2.0 * rate * &c.velocity + rate * rate * &c.residual;
    }
    let basis = decompose(&c.jacobian);
    let particular = -(&basis.pseudo_inverse * &gamma);
    let null = &basis.null_space;
    let reduced_mass = null.transpose() * &full_mass * null;
    let reduced_force = null.transpose() * (force - &full_mass * &particular);
    let z = massive_solve(reduced_mass, &reduced_force, massless).map_err(|k| {
        LoopError::MasslessMotion {
            velocity: null.column(k).iamax(),
        }
    })?;
    let accelerations = particular + null * z;
    let multipliers = basis.pseudo_inverse.transpose() * (&full_mass * &accelerations - force);
    Ok(Solution {
        accelerations,
        multipliers,
        rank: basis.rank,
    })
}

/// A motion whose inertia is below this fraction of the largest counts as without mass (a point
/// mass rod spinning about its own axis: 1e-12 relative, not 0, after the null-space basis
/// mixes it with motions that have mass).
const MASSLESS: f64 = 1e-10;

/// A force on a motion without mass stops the run above this fraction of the largest force on
/// the motions: it is a model that forgot a mass, not the residue (1e-6 relative seen on the
/// Delta's rod spins) of evaluating forces that balance exactly.
const MASSLESS_FORCE: f64 = 1e-3;

/// Solves the symmetric positive semi-definite system `a z = b` in the span of the eigenvectors
/// that carry mass; a motion without mass stays at rest unless a force acts on it (then its
/// eigenvector index is the error). The `massless` smallest eigenvalues count as without mass
/// whatever their value (see `massless_count`), and so does any below `MASSLESS`.
fn massive_solve(
    a: DMatrix<f64>,
    b: &DVector<f64>,
    massless: usize,
) -> Result<DVector<f64>, usize> {
    if a.nrows() == 0 {
        return Ok(DVector::zeros(0));
    }
    if massless == 0 {
        if let Some(cholesky) = a.clone().cholesky() {
            // Well conditioned (every pivot carries mass): the fast path.
            let pivots = cholesky.l_dirty().diagonal();
            if pivots.min() * pivots.min() > MASSLESS * pivots.max() * pivots.max() {
                return Ok(cholesky.solve(b));
            }
        }
    }
    let eigen = a.symmetric_eigen();
    let largest = eigen.eigenvalues.amax();
    let mut order: Vec<usize> = (0..eigen.eigenvalues.len()).collect();
    order.sort_by(|&i, &j| eigen.eigenvalues[i].total_cmp(&eigen.eigenvalues[j]));
    let scale = b.amax().max(f64::MIN_POSITIVE);
    let mut z = DVector::zeros(b.len());
    for (rank, &k) in order.iter().enumerate() {
        let (value, vector) = (eigen.eigenvalues[k], eigen.eigenvectors.column(k));
        let component = vector.dot(b);
        if rank >= massless && value > MASSLESS * largest {
            z += vector * (component / value);
        } else if component.abs() > MASSLESS_FORCE * scale {
            return Err(k);
        }
    }
    Ok(z)
}

/// How many of the motions the loops allow at (q) move no mass (rod spins, the angles of
/// complementary ball joints), counted on the constraint manifold. The count is a property of
/// the mechanism: between projections, in the integrator's trial states slightly off the
/// manifold, these motions pick up inertias of 1e-9 of the largest or so, and dividing the
/// residue of forces that balance exactly by such inertias makes a spurious fast motion.
pub fn massless_count(model: &Model, data: &mut Data, q: &[f64]) -> Result<usize, EvalError> {
    let rest = vec![0.0; model.velocities()];
    let allowed = decompose(&constraints(model, data, q, &rest, false)?.jacobian).null_space;
    let n = model.velocities();
    let mut mass = DMatrix::zeros(n, n);
    mass.view_mut((0, 0), (model.nv, model.nv))
        .copy_from(&crba(model, data, q)?);
    let eigenvalues = (allowed.transpose() * mass * &allowed).symmetric_eigenvalues();
    let largest = eigenvalues.amax();
    Ok(eigenvalues
        .iter()
        .filter(|&&value| value <= MASSLESS * largest)
        .count())
}

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
    /// G at the projected configuration.
    pub basis: Decomposition,
}

const NEWTON_ITERATIONS: usize = 8;

/// Moves (q, v) onto the constraints: Gauss–Newton steps on the positions (minimum-norm
/// corrections, so the free motions are not disturbed), then the orthogonal projection of the
/// velocities onto G v = 0.
pub fn project(
    model: &Model,
    data: &mut Data,
    q: &mut [f64],
    v: &mut [f64],
) -> Result<Projection, EvalError> {
    let rest = vec![0.0; v.len()];
    let mut current = constraints(model, data, q, &rest, false)?;
    let mut error = current.residual.amax();
    let before_position = error;
    for _ in 0..NEWTON_ITERATIONS {
        if error == 0.0 {
            break;
        }
        let step = -(decompose(&current.jacobian).pseudo_inverse * &current.residual);
        let mut trial = q.to_vec();
        model.retract(&mut trial, step.as_slice());
        let candidate = constraints(model, data, &trial, &rest, false)?;
        let trial_error = candidate.residual.amax();
        if trial_error >= error {
            break;
        }
        let converging = trial_error < 0.25 * error;
        q.copy_from_slice(&trial);
        (current, error) = (candidate, trial_error);
        if !converging {
            break;
        }
    }
    let basis = decompose(&current.jacobian);
    let velocity = &current.jacobian * DVector::from_column_slice(v);
    let corrected = DVector::from_column_slice(v) - &basis.pseudo_inverse * &velocity;
    let after_velocity = (&current.jacobian * &corrected).amax();
    v.copy_from_slice(corrected.as_slice());
    seat_ball_angles(model, data, q, v, false)?;
    Ok(Projection {
        before: Residuals {
            position: before_position,
            velocity: velocity.amax(),
        },
        after: Residuals {
            position: error,
            velocity: after_velocity,
        },
        basis,
    })
}

/// The active rows that depend on earlier ones (in loop order, then row order), at a configuration.
pub fn redundant_rows(jacobian: &DMatrix<f64>, active: &[bool]) -> Vec<usize> {
    let largest = (0..jacobian.nrows())
        .map(|r| jacobian.row(r).norm())
        .fold(0.0, f64::max);
    let mut basis: Vec<DVector<f64>> = Vec::new();
    let mut redundant = Vec::new();
    for r in (0..jacobian.nrows()).filter(|&r| active[r]) {
        let mut row: DVector<f64> = jacobian.row(r).transpose();
        // Twice, for orthogonality in floating point.
        for _ in 0..2 {
            for b in &basis {
                row -= b * b.dot(&row);
            }
        }
        let norm = row.norm();
        if norm <= RANK_TOLERANCE * largest {
            redundant.push(r);
        } else {
            basis.push(row / norm);
        }
    }
    redundant
}

/// The loop whose rows take the largest part in a left singular vector (a lost direction).
pub fn loop_of_direction(direction: &DVector<f64>) -> usize {
    (0..direction.len() / 6)
        .max_by(|&a, &b| {
            direction
                .rows(6 * a, 6)
                .norm_squared()
                .total_cmp(&direction.rows(6 * b, 6).norm_squared())
        })
        .unwrap_or(0)
}

/// The constraint wrenches as forces on the bodies (in their frames, about their origins):
/// +λ on each loop's second body, −λ on its first.
pub fn constraint_forces(
    model: &Model,
    data: &Data,
    c: &Constraints,
    multipliers: &DVector<f64>,
) -> Vec<Force> {
    let mut forces = vec![Force::zeros(); model.body_count() + 1];
    for (k, joint) in model.loops.iter().enumerate() {
        let wrench = Force::from_column_slice(multipliers.rows(6 * k, 6).as_slice());
        // About the fixed origin, then into each body's frame.
        let about_origin = spatial::force_to_parent(&translation(c.points[k]), &wrench);
        for (body, sign) in [(joint.second_body, 1.0), (joint.first_body, -1.0)] {
            if body != 0 {
                forces[body] += sign * spatial::force_to_child(&data.world[body], &about_origin);
            }
        }
    }
    forces
}
