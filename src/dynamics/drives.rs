//! The driven coordinates of the dynamic model (`drive crank.q = law`, checked and
//! differentiated in `kinematics::drives`): each one a unit row of the constraint rows
//! (`rows`) whose right-hand side follows the law, q̈ₖ = law''(t), kept at the position and
//! velocity levels after each step (qₖ = law(t), q̇ₖ = law'(t)); its multiplier is the
//! generalised force that imposes the motion, the drive's effort. The hidden coordinates of
//! rheonomic joints (`time` in a dof chain, `kinematics::rheonomic`) are driven alike.

use super::joint::{Joint, JointType};
use crate::diag::Diagnostic;
use crate::elab::mechanism::Mechanism;
use crate::kinematics::drives::{resolve, DriveLaw, LawAt};
use crate::kinematics::model::KinematicModel;

/// One driven coordinate, in the model's numbering.
#[derive(Clone, Debug)]
pub struct DrivenCoordinate {
    /// `crank.q`.
    pub coordinate: String,
    /// Its index among the declared coordinates.
    pub declared: usize,
    /// Its indices among the state's positions and velocities.
    pub position: usize,
    pub velocity: usize,
    pub law: DriveLaw,
    /// Its effort's name among the outputs.
    pub effort: String,
}

impl DrivenCoordinate {
    /// The law at time `t`.
    pub fn at(&self, t: f64) -> LawAt {
        self.law.at(t)
    }

    /// The law at time `t`, evaluated in `values` (see `DriveLaw::evaluate`).
    pub fn evaluate(&self, t: f64, values: &mut Vec<f64>) -> LawAt {
        self.law.evaluate(t, values)
    }

    /// The name of its effort among the outputs (`crank.drive_effort`, `ResolvedDrive::effort`).
    pub fn effort_name(&self) -> String {
        self.effort.clone()
    }
}

/// The program's drives on the tree's joints `joints` (refusals as `kinematics::drives`
/// reports them).
pub fn build(
    mechanism: &Mechanism,
    kinematics: &KinematicModel,
    joints: &[Joint],
    errors: &mut Vec<Diagnostic>,
) -> Vec<DrivenCoordinate> {
    let resolved = match resolve(mechanism, kinematics) {
        Ok(resolved) => resolved,
        Err(refused) => {
            errors.extend(refused);
            return Vec::new();
        }
    };
    resolved
        .into_iter()
        .filter_map(|drive| {
            // A drive imposes a coordinate of a joint in its own coordinates (`Chain`): as
            // many positions as velocities.
            let joint = joints.iter().find(|j| {
                let first = j.chain.offset;
                j.kind == JointType::Chain
                    && (first..first + j.chain.coordinate_count()).contains(&drive.coordinate)
            })?;
            let k = drive.coordinate - joint.chain.offset;
            Some(DrivenCoordinate {
                coordinate: drive.name,
                declared: drive.coordinate,
                position: joint.q_offset + k,
                velocity: joint.v_offset + k,
                law: drive.law,
                effort: drive.effort,
            })
        })
        .collect()
}
