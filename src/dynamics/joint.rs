//! Joints for the dynamics. Every join of the tree becomes one of:
//! - `Chain`: any dof chain, in its own coordinates (as many positions as velocities);
//! - `Spherical`: three rotations with one coordinate each (Euler or Bryant angles), integrated
//!   as a unit quaternion with the body angular velocity as velocity, so nothing fails at
//!   gimbal lock;
//! - `Free`: a translation `[x, y, z]` followed by three such rotations: position and unit
//!   quaternion, with the body twist as velocity.
//!
//! The angles the program declared are recovered from the quaternion for outputs and for the
//! expressions that use them.
//!
//! Conventions: the join relates frame A (first) and B (second) through D(q): pose(A)·D = pose(B).
//! The part that moves with the child, M, is D when A is on the parent and D⁻¹ otherwise, so the
//! child's pose in the parent is F_p · M · F_c⁻¹ with F_p, F_c the join's frames on the parent
//! and the child.

use nalgebra::{Matrix3, Quaternion, Rotation3, Translation3, Unit, UnitQuaternion, Vector3};

use super::scalar::{DynamicsScalar, NOT_DIFFERENTIABLE};
use crate::diag::Diagnostic;
use crate::elab::mechanism::{Link, Mechanism};
use crate::elab::value::SExpr;
use crate::kinematics::eval::EvalError;
use crate::kinematics::model::{linear_in_first, ChainMotion, JointModel, Step};
use crate::source::Span;
use crate::spatial::{self, constant, Force, Motion, Pose, Real, Transform};

#[derive(Clone, Debug, PartialEq)]
pub enum JointType {
    Chain,
    Spherical { axes: [Vector3<f64>; 3] },
    Free { axes: [Vector3<f64>; 3] },
}

#[derive(Clone, Debug)]
pub struct Joint {
    pub chain: JointModel,
    pub kind: JointType,
    pub parent: usize,
    pub child: usize,
    /// Whether the join's first frame is on the parent.
    pub first_on_parent: bool,
    /// The join's frames on the parent and on the child.
    pub on_parent: Pose,
    pub on_child: Pose,
    pub q_offset: usize,
    pub v_offset: usize,
    pub kernel: Kernel,
    /// The body the joint's transform is relative to: `parent`, or the body a welded parent is
    /// merged into (see `welds`).
    pub dynamic_parent: usize,
}

/// A joint's motion subspace in the child's frame: one column (a motion) per velocity, at most
/// six, stored inline so the algorithms allocate nothing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Subspace<T: Real = f64> {
    columns: [Motion<T>; 6],
    len: usize,
}

impl<T: Real> Subspace<T> {
    pub fn empty() -> Subspace<T> {
        Subspace {
            columns: [Motion::zeros(); 6],
            len: 0,
        }
    }

    /// Empties the subspace without touching its storage.
    pub fn clear(&mut self) {
        self.len = 0;
    }

    /// Makes the subspace the single column `column`, writing only that column.
    pub fn set_single(&mut self, column: Motion<T>) {
        self.columns[0] = column;
        self.len = 1;
    }

    pub fn push(&mut self, column: Motion<T>) {
        self.columns[self.len] = column;
        self.len += 1;
    }

