//! The loops' constraint rows. Every complementary link `A @ a and B @ b with D(q)` is six rows
//! between its two bodies: the chain's end frame E = pose(a)·A·D(q) must coincide with the target
//! frame T = pose(b)·B. The rows are written on the state's velocities (the tree's, then the
//! complementary links' own coordinates, which carry no inertia):
//!
//! - position: the rotation vector of E⁻¹T and the gap between their origins (fixed axes);
//! - velocity: `G v`, the difference of the two frames' angular velocities and of their
//!   velocities at the loop point (fixed axes), zero on a closed trajectory;
//! - acceleration: `G v̇ + γ = 0`, with γ from the bodies' velocity-product accelerations.

use nalgebra::{DVector, Vector3};

use super::jacobian::{ConstraintJacobian, LoopBlock};

use crate::dynamics::algorithms::{bias_accelerations, forward_kinematics, Data};
use crate::dynamics::model::Model;
use crate::dynamics::scalar::{DynamicsScalar, NOT_DIFFERENTIABLE};
use crate::kinematics::eval::EvalError;
use crate::kinematics::model::{ChainMotion, JointModel, SingleMotion};
use crate::spatial::{self, constant, Force, Motion, Real};
use crate::spatial::{motion_to_parent, translation, Pose};

/// Names of the six rows of a loop.
pub const ROW_NAMES: [&str; 6] = [
    "rotation about x",
    "rotation about y",
    "rotation about z",
    "translation along x",
    "translation along y",
    "translation along z",
];

/// The loops' constraint rows at a state, in the scalar `T`: `f64`, or dual numbers
/// (`DynamicsScalar`), in which the rows' derivative parts check G and γ.
pub struct Constraints<T: Real = f64> {
    /// Position rows: 6 per loop.
    pub residual: DVector<T>,
    /// ∂(rows' rates)/∂(velocities): 6 per loop, one column per state velocity.
    pub jacobian: ConstraintJacobian<T>,
    /// `G v`: the velocity rows.
    pub velocity: DVector<T>,
    /// γ = Ġ v (zero unless asked for).
    pub bias: DVector<T>,
    /// Where each loop closes (origin of its chain's end), fixed axes.
    pub points: Vec<Vector3<T>>,
    /// Each loop's first frame, pose(a)·A, where its chain starts.
    bases: Vec<Pose<T>>,
    /// Each loop's dof chain at the state (scratch kept between evaluations).
    chains: Vec<ChainMotion<T>>,
    /// Each loop's chain when it is one rotation or translation linear in its coordinate
    /// (`JointModel::single_motion`), found once here: reading the chain's expressions at
    /// every evaluation followed pointers scattered over the model, one loop after another.
    singles: Vec<Option<SingleMotion>>,
    /// The tree joints on the loops' paths to earth, and the fixed-frame twist of each of their
    /// velocities (by state velocity), computed once per state for every loop that shares them.
    path_joints: Vec<usize>,
    world_columns: Vec<Motion<T>>,
    /// Per loop, its tree columns (local index, state velocity) with the sign they enter its
    /// rows with: +1 on the second body's path to earth, −1 on the first's (a velocity on both
    /// moves both frames alike and is left out).
    pub(super) path_signs: Vec<Vec<(usize, usize, f64)>>,
}

impl Constraints {
    /// Rows of zeros for `model`'s loops, each loop's block already over the columns it touches
    /// (found once here: they depend on the tree alone), to be filled by `constraints_into`.
    pub fn new(model: &Model) -> Constraints {
        Constraints::with_scalar(model)
    }
}

