//! Forward kinematics: the pose of every body and its spatial Jacobian (world twist per unit
//! coordinate rate) from the mechanism's coordinates, walking the tree parent-first.

use nalgebra::DMatrix;

use super::eval::EvalError;
use super::model::{JointModel, KinematicModel};
use crate::spatial::{self, Pose, Twist};
use crate::topology::TreeLink;

pub struct Configuration {
    /// Pose of body j at index j; index 0 is earth.
    pub poses: Vec<Pose>,
    /// World-frame twist per unit rate of each coordinate (6 × coordinate count): a coordinate
    /// moves every body below its joint with this one twist. A body's Jacobian is these columns
    /// over the coordinates on its path to earth, zero elsewhere (`jacobian`); stored by column
    /// rather than per body, a chain of N bodies costs N columns instead of N Jacobians of N.
    pub columns: DMatrix<f64>,
    /// Per body, its parent body and the range of the coordinates of the joint to it (earth:
    /// itself and none).
    links: Vec<(usize, std::ops::Range<usize>)>,
}

impl Configuration {
    /// The coordinates that move body j (those on its path to earth), in increasing order.
    pub fn path_columns(&self, j: usize) -> Vec<usize> {
        let mut columns = Vec::new();
        let mut body = j;
        while body != 0 {
            let (parent, range) = &self.links[body];
            columns.extend(range.clone());
            body = *parent;
        }
        columns.sort_unstable();
        columns
    }

    /// World-frame twist of body j per unit rate of each coordinate (6 × coordinate count).
    pub fn jacobian(&self, j: usize) -> DMatrix<f64> {
        let mut jacobian = DMatrix::zeros(6, self.columns.ncols());
        for c in self.path_columns(j) {
            jacobian.set_column(c, &self.columns.column(c));
        }
        jacobian
    }

    /// The world twist of coordinate c's unit rate.
    pub fn column(&self, c: usize) -> Twist {
        Twist::from_column_slice(self.columns.column(c).as_slice())
    }

    /// Twist of body j (world frame) for coordinate rates `v`: the columns on its path, summed
    /// in the coordinates' order (the dense product's order, its zero terms left out).
    pub fn twist(&self, j: usize, v: &[f64]) -> Twist {
        self.path_columns(j)
            .into_iter()
            .fold(Twist::zeros(), |sum, c| sum + self.column(c) * v[c])
    }
}

pub fn forward(model: &KinematicModel, q: &[f64]) -> Result<Configuration, EvalError> {
    let n = model.topology.body_count();
    let nq = model.coordinate_count;
    let mut poses = vec![Pose::identity(); n + 1];
    let mut columns = DMatrix::zeros(6, nq);
    let mut links = vec![(0, 0..0); n + 1];
    for link in &model.topology.principal {
        let joint = &model.joints[link.child - 1];
        let coordinates = &q[joint.offset..joint.offset + joint.coordinate_count()];
        let (chain, subspace) = joint.chain(coordinates)?;
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
            columns.set_column(joint.offset + k, &world);
        }
        poses[link.child] = child_pose;
        links[link.child] = (
            link.parent,
            joint.offset..joint.offset + joint.coordinate_count(),
        );
    }
    Ok(Configuration {
        poses,
        columns,
        links,
    })
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