    pub fn len(&self) -> usize {
        self.len
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    pub fn column(&self, k: usize) -> &Motion<T> {
        &self.columns[..self.len][k]
    }

    pub fn columns(&self) -> &[Motion<T>] {
        &self.columns[..self.len]
    }

    /// `S x`: the motion of the joint velocities (or accelerations) `x`.
    #[inline]
    pub fn apply(&self, x: &[T]) -> Motion<T> {
        self.columns()
            .iter()
            .zip(x)
            .fold(Motion::zeros(), |sum, (c, xi)| sum + c * *xi)
    }

    /// `Sᵀ f` into `out`: the generalised forces of a spatial force.
    #[inline]
    pub fn project(&self, f: &Force<T>, out: &mut [T]) {
        for (o, c) in out.iter_mut().zip(self.columns()) {
            *o = c.dot(f);
        }
    }
}

/// How a joint's pose and subspace are computed, decided once when the model is built. Most
/// joints of real robots are one rotation or one translation along a fixed axis, or a weld:
/// these need no evaluation of the dof chain, their subspace is constant in the child frame,
/// and their transform is computed directly as a matrix.
#[derive(Clone, Debug, PartialEq)]
pub enum Kernel {
    /// No coordinate: the child's pose in the parent is constant.
    Weld { transform: Transform },
    /// The moving part M is a rotation by θ = `scale` · q about a unit axis a of the join's
    /// first frame. With the join frame on the parent (P) first, P·M has the rotation
    /// cos θ · R_P + sin θ · R_P â + (1 − cos θ) · R_P a aᵀ (Rodrigues, the three matrices
    /// computed once) and the translation of P; `after` is the child's join frame inverted,
    /// absent when it is the identity.
    /// When the axis is ±x, ±y or ±z (`aligned`, the sign folded into `scale`), only two columns
    /// of R_P turn: 12 products instead of Rodrigues's 27.
    Rotation {
        terms: [Matrix3<f64>; 3],
        aligned: Option<usize>,
        origin: Vector3<f64>,
        scale: f64,
        after: Option<Transform>,
        column: Motion,
    },
    /// The moving part M is a translation by q · d: P·M has P's rotation and the translation
    /// origin + q · R_P d.
    Translation {
        rotation: Matrix3<f64>,
        origin: Vector3<f64>,
        direction: Vector3<f64>,
        after: Option<Transform>,
        column: Motion,
    },
    /// Anything else: the dof chain is evaluated at each state.
    General,
}

/// A joint at given positions and velocities, in the child's frame.
#[derive(Clone, Debug)]
pub struct JointState<T: Real = f64> {
    /// Pose of the child in the parent, and the same as a matrix transform.
    pub pose: Pose<T>,
    pub transform: Transform<T>,
    /// Motion subspace, 6 × nv.
    pub subspace: Subspace<T>,
    /// Joint velocity `S v` and its bias `Ṡ v`.
    pub velocity: Motion<T>,
    pub bias: Motion<T>,
    /// A general dof chain's motion (scratch kept between evaluations, in `f64` whatever the
    /// scalar: only `f64` evaluates the chain's expressions, see `DynamicsScalar`).
    pub(super) chain: ChainMotion,
}

impl<T: Real> JointState<T> {
    fn empty() -> JointState<T> {
        JointState {
            pose: Pose::identity(),
            transform: Transform::identity(),
            subspace: Subspace::empty(),
            velocity: Motion::zeros(),
            bias: Motion::zeros(),
            chain: ChainMotion::default(),
        }
    }
}

fn is_coordinate(s: &SExpr, index: u32) -> bool {
    matches!(s, SExpr::Coordinate { index: i, order: 0 } if *i == index)
}

/// The joint type a dof chain calls for.
pub fn classify(chain: &JointModel) -> JointType {
    let rotations = |steps: &[Step], first: u32| -> Option<[Vector3<f64>; 3]> {
        let mut axes = [Vector3::zeros(); 3];
        for (k, step) in steps.iter().enumerate() {
            match step {
                Step::Rotation { angle, axis } if is_coordinate(angle, first + k as u32) => {
                    axes[k] = *axis
                }
                _ => return None,
            }
        }
        // Consecutive axes must not be parallel, or the three angles do not span rotations.
        let independent =
            axes[0].cross(&axes[1]).norm() > 1e-9 && axes[1].cross(&axes[2]).norm() > 1e-9;
        independent.then_some(axes)
    };
    if !chain.prescribed.is_empty() {
        // A rheonomic chain's hidden coordinates are driven one by one: no quaternion.
        return JointType::Chain;
    }
    match chain.steps.as_slice() {
        [a, b, c] if chain.coordinate_count() == 3 => {
            match rotations(&[a.clone(), b.clone(), c.clone()], 0) {
                Some(axes) => JointType::Spherical { axes },
                None => JointType::Chain,
            }
        }
        [Step::Translation(t), rest @ ..] if rest.len() == 3 && chain.coordinate_count() == 6 => {
            let translation = (0..3).all(|i| is_coordinate(&t[i], i as u32));
            match rotations(rest, 3) {
                Some(axes) if translation => JointType::Free { axes },
                _ => JointType::Chain,
            }
        }
        _ => JointType::Chain,
    }
}

/// The transform of a one-rotation kernel at angle θ.
fn rotation_transform<T: Real>(
    terms: &[Matrix3<f64>; 3],
    aligned: Option<usize>,
    origin: &Vector3<f64>,
    angle: T,
    after: &Option<Transform>,
) -> Transform<T> {
    let (sin, cos) = angle.sin_cos();
    let rotation = match aligned {
        Some(k) => turn_columns(&terms[0].cast(), k, sin, cos),
        None => {
            terms[0].cast::<T>() * cos
                + terms[1].cast::<T>() * sin
                + terms[2].cast::<T>() * (T::one() - cos)
        }
    };
    with_after(
        Transform {
            rotation,
            translation: origin.cast(),
        },
        after,
    )
}

/// The constant part on the child's side, when there is one.
fn with_after<T: Real>(transform: Transform<T>, after: &Option<Transform>) -> Transform<T> {
    match after {
        Some(after) => transform * lift_transform(after),
        None => transform,
    }
}

/// A constant transform of the model in the scalar of a computation.
fn lift_transform<T: Real>(t: &Transform) -> Transform<T> {
    Transform {
        rotation: t.rotation.cast(),
        translation: t.translation.cast(),
    }
}

/// R · Rot(e_k, θ) from sin θ and cos θ: column k stays, the two others turn in their plane.
pub(crate) fn turn_columns<T: Real>(r: &Matrix3<T>, k: usize, sin: T, cos: T) -> Matrix3<T> {
    let (i, j) = ((k + 1) % 3, (k + 2) % 3);
    let (ri, rj) = (r.column(i), r.column(j));
    let mut out = *r;
    out.set_column(i, &(ri * cos + rj * sin));
    out.set_column(j, &(rj * cos - ri * sin));
    out
}

/// `turn_columns` written into `out`.
pub(crate) fn turn_columns_into(
    r: &Matrix3<f64>,
    k: usize,
    sin: f64,
    cos: f64,
    out: &mut Matrix3<f64>,
) {
    let (i, j) = ((k + 1) % 3, (k + 2) % 3);
    for row in 0..3 {
        let (ri, rj) = (r[(row, i)], r[(row, j)]);
        out[(row, k)] = r[(row, k)];
        out[(row, i)] = ri * cos + rj * sin;
        out[(row, j)] = rj * cos - ri * sin;
    }
}

/// The index of the coordinate axis `axis` lies along, and the sign, if it does.
fn coordinate_axis(axis: &Vector3<f64>) -> Option<(usize, f64)> {
    (0..3)
        .find(|&k| axis[k].abs() == 1.0 && (0..3).all(|m| m == k || axis[m] == 0.0))
        .map(|k| (k, axis[k]))
}

/// The child's join frame inverted, or nothing when it is the identity (as in imported URDF).
fn after_motion(on_child: &Pose) -> Option<Transform> {
    (*on_child != Pose::identity()).then(|| Transform::from_pose(&on_child.inverse()))
}

/// The kernel for a joint: a weld, one rotation or translation linear in the joint's single
/// coordinate, or the general evaluation.
pub fn kernel(joint: &Joint) -> Kernel {
    let chain = &joint.chain;
    if chain.coordinate_count() == 0 {
        return match chain.chain_motion(&[], None) {
            Ok(motion) => {
                let moving = if joint.first_on_parent {
                    motion.pose
                } else {
                    motion.pose.inverse()
                };
                Kernel::Weld {
                    transform: Transform::from_pose(
                        &(joint.on_parent * moving * joint.on_child.inverse()),
                    ),
                }
            }
            Err(_) => Kernel::General,
        };
    }
    if chain.coordinate_count() != 1 || joint.kind != JointType::Chain {
        return Kernel::General;
    }
    // The moving part is D when the first frame is on the parent, D⁻¹ otherwise: the sign.
    let sign = if joint.first_on_parent { 1.0 } else { -1.0 };
    let (on_parent, on_child) = (Transform::from_pose(&joint.on_parent), joint.on_child);
    let after = after_motion(&on_child);
    match chain.steps.as_slice() {
        [Step::Rotation { angle, axis }] => {
            match (linear_in_first(angle), Unit::try_new(*axis, 1e-12)) {
                (Some(scale), Some(unit)) if scale != 0.0 => {
                    let unit_twist = Motion::new(unit.x, unit.y, unit.z, 0.0, 0.0, 0.0);
                    let column = spatial::motion_to_parent(&on_child, &unit_twist) * (sign * scale);
                    let r = on_parent.rotation;
                    let terms = [
                        r,
                        r * spatial::skew(&unit),
                        r * (unit.into_inner() * unit.transpose()),
                    ];
                    let (aligned, scale) = match coordinate_axis(&unit) {
                        Some((k, direction)) => (Some(k), sign * scale * direction),
                        None => (None, sign * scale),
                    };
                    Kernel::Rotation {
                        terms,
                        aligned,
                        origin: on_parent.translation,
                        scale,
                        after,
                        column,
                    }
                }
                _ => Kernel::General,
            }
        }
        [Step::Translation(t)] => match (
            linear_in_first(&t[0]),
            linear_in_first(&t[1]),
            linear_in_first(&t[2]),
        ) {
            (Some(x), Some(y), Some(z)) if (x, y, z) != (0.0, 0.0, 0.0) => {
                let column =
                    spatial::motion_to_parent(&on_child, &Motion::new(0.0, 0.0, 0.0, x, y, z))
                        * sign;
                let direction = on_parent.rotation * Vector3::new(x, y, z) * sign;
                Kernel::Translation {
                    rotation: on_parent.rotation,
                    origin: on_parent.translation,
                    direction,
                    after,
                    column,
                }
            }
            _ => Kernel::General,
        },
        _ => Kernel::General,
    }
}

impl Joint {
    /// Whether the joint has one coordinate that the state holds as it is, its rate the one
    /// velocity (a revolute or prismatic link): the joints stops, rotors, couplings and
    /// friction act on.
    pub fn is_single_coordinate(&self) -> bool {
        self.kind == JointType::Chain && self.chain.coordinate_count() == 1
    }

