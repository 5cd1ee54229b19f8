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

use nalgebra::{DMatrix, Quaternion, Translation3, UnitQuaternion, Vector3};

use super::spatial::{self, Motion, Pose};
use crate::kinematics::eval::{EvalError, UnknownValues};
use crate::kinematics::model::{JointModel, Step};
use crate::elab::value::SExpr;

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
}

/// A joint at given positions and velocities, in the child's frame.
pub struct JointState {
    /// Pose of the child in the parent.
    pub pose: Pose,
    /// Motion subspace, 6 × nv.
    pub subspace: DMatrix<f64>,
    /// Joint velocity `S v` and its bias `Ṡ v`.
    pub velocity: Motion,
    pub bias: Motion,
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
                Step::Rotation { angle, axis } if is_coordinate(angle, first + k as u32) => axes[k] = *axis,
                _ => return None,
            }
        }
        // Consecutive axes must not be parallel, or the three angles do not span rotations.
        let independent = axes[0].cross(&axes[1]).norm() > 1e-9 && axes[1].cross(&axes[2]).norm() > 1e-9;
        independent.then_some(axes)
    };
    match chain.steps.as_slice() {
        [a, b, c] if chain.coordinate_count() == 3 => match rotations(&[a.clone(), b.clone(), c.clone()], 0) {
            Some(axes) => JointType::Spherical { axes },
            None => JointType::Chain,
        },
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

impl Joint {
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

    /// Position, subspace, velocity and bias at the joint's positions `q` and velocities `v`.
    pub fn state(&self, q: &[f64], v: &[f64], unknowns: &UnknownValues) -> Result<JointState, EvalError> {
        match self.kind {
            JointType::Chain => self.chain_state(q, v, unknowns),
            JointType::Spherical { .. } | JointType::Free { .. } => Ok(self.quaternion_state(q, v)),
        }
    }

    fn chain_state(&self, q: &[f64], v: &[f64], unknowns: &UnknownValues) -> Result<JointState, EvalError> {
        let motion = self.chain.chain_motion(q, Some(v), unknowns)?;
        let d = motion.pose;
        let n = self.nv();
        let mut subspace = DMatrix::zeros(6, n);
        // Twists of D (in the first frame) seen in the child frame: through B·D⁻¹ when the first
        // frame is on the parent, through −A when it is on the child (the child moves with D⁻¹).
        let (to_child, sign) = if self.first_on_parent { (self.on_child * d.inverse(), 1.0) } else { (self.on_child, -1.0) };
        for k in 0..n {
            let column = Motion::from_column_slice(motion.subspace.column(k).as_slice());
            subspace.set_column(k, &(sign * spatial::motion_to_parent(&to_child, &column)));
        }
        let moving = if self.first_on_parent { d } else { d.inverse() };
        Ok(JointState {
            pose: self.on_parent * moving * self.on_child.inverse(),
            subspace,
            velocity: sign * spatial::motion_to_parent(&to_child, &motion.velocity),
            bias: sign * spatial::motion_to_parent(&to_child, &motion.bias),
        })
    }

    /// Spherical and free joints: M = Trans(p)·Rot(Q) with the body twist of M as velocity, so
    /// the subspace is constant in the child frame and the bias vanishes.
    fn quaternion_state(&self, q: &[f64], v: &[f64]) -> JointState {
        let (moving, n) = match self.kind {
            JointType::Free { .. } => (Pose::from_parts(Translation3::new(q[0], q[1], q[2]), quaternion(&q[3..7])), 6),
            _ => (Pose::from_parts(Translation3::identity(), quaternion(&q[0..4])), 3),
        };
        let mut subspace = DMatrix::zeros(6, n);
        for k in 0..n {
            // Velocity layout: angular velocity first, then (free joints) linear velocity.
            let mut unit = Motion::zeros();
            unit[k] = 1.0;
            subspace.set_column(k, &spatial::motion_to_parent(&self.on_child, &unit));
        }
        let velocity = &subspace * nalgebra::DVector::from_column_slice(v);
        JointState {
            pose: self.on_parent * moving * self.on_child.inverse(),
            subspace,
            velocity: Motion::from_column_slice(velocity.as_slice()),
            bias: Motion::zeros(),
        }
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
pub fn quaternion(q: &[f64]) -> UnitQuaternion<f64> {
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