impl<T: Real> Constraints<T> {
    /// `Constraints::new` in the scalar `T`.
    pub fn with_scalar(model: &Model) -> Constraints<T> {
        let rows = 6 * model.loops.len();
        let blocks = (0..model.loops.len())
            .map(|k| {
                let joint = &model.loops[k];
                let own = if model.loop_balls[k].is_some() {
                    0
                } else {
                    joint.coordinate_count()
                };
                let first = model.nv + model.loop_offset(k);
                let cycle = cycle_signs(model, [joint.first_body, joint.second_body]);
                let tree = cycle.iter().map(|&(column, _)| column);
                LoopBlock::zeros(tree.chain(first..first + own).collect())
            })
            .collect::<Vec<LoopBlock<T>>>();
        let path_signs = (model.loops.iter())
            .map(|joint| {
                let cycle = cycle_signs(model, [joint.first_body, joint.second_body]);
                let signs = cycle.into_iter().enumerate();
                signs
                    .map(|(local, (column, sign))| (local, column, sign))
                    .collect()
            })
            .collect();
        Constraints {
            path_signs,
            residual: DVector::zeros(rows),
            jacobian: ConstraintJacobian::new(model.velocities(), blocks),
            velocity: DVector::zeros(rows),
            bias: DVector::zeros(rows),
            points: vec![Vector3::zeros(); model.loops.len()],
            bases: vec![Pose::identity(); model.loops.len()],
            chains: vec![ChainMotion::default(); model.loops.len()],
            singles: model.loops.iter().map(JointModel::single_motion).collect(),
            path_joints: path_joints(model),
            world_columns: vec![Motion::zeros(); model.nv],
        }
    }
}

/// A loop's tree columns with the sign they enter its rows with (see
/// `Constraints::path_signs`), in increasing order: the velocities on the loop's cycle, from
/// each of its two bodies up to their last common ancestor. A velocity above it moves both
/// frames alike and is left out, so that the loop's rows, and the products between loops that
/// fill their normal matrix, cost what the cycle costs however deep in the tree it closes (a
/// ladder of N loops hanging from a chain: N short cycles, not N paths to earth of up to N
/// joints each).
fn cycle_signs(model: &Model, [first, second]: [usize; 2]) -> Vec<(usize, f64)> {
    let mut signs: Vec<(usize, f64)> = Vec::new();
    for (body, sign) in [(second, 1.0), (first, -1.0)] {
        for on_path in model.path_to_earth(body) {
            let joint = &model.joints[on_path - 1];
            signs.extend((joint.v_offset..joint.v_offset + joint.nv()).map(|c| (c, sign)));
        }
    }
    signs.sort_unstable_by_key(|&(column, _)| column);
    let mut merged: Vec<(usize, f64)> = Vec::with_capacity(signs.len());
    for (column, sign) in signs {
        match merged.last_mut() {
            Some(last) if last.0 == column => last.1 += sign,
            _ => merged.push((column, sign)),
        }
    }
    merged.retain(|&(_, sign)| sign != 0.0);
    merged
}

/// The tree joints on the loops' cycles (`cycle_signs`), in increasing order.
fn path_joints(model: &Model) -> Vec<usize> {
    let mut joints = Vec::new();
    for joint in &model.loops {
        let cycle = cycle_signs(model, [joint.first_body, joint.second_body]);
        let columns: Vec<usize> = cycle.into_iter().map(|(column, _)| column).collect();
        for body in [joint.first_body, joint.second_body] {
            let on_cycle = |j: &usize| {
                let v = model.joints[*j].v_offset;
                columns.binary_search(&v).is_ok()
            };
            joints.extend(model.path_to_earth(body).map(|b| b - 1).filter(on_cycle));
        }
    }
    joints.sort_unstable();
    joints.dedup();
    joints
}

/// The constraints at (q, v), both of the state's length, to `extent`. Leaves the forward
/// kinematics of (q, v) in `data`.
pub fn constraints(
    model: &Model,
    data: &mut Data,
    q: &[f64],
    v: &[f64],
    extent: Extent,
) -> Result<Constraints, EvalError> {
    let mut c = Constraints::new(model);
    forward_kinematics(model, data, q, v)?;
    constraints_into(model, data, q, v, extent, &mut c)?;
    Ok(c)
}

