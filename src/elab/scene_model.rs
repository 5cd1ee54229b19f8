//! What a scene's model holds, for the reports: the bodies and loops kept of the program's,
//! the parts left out and why, the locks welded and the efforts left out (`elab::scene`
//! decides them).

use serde::Serialize;

/// What a scene's model holds, for the reports (`model` in a run's report, `lsdc tree`).
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct SceneModel {
    /// The scene's name.
    pub scene: String,
    /// The bodies joined in the scene's model, and in the whole program.
    pub bodies: usize,
    pub bodies_total: usize,
    /// The independent loops (joins beyond a spanning tree) in the model, and in the program.
    pub loops: usize,
    pub loops_total: usize,
    /// The parts left out, each a group of bodies, and why.
    pub left_out: Vec<LeftOut>,
    /// Applications of efforts left out because their value is identically zero (a zero
    /// vector written as numbers, with no potential and no field).
    pub zero_efforts: usize,
    /// `apply` declarations left out by the scene's `apply only` or `apply without`.
    pub efforts_not_chosen: usize,
    /// Coordinates the scene locks, welded (their joins' bodies merged when all are locked).
    pub welded: usize,
    /// Whether the scene's run builds no dynamics: every coordinate follows its drive or the
    /// loops, and nothing the scene reads needs a mass or an effort (`prepare::kinematic_scene`).
    /// Decided when the run is prepared, false until then.
    pub kinematics_only: bool,
    /// The bodies of fully driven subtrees, run as kinematics: their drives' laws give their
    /// motion and their inverse dynamics the drives' efforts, with no row of the constraint
    /// stack (`dynamics::driven_subtrees`). Decided when the run is prepared, 0 until then.
    pub driven_kinematics: usize,
}

/// A group of bodies left out of a scene's model.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct LeftOut {
    pub bodies: Vec<String>,
    pub reason: String,
}

/// Why a group is left out.
pub(super) const NOT_READ: &str = "not read by the scene's outputs";
/// Why a massless subtree is left out (`elab::scene::massless`).
pub(super) const MASSLESS: &str = "massless, nothing the scene reads moves with them";

impl SceneModel {
    /// `model of scene `arm`: 3 of 6 bodies, 0 of 0 loops; left out: right:base, right:upper
    /// and 1 other body (not read by the scene's outputs)`.
    pub fn describe(&self) -> String {
        let mut text = format!(
            "model of scene `{}`: {} of {} bodies, {} of {} loops",
            self.scene, self.bodies, self.bodies_total, self.loops, self.loops_total
        );
        // The parts in order, each reason said once after the last part it explains.
        let mut parts = Vec::new();
        for (i, part) in self.left_out.iter().enumerate() {
            let mut said = listed(&part.bodies);
            if self
                .left_out
                .get(i + 1)
                .is_none_or(|next| next.reason != part.reason)
            {
                said += &format!(" ({})", part.reason);
            }
            parts.push(said);
        }
        if self.welded > 0 {
            let plural = if self.welded == 1 { "" } else { "s" };
            text += &format!("; {} locked coordinate{plural} welded", self.welded);
        }
        if self.zero_efforts > 0 {
            let plural = if self.zero_efforts == 1 { "" } else { "s" };
            parts.push(format!(
                "{} applied effort{plural} identically zero",
                self.zero_efforts
            ));
        }
        if self.efforts_not_chosen > 0 {
            let plural = if self.efforts_not_chosen == 1 {
                ""
            } else {
                "s"
            };
            parts.push(format!(
                "{} applied effort{plural} (not chosen by the scene)",
                self.efforts_not_chosen
            ));
        }
        if !parts.is_empty() {
            text += &format!("; left out: {}", parts.join("; "));
        }
        if self.driven_kinematics > 0 {
            let plural = if self.driven_kinematics == 1 {
                "y"
            } else {
                "ies"
            };
            text += &format!(
                "; {} driven bod{plural} as kinematics",
                self.driven_kinematics
            );
        }
        if self.kinematics_only {
            text += "; kinematics only (every coordinate driven or closed by the loops): no dynamics built";
        }
        text
    }
}

/// Up to three names, then how many more.
fn listed(names: &[String]) -> String {
    match names {
        [one] => one.clone(),
        [a, b] => format!("{a} and {b}"),
        [a, b, c] => format!("{a}, {b} and {c}"),
        [a, b, rest @ ..] => format!(
            "{a}, {b} and {} other bod{}",
            rest.len(),
            if rest.len() == 1 { "y" } else { "ies" }
        ),
        [] => String::new(),
    }
}