    /// `swing.q`: the name of the joint's first coordinate, as the outputs give it.
    pub fn coordinate_label(&self) -> String {
        format!("{}.{}", self.chain.name, self.chain.coordinate_names[0])
    }

    pub fn nq(&self) -> usize {
        match self.kind {
            JointType::Chain => self.chain.coordinate_count(),
            JointType::Spherical { .. } => 4,
            JointType::Free { .. } => 7,
        }
    }

    pub fn nv(&self) -> usize {
        match self.kind {
            JointType::Chain => self.chain.coordinate_count(),
            JointType::Spherical { .. } => 3,
            JointType::Free { .. } => 6,
        }
    }

    /// A state for this joint: the constant subspace of a one-rotation or one-translation
    /// kernel is written here, once, and `update` leaves it alone.
    pub fn new_state<T: Real>(&self) -> JointState<T> {
        let mut state = JointState::empty();
        if let Kernel::Rotation { column, .. } | Kernel::Translation { column, .. } = &self.kernel {
            state.subspace.set_single(column.cast());
        }
        state
    }

    /// The transform of a weld, one-rotation or one-translation kernel at positions q; `None`
    /// for the general kernel, whose transform comes with its whole state (`update`).
    fn kernel_transform<T: Real>(&self, q: &[T]) -> Option<Transform<T>> {
        match &self.kernel {
            Kernel::Weld { transform } => Some(lift_transform(transform)),
            Kernel::Rotation {
                terms,
                aligned,
                origin,
                scale,
                after,
                ..
            } => Some(rotation_transform(
                terms,
                *aligned,
                origin,
                q[0] * constant(*scale),
                after,
            )),
            Kernel::Translation {
                rotation,
                origin,
                direction,
                after,
                ..
            } => Some(with_after(
                Transform {
                    rotation: rotation.cast(),
                    translation: origin.cast() + direction.cast() * q[0],
                },
                after,
            )),
            Kernel::General => None,
        }
    }

