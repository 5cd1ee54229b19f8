//! Friction in joints (a link's `friction` and `damping`; URDF `<dynamics friction damping>`):
//! on a coordinate q of rate q̇, a dry (Coulomb) force or torque of magnitude F_c opposing q̇,
//! and a viscous one, −c q̇.
//!
//! Dry friction is simulated as a switch between two phases, each smooth, located in time as
//! events (no regularisation, so no error of its own):
//!
//! - **slipping** in a direction s = ±1 held for the phase: the joint's effort gains −s F_c − c q̇;
//!   the phase ends where s q̇ crosses zero;
//! - **sticking**: q̇ = 0 is held by a force λ (found with the accelerations, as a stop's
//!   contact force is); the phase ends where |λ| reaches F_c, and the joint slips in the
//!   direction −sign λ that the unbalanced effort drives it.
//!
//! Where a slipping joint's rate reaches zero it sticks if the force that holds it there is
//! within F_c, and slips back the other way otherwise.
//!
//! A **driven** joint (`drive slide.q = law`) has no phases: its motion is imposed, so its
//! friction is −F_c sign q̇ − c q̇ at the rate the law gives, and the drive's effort, the
//! multiplier of its row, supplies it. A generalised force along a driven coordinate changes
//! only that multiplier, never the motion, so no event is needed where the rate changes sign.
//! Where the law holds the joint at rest (q̇ = 0) the static friction is indeterminate (drive
//! and friction share one load): lsdc takes it as zero, the drive's effort carrying the load.

use serde::Serialize;

use super::joint::{refuse_declared, Joint};
use crate::diag::Diagnostic;
use crate::elab::mechanism::{LinkFriction, Mechanism};
use crate::kinematics::eval::{eval, UnknownValues};
use crate::kinematics::model::JointModel;

/// The friction of one joint, in the model's numbering.
#[derive(Clone, Debug)]
pub struct Friction {
    /// The joint (index into `Model::joints`).
    pub joint: usize,
    /// `slide.q`, as the outputs name the coordinate.
    pub coordinate: String,
    /// The coordinate's index among the state's positions, its rate's among the velocities.
    pub position: usize,
    pub velocity: usize,
    /// F_c ≥ 0 (N or N m) and c ≥ 0 (N s/m or N m s/rad).
    pub dry: f64,
    pub viscous: f64,
    /// Whether a drive imposes the coordinate's motion (no phases: see the module's notes).
    pub driven: bool,
}

/// A change of phase of a joint with friction, as the run report gives it.
#[derive(Clone, Debug, Serialize)]
pub struct Switch {
    pub time: f64,
    /// `slide.q`, and its value there.
    pub coordinate: String,
    pub position: f64,
    /// The phase from then on.
    pub phase: Phase,
}

/// The phase of a joint with friction.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Phase {
    /// Moving with the sign of the rate given (±1).
    Slipping(f64),
    Sticking,
}

impl Phase {
    /// "sticks", "slips forward" (q increasing) or "slips back".
    pub fn describe(self) -> &'static str {
        match self {
            Phase::Sticking => "sticks",
            Phase::Slipping(s) if s > 0.0 => "slips forward",
            Phase::Slipping(_) => "slips back",
        }
    }
}

impl Friction {
    /// The friction's effort on the joint while slipping in `direction` at rate `rate`.
    pub fn slipping_effort(&self, direction: f64, rate: f64) -> f64 {
        -direction * self.dry - self.viscous * rate
    }

    /// The friction's effort on a driven joint at the rate `rate` its law imposes: opposing the
    /// rate, none at rest (the drive's effort then carries the load alone).
    pub fn driven_effort(&self, rate: f64) -> f64 {
        let direction = if rate == 0.0 { 0.0 } else { rate.signum() };
        self.slipping_effort(direction, rate)
    }

    /// The phase at a rate `rate` where the force holding the joint at rest would be `hold`:
    /// moving on with the rate's sign, or from rest, sticking while |hold| ≤ F_c and slipping
    /// the way the unbalanced effort drives it otherwise.
    pub fn phase_at(&self, rate: f64, hold: f64) -> Phase {
        match rate {
            r if r != 0.0 => Phase::Slipping(r.signum()),
            // Without dry friction nothing holds the joint: it moves off at once, if at all.
            _ if hold.abs() <= self.dry && self.dry > 0.0 => Phase::Sticking,
            _ => Phase::Slipping(-hold.signum()),
        }
    }
}

/// The friction of the tree's links. A link with friction must have one coordinate (E0474) and
/// be a join of the tree, not one closing a loop (E0474), and its coefficients must be numbers
/// ≥ 0 (E0474).
pub fn build(
    mechanism: &Mechanism,
    joints: &[Joint],
    loops: &[JointModel],
    unknowns: &UnknownValues,
    errors: &mut Vec<Diagnostic>,
) -> Vec<Friction> {
    let mut found = Vec::new();
    refuse_declared(
        mechanism,
        loops,
        |link| link.friction().is_declared(),
        |name, span| {
            Diagnostic::error("E0474", format!("`{name}` has friction and closes a loop"))
                .primary(span, "friction acts in the joints of the tree only")
                .help("put the friction on a join of the tree, or remove it")
        },
        errors,
    );
    for (k, joint) in joints.iter().enumerate() {
        let link = mechanism.link(mechanism.join(joint.chain.join).link);
        if !link.friction().is_declared() {
            continue;
        }
        match joint_friction(joint, link.friction(), unknowns) {
            Ok(friction) => found.push(Friction { joint: k, ..friction }),
            Err((message, label)) => errors.push(
                Diagnostic::error("E0474", message)
                    .primary(link.span, label)
.secondary(mechanism.join(joint.chain.join).span, "the join")
                    .help("give `friction` (and `damping`) as numbers ≥ 0 on a revolute or prismatic link"),
            ),
        }
    }
    found
}

fn joint_friction(
    joint: &Joint,
    declared: &LinkFriction,
    unknowns: &UnknownValues,
) -> Result<Friction, (String, &'static str)> {
    let name = &joint.chain.name;
    if !joint.is_single_coordinate() {
        let count = joint.chain.coordinate_count();
        return Err((
            format!("`{name}` has friction but {count} coordinates"),
            "`friction` and `damping` need a link with one coordinate",
        ));
    }
    let number = |value: &Option<crate::elab::value::Scalar>| match value {
        None => Some(0.0),
        Some(value) => eval(value, unknowns)
            .ok()
            .filter(|x| x.is_finite() && *x >= 0.0),
    };
    match (number(&declared.dry), number(&declared.viscous)) {
        (Some(dry), Some(viscous)) => Ok(Friction {
            joint: 0,
            coordinate: joint.coordinate_label(),
            position: joint.q_offset,
            velocity: joint.v_offset,
            dry,
            viscous,
            driven: false,
        }),
        _ => Err((
            format!("the friction of `{name}` is not a number ≥ 0"),
            "`friction` and `damping` must be numbers ≥ 0",
        )),
    }
}
