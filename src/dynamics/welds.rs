//! Welded bodies merged into the body they are welded to, for the recursive algorithms.
//!
//! A body joined to its parent by a weld moves with it: RNEA, CRBA and ABA need only the sum of
//! the two inertias, not one more body to carry through every pass (a humanoid's URDF has as
//! many sensor and tool frames as moving joints). A welded body is merged into its *anchor*, the
//! nearest ancestor reached through a moving joint, when nothing acts on it alone: no effort is
//! applied to it, no loop closes on it, and every joint below it is a one-rotation,
//! one-translation or weld kernel (so the anchor's offset folds into their constant terms).
//!
//! The anchor may be earth: a fixed-base robot's URDF welds its base link to the world, and that
//! body, at rest whatever the state, would otherwise cost a joint's transform, a world pose and
//! a composite inertia in every pass (one joint in seven on UR5). Its inertia then counts
//! nowhere in the algorithms, as it takes no part in the motion; a body that carries a rotor is
//! kept (the rotor's spin is the algorithms' business, and earth carries nothing).
//!
//! Every joint's transform is then relative to its `dynamic_parent` (the anchor of its parent):
//! for a merged body, its constant pose in its anchor. The merged bodies keep their world poses,
//! velocities and names; only the algorithms' passes skip them.

use super::elements::{AppliedEffort, BodyInertia, LinkEffort};
use super::joint::{Joint, Kernel};
use crate::spatial::{Inertia, RigidInertia, Transform};

/// What merging gives the model.
pub struct Merged {
    /// The joints the algorithms' passes visit, in order: all but the merged welds.
    pub dynamic_joints: Vec<usize>,
    /// Per body, the inertia the algorithms use: its own and its merged bodies' for an anchor,
    /// nothing for a merged body.
    pub dynamic_bodies: Vec<BodyInertia>,
    /// Per body number (0 is earth), its pose in its anchor (identity for an anchor).
    pub anchor_offsets: Vec<Transform>,
}

/// Whether the weld of `joint` can be merged (see the module's comment).
fn mergeable(
    k: usize,
    joints: &[Joint],
    applied: &[AppliedEffort],
    link_efforts: &[LinkEffort],
    rotor_carriers: &[usize],
    has_loops: bool,
) -> bool {
    let joint = &joints[k];
    let child = joint.child;
    !has_loops
        && (joint.parent != 0 || !rotor_carriers.contains(&child))
        && matches!(joint.kernel, Kernel::Weld { .. })
        && !applied.iter().any(|e| e.body == child)
        && !link_efforts.iter().any(|e| e.joint == k)
        && joints
            .iter()
            .filter(|j| j.parent == child)
            .all(|j| !matches!(j.kernel, Kernel::General))
}

/// Merges the welds that can be, rewriting the joints' kernels and dynamic parents.
pub fn merge(
    joints: &mut [Joint],
    bodies: &[BodyInertia],
    applied: &[AppliedEffort],
    link_efforts: &[LinkEffort],
    rotor_carriers: &[usize],
    has_loops: bool,
) -> Merged {
    let n = joints.len();
    let mut offsets = vec![Transform::identity(); n + 1];
    let mut anchor: Vec<usize> = (0..=n).collect();
    let mut merged = vec![false; n];
    for k in 0..n {
        let (parent, child) = (joints[k].parent, joints[k].child);
        let parent_offset = offsets[parent];
        if mergeable(k, joints, applied, link_efforts, rotor_carriers, has_loops) {
            let Kernel::Weld { transform } = joints[k].kernel else {
                unreachable!("mergeable welds only")
            };
            offsets[child] = parent_offset * transform;
            anchor[child] = anchor[parent];
            merged[k] = true;
            joints[k].kernel = Kernel::Weld {
                transform: offsets[child],
            };
        } else if anchor[parent] != parent {
            joints[k].kernel = fold(&joints[k].kernel, &parent_offset);
        }
        joints[k].dynamic_parent = anchor[parent];
    }
    let mut dynamic_bodies: Vec<BodyInertia> = bodies.to_vec();
    for k in (0..n).filter(|&k| merged[k]).rev() {
        let child = joints[k].child;
        // Earth (anchor 0) takes no inertia: it does not move.
        if anchor[child] != 0 && !bodies[child - 1].massless {
            let moved = bodies[child - 1].rigid.to_parent(&offsets[child]);
            add_inertia(&mut dynamic_bodies[anchor[child] - 1], moved);
        }
        dynamic_bodies[child - 1] = BodyInertia {
            mass: 0.0,
            com: Default::default(),
            inertia: Inertia::zeros(),
            rigid: RigidInertia::zeros(),
            massless: true,
        };
    }
    Merged {
        dynamic_joints: (0..n).filter(|&k| !merged[k]).collect(),
        dynamic_bodies,
        anchor_offsets: offsets,
    }
}

/// Adds a rigid inertia (about the same origin) to a body's.
fn add_inertia(body: &mut BodyInertia, other: RigidInertia) {
    let mut rigid = if body.massless {
        RigidInertia::zeros()
    } else {
        body.rigid
    };
    rigid += other;
    body.mass = rigid.mass;
    body.com = if rigid.mass > 0.0 {
        rigid.first / rigid.mass
    } else {
        body.com
    };
    body.rigid = rigid;
    body.inertia = rigid.matrix();
    body.massless = rigid == RigidInertia::zeros();
}

/// A kernel whose joint hangs from a merged body, re-expressed from its anchor: the offset O of
/// the merged body in the anchor multiplies the constant part on the parent's side.
fn fold(kernel: &Kernel, offset: &Transform) -> Kernel {
    let (r, t) = (offset.rotation, offset.translation);
    match kernel {
        Kernel::Weld { transform } => Kernel::Weld {
            transform: *offset * *transform,
        },
        Kernel::Rotation {
            terms,
            aligned,
            origin,
            scale,
            after,
            column,
        } => Kernel::Rotation {
            terms: terms.map(|m| r * m),
            aligned: *aligned,
            origin: r * origin + t,
            scale: *scale,
            after: *after,
            column: *column,
        },
        Kernel::Translation {
            rotation,
            origin,
            direction,
            after,
            column,
        } => Kernel::Translation {
            rotation: r * rotation,
            origin: r * origin + t,
            direction: r * direction,
            after: *after,
            column: *column,
        },
        Kernel::General => unreachable!("joints below a merged body have constant-term kernels"),
    }
}