/// How much of the constraints `constraints_into` computes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Extent {
    /// The position rows alone (a trial configuration, kept only if it reduces them).
    Residual,
    /// The position rows, G and G v.
    Rows,
    /// The rows and γ.
    WithBias,
    /// G and γ, with the position rows' rotations and the velocity rows G v left at zero: what
    /// the equations of motion read when no feedback of the constraints (Baumgarte's) is asked
    /// for. The rotation vector is each loop's residual's costliest part; `complete_rotations`
    /// adds both where a projection goes on from these rows.
    Motion,
}

/// Writes the constraints at (q, v) into `c` (made by `Constraints::new` for this model) to
/// `extent`, reusing its storage; `data` must hold the forward kinematics of (q, v).
pub fn constraints_into<T: DynamicsScalar>(
    model: &Model,
    data: &mut Data<T>,
    q: &[T],
    v: &[T],
    extent: Extent,
    c: &mut Constraints<T>,
) -> Result<(), EvalError> {
    let rotations = extent != Extent::Motion;
    for k in 0..model.loops.len() {
        loop_residual(model, data, q, v, k, rotations, c)?;
    }
    if extent != Extent::Residual {
        let with_bias = matches!(extent, Extent::WithBias | Extent::Motion);
        rows_after_residual(model, data, with_bias, c);
        if extent == Extent::Motion {
            // As slices: nalgebra's `fill` steps a strided iterator element by element.
            c.velocity.as_mut_slice().fill(T::zero());
        } else {
            c.jacobian.mul_into(v, &mut c.velocity);
        }
    }
    Ok(())
}

/// The rotation rows of a loop whose chain ends at `end` and whose second frame is at `target`:
/// the rotation carrying one onto the other, as a rotation vector in fixed axes.
fn rotation_residual<T: Real>(end: &Pose<T>, target: &Pose<T>) -> Vector3<T> {
    let relative = end.rotation.inverse() * target.rotation;
    end.rotation * rotation_vector(&relative)
}

/// The rotation vector of a unit quaternion (nalgebra's `scaled_axis`, the same operations),
/// with its limit 2 v / |w| where the vector part v vanishes, which `scaled_axis` returns as
/// zero: the same value there, and for dual numbers the derivative at a closed loop, where the
/// rows' rotation is the identity and the vector part's value is exactly zero.
fn rotation_vector<T: Real>(rotation: &nalgebra::UnitQuaternion<T>) -> Vector3<T> {
    let (w, vector) = (rotation.scalar(), rotation.vector());
    let norm = vector.norm();
    if norm == T::zero() {
        return vector * (constant::<T>(2.0) / w);
    }
    rotation.scaled_axis()
}

/// Completes the constraints `constraints_into` left at `Extent::Motion` with the position
/// rows' rotations and the velocity rows, from the same state (q, v), whose forward kinematics
/// `data` must still hold.
pub fn complete_rotations(model: &Model, data: &Data, v: &[f64], c: &mut Constraints) {
    c.jacobian.mul_into(v, &mut c.velocity);
    for (k, joint) in model.loops.iter().enumerate() {
        if model.loop_balls[k].is_some() {
            continue;
        }
        let end = c.bases[k] * c.chains[k].pose;
        let target = data.world[joint.second_body] * joint.second;
        c.residual
            .rows_mut(6 * k, 3)
            .copy_from(&rotation_residual(&end, &target));
    }
}

/// Completes the constraints `constraints_into` left at `Extent::Residual` to `Extent::Rows`,
/// from the same state (whose forward kinematics `data` must still hold).
pub fn complete_rows(model: &Model, data: &mut Data, v: &[f64], c: &mut Constraints) {
    rows_after_residual(model, data, false, c);
    c.jacobian.mul_into(v, &mut c.velocity);
}