    /// For the commonest joint of imported robots, a revolute about x, y or z with no frame on
    /// the child: the axis's index k and the factor s of its coordinate (θ = s q). Its motion
    /// subspace is the constant column [s e_k; 0] in the child's frame.
    pub fn axis_rotation(&self) -> Option<(usize, f64)> {
        match &self.kernel {
            Kernel::Rotation {
                aligned: Some(k),
                scale,
                after: None,
                ..
            } => Some((*k, *scale)),
            _ => None,
        }
    }

    /// The transform alone at positions q (for the mass matrix, which needs no velocities).
    pub fn update_transform(&self, q: &[f64], state: &mut JointState) -> Result<(), EvalError> {
        if let (Some((k, scale)), Kernel::Rotation { terms, origin, .. }) =
            (self.axis_rotation(), &self.kernel)
        {
            // `rotation_transform`'s arithmetic, written in place.
            let (sin, cos) = (q[0] * scale).sin_cos();
            turn_columns_into(&terms[0], k, sin, cos, &mut state.transform.rotation);
            state.transform.translation = *origin;
            return Ok(());
        }
        match self.kernel_transform(q) {
            Some(transform) => state.transform = transform,
            None => self.update(q, &[0.0; 6][..self.nv()], state)?,
        }
        Ok(())
    }

