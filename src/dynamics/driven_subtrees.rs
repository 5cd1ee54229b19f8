//! Subtrees whose every coordinate is driven: kinematics, not dynamics.
//!
//! A driven coordinate's position, rate and acceleration are its law's. When every joint of a
//! subtree of the tree is driven (every one of its velocities follows a `drive` or a rheonomic
//! motion), the subtree has no unknown acceleration: its bodies move along the drives, and all
//! the rest of the tree needs of them is the force they transmit to their parent. This is
//! Featherstone's hybrid dynamics (*Rigid Body Dynamics Algorithms*, 2008, §9.2), the case of
//! known accelerations in the articulated-body algorithm: a joint whose acceleration is known
//! hands its whole articulated inertia and the bias of its known motion to its parent, and its
//! effort comes afterwards from Sᵀ (Iᴬ a + pᴬ); below a fully driven joint Iᴬ is the rigid
//! composite inertia and the effort is the subtree's inverse dynamics (RNEA with the known
//! accelerations). The drives are then no rows of the constraint stack, and no mass matrix is
//! formed to solve them (`dynamics::algorithms::hybrid`).
//!
//! The reduction is taken where the tree's own solve is the articulated-body algorithm and the
//! drives are its only rows: no closed loop (a driven joint in a loop is a row of the loops'
//! block), no contact, mimic coupling, geared rotor, joint friction, stop or frame's path, and
//! every drive in a fully driven subtree (a driven joint with a free joint below it keeps its
//! row). Otherwise the model is run as it is, with the drives' rows.

use super::model::Model;

/// The fully driven subtrees of a model (see the module's comment).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct DrivenSubtrees {
    /// Per joint of the model, whether it belongs to a fully driven subtree: its acceleration
    /// is its drives' laws'.
    pub known: Vec<bool>,
    /// The bodies the subtrees move (merged welds included).
    pub bodies: usize,
}

impl DrivenSubtrees {
    /// The fully driven subtrees of `model`, or why the model keeps its drives' rows.
    pub fn find(model: &Model) -> Result<DrivenSubtrees, String> {
        if model.drives.is_empty() {
            return Err("no drive".to_string());
        }
        let refusal = [
            (model.has_loops(), "closed loops"),
            (model.has_contacts(), "contacts"),
            (!model.mimics.is_empty(), "mimic couplings"),
            (!model.rotors.is_empty(), "geared rotors"),
            (!model.frictions.is_empty(), "joint friction"),
            (!model.stops.is_empty(), "stops"),
            (!model.position_drives.is_empty(), "a frame's path"),
        ];
        if let Some((_, why)) = refusal.iter().find(|(present, _)| *present) {
            return Err(format!(
                "the drives stay rows of the constraint stack with {why}"
            ));
        }
        let mut driven = vec![false; model.velocities()];
        for drive in &model.drives {
            driven[drive.velocity] = true;
        }
        let joints = &model.joints;
        // From the leaves in: a joint is fully driven when its velocities are and every joint
        // on its child is (joints are numbered breadth-first, parents first).
        let mut full = vec![false; joints.len()];
        for k in (0..joints.len()).rev() {
            let joint = &joints[k];
            let own =
                (joint.v_offset..joint.v_offset + joint.nv()).all(|velocity| driven[velocity]);
            let below = (k + 1..joints.len())
                .filter(|&j| joints[j].parent == joint.child)
                .all(|j| full[j]);
            full[k] = own && below;
        }
        // A subtree is rooted at a driven joint: a weld at a tip below a free joint is the
        // articulated-body algorithm's own business.
        let mut known = vec![false; joints.len()];
        for k in 0..joints.len() {
            let joint = &joints[k];
            let parent_known = (joint.parent != 0) && known[joint.parent - 1];
            known[k] = full[k] && (parent_known || joint.nv() > 0);
        }
        let every_drive_known = model
            .drives
            .iter()
            .all(|drive| (model.joint_index_of_velocity(drive.velocity)).is_some_and(|k| known[k]));
        if !every_drive_known {
            return Err("a driven joint has a free joint below it".to_string());
        }
        let bodies = known.iter().filter(|&&k| k).count();
        Ok(DrivenSubtrees { known, bodies })
    }
}