/// G and, `with_bias`, γ, from the chains and loop points `loop_residual` left in `c`.
fn rows_after_residual<T: Real>(
    model: &Model,
    data: &mut Data<T>,
    with_bias: bool,
    c: &mut Constraints<T>,
) {
    if with_bias {
        bias_accelerations(model, data);
    } else {
        c.bias.fill(T::zero());
    }
    for &k in &c.path_joints {
        let (joint, state) = (&model.joints[k], &data.states[k]);
        for column in 0..joint.nv() {
            let local = Motion::from_column_slice(state.subspace.column(column).as_slice());
            c.world_columns[joint.v_offset + column] =
                spatial::motion_to_parent(&data.world[joint.child], &local);
        }
    }
    for k in 0..model.loops.len() {
        loop_rows(model, data, k, with_bias, c);
    }
}

/// Loop `k`'s chain at (q, v), its position rows (their rotations only when asked for, zero
/// otherwise) and its closing point, into `c`.
fn loop_residual<T: DynamicsScalar>(
    model: &Model,
    data: &Data<T>,
    q: &[T],
    v: &[T],
    k: usize,
    rotations: bool,
    c: &mut Constraints<T>,
) -> Result<(), EvalError> {
    let joint = &model.loops[k];
    let (offset, n) = (model.loop_offset(k), joint.coordinate_count());
    // A ball joint's rotation is free: only its centre is constrained, which its angles do not
    // move; its angle rates are left out. Its chain is three rotations about its centre: its
    // end is the first frame as far as the rows are concerned (the rotation rows are not
    // kept), so it is not evaluated and stays at the identity, at rest.
    let ball = model.loop_balls[k].is_some();
    if !ball {
        chain_motion_into(
            joint,
            c.singles[k],
            &q[model.nq + offset..model.nq + offset + n],
            &v[model.nv + offset..model.nv + offset + n],
            &mut c.chains[k],
        )?;
    }
    let base = data.world[joint.first_body] * joint.first.cast::<T>();
    let end = base * c.chains[k].pose;
    let target = data.world[joint.second_body] * joint.second.cast::<T>();
    let point = end.translation.vector;
    c.bases[k] = base;
    let row = 6 * k;
    if ball || !rotations {
        c.residual.rows_mut(row, 3).fill(T::zero());
    } else {
        c.residual
            .rows_mut(row, 3)
            .copy_from(&rotation_residual(&end, &target));
    }
    c.residual
        .rows_mut(row + 3, 3)
        .copy_from(&(target.translation.vector - point));
    c.points[k] = point;
    Ok(())
}

/// A loop's dof chain at its coordinates and rates: evaluated in `f64`, or in dual numbers for
/// a chain of one rotation or translation (its rotation by the half-angle formula, whose
/// derivative holds at zero: `spatial::smooth_rotation`), the others refused
/// (`DynamicsScalar`). `single` is the chain's single motion, if it is one (`Constraints::singles`).
fn chain_motion_into<T: DynamicsScalar>(
    joint: &JointModel,
    single: Option<SingleMotion>,
    q: &[T],
    rates: &[T],
    out: &mut ChainMotion<T>,
) -> Result<(), EvalError> {
    if let (Some(q), Some(rates)) = (T::plain(q), T::plain(rates)) {
        if let Some(out) = T::plain_motion(out) {
            // The rotation `JointModel::chain_motion_into` takes for a single motion.
            let Some(single) = single else {
                return joint.chain_motion_into(q, Some(rates), out);
            };
            single.motion_into(q, Some(rates), spatial::rotation, out);
            return Ok(());
        }
    }
    let single = single.ok_or(NOT_DIFFERENTIABLE)?;
    single.motion_into(q, Some(rates), spatial::smooth_rotation, out);
    Ok(())
}