    /// Writes the joint's state at (q, v) into `state` (made by `new_state`), reusing its
    /// storage: its transform, subspace, velocity and bias. `state.pose` is left as it was for
    /// the one-rotation, one-translation and weld kernels; `forward_kinematics` sets it (see
    /// `fill_pose`).
    pub fn update<T: DynamicsScalar>(
        &self,
        q: &[T],
        v: &[T],
        state: &mut JointState<T>,
    ) -> Result<(), EvalError> {
        if let Some(transform) = self.kernel_transform(q) {
            state.transform = transform;
            match &self.kernel {
                Kernel::Rotation { column, .. } | Kernel::Translation { column, .. } => {
                    state.velocity = column.cast() * v[0];
                }
                _ => {
                    state.subspace.clear();
                    state.velocity = Motion::zeros();
                }
            }
            state.bias = Motion::zeros();
            return Ok(());
        }
        if self.kind == JointType::Chain {
            match (T::plain(q), T::plain(v)) {
                (Some(q), Some(v)) => self.chain_state(q, v, state)?,
                _ => return Err(NOT_DIFFERENTIABLE),
            }
        } else {
            self.quaternion_state(q, v, state);
        }
        state.transform = Transform::from_pose(&state.pose);
        Ok(())
    }

    /// Sets `state.pose` from the transform where `update` did not compute it.
    pub fn fill_pose<T: Real>(&self, state: &mut JointState<T>) {
        if !matches!(self.kernel, Kernel::General) {
            let rotation = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(
                state.transform.rotation,
            ));
            state.pose =
                Pose::from_parts(Translation3::from(state.transform.translation), rotation);
        }
    }

    /// A general dof chain's pose, subspace, velocity and bias, its expressions evaluated at
    /// (q, v) (in `f64`: `DynamicsScalar`).
    fn chain_state<T: Real>(
        &self,
        q: &[f64],
        v: &[f64],
        state: &mut JointState<T>,
    ) -> Result<(), EvalError> {
        self.chain.chain_motion_into(q, Some(v), &mut state.chain)?;
        let motion = &state.chain;
        let d = motion.pose;
        // Twists of D (in the first frame) seen in the child frame: through B·D⁻¹ when the first
        // frame is on the parent, through −A when it is on the child (the child moves with D⁻¹).
        let (to_child, sign) = if self.first_on_parent {
            (self.on_child * d.inverse(), 1.0)
        } else {
            (self.on_child, -1.0)
        };
        state.subspace.clear();
        for k in 0..self.nv() {
            let column = Motion::from_column_slice(motion.subspace.column(k).as_slice());
            let column = sign * spatial::motion_to_parent(&to_child, &column);
            state.subspace.push(column.cast());
        }
        let moving = if self.first_on_parent { d } else { d.inverse() };
        state.pose = (self.on_parent * moving * self.on_child.inverse()).cast();
        state.velocity = (sign * spatial::motion_to_parent(&to_child, &motion.velocity)).cast();
        state.bias = (sign * spatial::motion_to_parent(&to_child, &motion.bias)).cast();
        Ok(())
    }

