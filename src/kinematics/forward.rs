//! Forward kinematics: the pose of every body and its spatial Jacobian (world twist per unit
//! coordinate rate) from the mechanism's coordinates, walking the tree parent-first.

use nalgebra::DMatrix;

use super::eval::EvalError;
use super::model::{JointModel, KinematicModel};
use crate::topology::TreeLink;
use crate::spatial::{self, Pose, Twist};

pub struct Configuration {
    /// Pose of body j at index j; index 0 is earth.
    pub poses: Vec<Pose>,
    /// World-frame twist of body j per unit rate of each coordinate (6 × coordinate count).
    pub jacobians: Vec<DMatrix<f64>>,
}

impl Configuration {
    /// Twist of body j (world frame) for coordinate rates `v`.
    pub fn twist(&self, j: usize, v: &[f64]) -> Twist {
        let product = &self.jacobians[j] * nalgebra::DVector::from_column_slice(v);
        Twist::from_column_slice(product.as_slice())
    }
}

pub fn forward(model: &KinematicModel, q: &[f64]) -> Result<Configuration, EvalError> {
    let n = model.topology.body_count();
    let nq = model.coordinate_count;
    let mut poses = vec![Pose::identity(); n + 1];
    let mut jacobians = vec![DMatrix::zeros(6, nq); n + 1];
    for link in &model.topology.principal {
        let joint = &model.joints[link.child - 1];
        let coordinates = &q[joint.offset..joint.offset + joint.coordinate_count()];
        let (chain, subspace) = joint.chain(coordinates)?;
        let mut jacobian = jacobians[link.parent].clone();
        let (base, child_pose) = placed(link, joint, poses[link.parent], &chain);
        let inverse_chain = chain.inverse();
        for k in 0..joint.coordinate_count() {
            let column = Twist::from_column_slice(subspace.column(k).as_slice());
            // Reversed traversal: the child moves with the inverse chain, whose twist in the
            // base frame is -Ad(D⁻¹) S.
            let local = if link.first_on_parent {
                column
            } else {
                -spatial::motion_to_parent(&inverse_chain, &column)
            };
            let world = spatial::motion_to_parent(&base, &local);
            for r in 0..6 {
                jacobian[(r, joint.offset + k)] += world[r];
            }
        }
        poses[link.child] = child_pose;
        jacobians[link.child] = jacobian;
    }
    Ok(Configuration { poses, jacobians })
}

/// The pose of every body alone (index 0 is earth), without the Jacobians, whose 6 × n entries
/// per body a long chain cannot afford where only the poses are read.
pub fn poses(model: &KinematicModel, q: &[f64]) -> Result<Vec<Pose>, EvalError> {
    let mut poses = vec![Pose::identity(); model.topology.body_count() + 1];
    for link in &model.topology.principal {
        let joint = &model.joints[link.child - 1];
        let coordinates = &q[joint.offset..joint.offset + joint.coordinate_count()];
        let (chain, _) = joint.chain(coordinates)?;
        poses[link.child] = placed(link, joint, poses[link.parent], &chain).1;
    }
    Ok(poses)
}

/// The frame the joint's motion is expressed in (its frame on the parent) and the child's pose,
/// for the joint's displacement `chain`, from the parent's pose.
fn placed(link: &TreeLink, joint: &JointModel, parent_pose: Pose, chain: &Pose) -> (Pose, Pose) {
    if link.first_on_parent {
        let base = parent_pose * joint.first;
        (base, base * chain * joint.second.inverse())
    } else {
        let base = parent_pose * joint.second;
        (base, base * chain.inverse() * joint.first.inverse())
    }
}