/// Loop `k`'s six rows of G and, `with_bias`, of γ, at the chain and point `loop_residual` left.
fn loop_rows<T: Real>(
    model: &Model,
    data: &Data<T>,
    k: usize,
    with_bias: bool,
    c: &mut Constraints<T>,
) {
    let joint = &model.loops[k];
    let offset = model.loop_offset(k);
    let ball = model.loop_balls[k].is_some();
    let chain = &c.chains[k];
    let base = c.bases[k];
    let point = c.points[k];
    let row = 6 * k;
    // Rates are taken at the loop point, in fixed axes.
    let own = if ball { 0 } else { joint.coordinate_count() };
    let block = &mut c.jacobian.blocks[k];
    block.values.as_mut_slice().fill(T::zero());
    for &(local, column, sign) in &c.path_signs[k] {
        let moved = spatial::shifted(&point, &c.world_columns[column]);
        block
            .values
            .column_mut(local)
            .copy_from(&(moved * constant::<T>(sign)));
    }
    for column in 0..own {
        let twist = motion_to_parent(
            &base,
            &Motion::from_column_slice(chain.subspace.column(column).as_slice()),
        );
        let moved = spatial::shifted(&point, &twist);
        let local = block.local(model.nv + offset + column);
        let mut target_column = block.values.column_mut(local);
        target_column -= moved;
    }
    if with_bias {
        // World-frame spatial accelerations are the derivatives of world-frame spatial twists, so
        // γ is the difference of the two frames' accelerations at zero joint accelerations.
        let world = |motions: &[Motion<T>], body: usize| {
            spatial::motion_to_parent(&data.world[body], &motions[body])
        };
        let first_velocity = world(&data.velocity, joint.first_body);
        let chain_velocity = motion_to_parent(&base, &chain.velocity);
        let mut end_acceleration = world(&data.acceleration, joint.first_body)
            + spatial::cross_motion(&first_velocity, &chain_velocity);
        // Zero for a chain of one rotation or translation proportional to its coordinate.
        if chain.bias != Motion::zeros() {
            end_acceleration += motion_to_parent(&base, &chain.bias);
        }
        let difference = world(&data.acceleration, joint.second_body) - end_acceleration;
        c.bias
            .rows_mut(row, 6)
            .copy_from(&spatial::shifted(&point, &difference));
        if ball {
            // The point rows are the relative velocity at a moving point p: d/dt adds
            // (ω_T − ω_E) × ṗ, which vanishes when the rotation rows hold (ω_T = ω_E).
            let second_velocity = world(&data.velocity, joint.second_body);
            let relative_spin = (second_velocity - first_velocity)
                .fixed_rows::<3>(0)
                .into_owned();
            let point_velocity = spatial::shifted(&point, &first_velocity)
                .fixed_rows::<3>(3)
                .into_owned();
            let mut linear = c.bias.rows_mut(row + 3, 3);
            linear += relative_spin.cross(&point_velocity);
        }
    }
    if ball {
        c.jacobian.blocks[k].values.rows_mut(0, 3).fill(T::zero());
        c.bias.rows_mut(row, 3).fill(T::zero());
    }
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

/// `seat_ball_angles` without rates, when `data` already holds the bodies' poses at q.
pub fn seat_ball_angles_at_poses(
    model: &Model,
    data: &Data,
    q: &mut [f64],
    v: &mut [f64],
) -> Result<(), EvalError> {
    seat_balls(model, data, q, v, false)
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
        let angles = crate::dynamics::angles::angles_from_rotation(axes, &relative, &previous);
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
        let subspace = joint.chain(&angles)?.1;
        let rates = crate::linalg::pseudo_inverse(subspace.rows(0, 3).into_owned(), 1e-12)
            .map(|p| p * omega)
            .unwrap_or_else(|| DVector::zeros(3));
        v[model.nv + start..model.nv + start + 3].copy_from_slice(rates.as_slice());
    }
    Ok(())
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