    /// Spherical and free joints: M = Trans(p)·Rot(Q) with the body twist of M as velocity, so
    /// the subspace is constant in the child frame and the bias vanishes.
    fn quaternion_state<T: Real>(&self, q: &[T], v: &[T], state: &mut JointState<T>) {
        let (moving, n) = match self.kind {
            JointType::Free { .. } => (
                Pose::from_parts(Translation3::new(q[0], q[1], q[2]), quaternion(&q[3..7])),
                6,
            ),
            _ => (
                Pose::from_parts(Translation3::identity(), quaternion(&q[0..4])),
                3,
            ),
        };
        let (on_parent, on_child): (Pose<T>, Pose<T>) =
            (self.on_parent.cast(), self.on_child.cast());
        state.subspace.clear();
        for k in 0..n {
            // Velocity layout: angular velocity first, then (free joints) linear velocity.
            let mut unit = Motion::zeros();
            unit[k] = T::one();
            state
                .subspace
                .push(spatial::motion_to_parent(&on_child, &unit));
        }
        state.velocity = state.subspace.apply(v);
        state.pose = on_parent * moving * on_child.inverse();
        state.bias = Motion::zeros();
    }

    /// dq/dt from the velocities.
    pub fn position_rate(&self, q: &[f64], v: &[f64], rate: &mut [f64]) {
        match self.kind {
            JointType::Chain => rate.copy_from_slice(v),
            JointType::Spherical { .. } => quaternion_rate(&q[0..4], &v[0..3], rate),
            JointType::Free { .. } => {
                let rotation = quaternion(&q[3..7]);
                let linear = rotation * Vector3::new(v[3], v[4], v[5]);
                rate[0..3].copy_from_slice(linear.as_slice());
                quaternion_rate(&q[3..7], &v[0..3], &mut rate[3..7]);
            }
        }
    }

    /// Brings the quaternion back to unit length after an integration step.
    pub fn normalize(&self, q: &mut [f64]) {
        let range = match self.kind {
            JointType::Chain => return,
            JointType::Spherical { .. } => 0..4,
            JointType::Free { .. } => 3..7,
        };
        let norm = q[range.clone()].iter().map(|x| x * x).sum::<f64>().sqrt();
        if norm > 0.0 {
            q[range].iter_mut().for_each(|x| *x /= norm);
        }
    }
}

/// (w, x, y, z) → unit quaternion.
pub fn quaternion<T: Real>(q: &[T]) -> UnitQuaternion<T> {
    UnitQuaternion::from_quaternion(Quaternion::new(q[0], q[1], q[2], q[3]))
}

/// dQ/dt = ½ Q ⊗ (0, ω) for the body angular velocity ω.
fn quaternion_rate(q: &[f64], w: &[f64], rate: &mut [f64]) {
    let (qw, qx, qy, qz) = (q[0], q[1], q[2], q[3]);
    let (wx, wy, wz) = (w[0], w[1], w[2]);
    rate[0] = 0.5 * (-qx * wx - qy * wy - qz * wz);
    rate[1] = 0.5 * (qw * wx + qy * wz - qz * wy);
    rate[2] = 0.5 * (qw * wy - qx * wz + qz * wx);
    rate[3] = 0.5 * (qw * wz + qx * wy - qy * wx);
}

/// One refusal per chain of `chains` whose link declares a field the run cannot simulate there
/// (`declared`): `refusal` builds it from the chain's name and the span of its join.
pub fn refuse_declared<'a>(
    mechanism: &Mechanism,
    chains: impl IntoIterator<Item = &'a JointModel>,
    declared: impl Fn(&Link) -> bool,
    refusal: impl Fn(&str, Span) -> Diagnostic,
    errors: &mut Vec<Diagnostic>,
) {
    for chain in chains {
        let join = mechanism.join(chain.join);
        if declared(mechanism.link(join.link)) {
            errors.push(refusal(&chain.name, join.span));
        }
    }
}
