//! Whether a mechanism's joints move its bodies in one plane, decided from the kinematic model
//! alone (no inertia, no effort: `lsdc tree` asks it without building any dynamics): every
//! joint of the tree and every complementary link a weld, or one rotation about an axis
//! parallel to one normal n, or one translation perpendicular to it. A joint's axis is fixed in
//! the body that carries its first frame, which then turns about n only, so the axes at one
//! configuration (every coordinate zero) decide every configuration.
//!
//! The planar form of the dynamics (`dynamics::planar::decide`) starts from this plane and asks
//! more of the model: its efforts, its gravity field and its other elements in the plane.

use nalgebra::Vector3;

use super::forward::poses;
use super::model::{JointModel, KinematicModel, SingleMotion};

/// How far from parallel (or perpendicular) two unit directions may be and still count as
/// such: the round-off of the frames' rotations (a turn by π/2 leaves cos(π/2) = 6e-17).
pub const ROUND_OFF: f64 = 1e-12;

/// A joint's one motion at every coordinate zero, in the fixed axes.
enum FixedMotion {
    Rotation(Vector3<f64>),
    Translation(Vector3<f64>),
}

/// The normal of the plane the joints move the bodies in (the axis of the first rotation, tree
/// joints first, its largest component made positive), or why there is none.
pub fn motion_plane(model: &KinematicModel) -> Result<Vector3<f64>, String> {
    let single = |joint: &JointModel| match joint.coordinate_count() {
        0 => Ok(None),
        _ => match joint.single_motion() {
            Some(motion) => Ok(Some(motion)),
            None => Err(format!(
                "`{}` is not one rotation or translation",
                joint.name
            )),
        },
    };
    let motions: Vec<(&JointModel, Option<SingleMotion>)> = (model.joints.iter())
        .map(|joint| single(joint).map(|motion| (joint, motion)))
        .collect::<Result<_, _>>()?;
    let zeros = vec![0.0; model.coordinate_count];
    let poses =
        poses(model, &zeros).map_err(|_| "its joints cannot be evaluated at zero".to_string())?;
    let fixed: Vec<(&JointModel, FixedMotion)> = (motions.into_iter())
        .filter_map(|(joint, motion)| {
            let rotation = (poses[joint.first_body] * joint.first).rotation;
            motion.map(|motion| match motion {
                SingleMotion::Rotation { axis, .. } => {
                    (joint, FixedMotion::Rotation(rotation * axis))
                }
                SingleMotion::Translation { direction } => {
                    (joint, FixedMotion::Translation(rotation * direction))
                }
            })
        })
        .collect();
    let first_axis = fixed.iter().find_map(|(_, motion)| match motion {
        FixedMotion::Rotation(axis) => Some(*axis),
        FixedMotion::Translation(_) => None,
    });
    let normal = (first_axis.and_then(|axis| axis.try_normalize(0.0)))
        .filter(|axis| axis.iter().all(|x| x.is_finite()))
        .ok_or("it has no revolute joint to set its plane")?;
    let normal = normal * normal[normal.iamax()].signum();
    for (joint, motion) in &fixed {
        // Written so that a value that is not a number refuses.
        let in_plane = match motion {
            FixedMotion::Rotation(axis) => axis.cross(&normal).norm() <= ROUND_OFF * axis.norm(),
            FixedMotion::Translation(direction) => {
                direction.dot(&normal).abs() <= ROUND_OFF * direction.norm()
            }
        };
        if !in_plane {
            return Err(format!(
                "`{}` moves out of the plane of the others",
                joint.name
            ));
        }
    }
    Ok(normal)
}
