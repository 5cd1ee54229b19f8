//! Geared rotors (a link's `rotor_inertia`, `gear_ratio`, `rotor_axis`; Llibre §2.2–2.5): a
//! motor's rotor carried by the body of the join's first frame, spinning about `rotor_axis`
//! relative to it at n q̇ (n the ratio, q the link's coordinate), with moment of inertia J about
//! its axis. Its mass and transverse inertia belong to the carrying body; what it adds is its
//! spin, of kinetic energy ½ J (ε·ω_B + n q̇)², ω_B the carrier's angular velocity and ε the
//! axis. Hence the mass matrix gains J w wᵀ, w_j = ε·ω_B(e_j) + n δ_jk: the reflected inertia
//! n² J on the coordinate's diagonal and the coupling n J ε·ω_B(e_j) with the joints that turn
//! the carrier; inverse dynamics gains the rotor's torque on its carrier,
//! τ_r = J[(ε·ω̇_B + n q̈) ε + (ε·ω_B + n q̇) ω_B × ε], and n ε·τ_r on the coordinate.

use nalgebra::Vector3;

use super::joint::{refuse_declared, Joint, JointType};
use crate::diag::Diagnostic;
use crate::elab::mechanism::{LinkRotor, Mechanism};
use crate::kinematics::eval::{eval, UnknownValues};
use crate::kinematics::model::JointModel;

/// One geared rotor, in the model's numbering.
#[derive(Clone, Debug)]
pub struct Rotor {
    /// The joint it drives (index into `Model::joints`) and its velocity's index.
    pub joint: usize,
    pub velocity: usize,
    /// The body number that carries it (0 for earth) and its axis there (unit).
    pub carrier: usize,
    pub axis: Vector3<f64>,
    pub inertia: f64,
    pub ratio: f64,
}

/// The rotors of the tree's links. A link with a rotor must have one coordinate (E0453), be a
/// link of the tree rather than one that closes a loop (E0827), and give all three fields as
/// numbers with a non-zero axis (E0453).
pub fn build(
    mechanism: &Mechanism,
    joints: &[Joint],
    loops: &[JointModel],
    unknowns: &UnknownValues,
    errors: &mut Vec<Diagnostic>,
) -> Vec<Rotor> {
    let mut rotors = Vec::new();
    refuse_on_closing_links(mechanism, loops, errors);
    for (k, joint) in joints.iter().enumerate() {
        let join = mechanism.join(joint.chain.join);
        let link = mechanism.link(join.link);
        if !link.rotor().is_declared() {
            continue;
        }
        let name = &joint.chain.name;
        let single = joint.chain.coordinate_count() == 1
            && joint.kind == JointType::Chain
            && joint.nv() == 1;
        match (single, rotor_values(link.rotor(), unknowns)) {
            (true, Some((inertia, ratio, axis))) => {
                let frame = if joint.first_on_parent { joint.on_parent } else { joint.on_child };
                rotors.push(Rotor {
                    joint: k,
                    velocity: joint.v_offset,
                    carrier: if joint.first_on_parent { joint.parent } else { joint.child },
                    axis: frame.rotation * axis.normalize(),
                    inertia,
                    ratio,
                });
            }
            (false, _) => errors.push(
                Diagnostic::error("E0453", format!("`{name}` has a geared rotor but {} coordinates", joint.chain.coordinate_count()))
                    .primary(link.span, "a rotor drives a link with one coordinate")
.secondary(mechanism.join(joint.chain.join).span, "the join")
                    .help("put the rotor on a revolute or prismatic link (`geared_revolute` in `joints`)"),
            ),
            (true, None) => errors.push(
                Diagnostic::error("E0453", format!("the geared rotor of `{name}` is incomplete"))
                    .primary(link.span, "needs `rotor_inertia` (≥ 0), `gear_ratio` and a non-zero `rotor_axis`, as numbers")
.secondary(mechanism.join(joint.chain.join).span, "the join")
                    .help("give all three fields, e.g. `rotor_inertia = 2e-5, gear_ratio = 100, rotor_axis = [0, 0, 1]`"),
            ),
        }
    }
    rotors
}

fn rotor_values(rotor: &LinkRotor, unknowns: &UnknownValues) -> Option<(f64, f64, Vector3<f64>)> {
    let inertia = eval(rotor.inertia.as_ref()?, unknowns).ok()?;
    let ratio = eval(rotor.ratio.as_ref()?, unknowns).ok()?;
    let axis = rotor.axis.as_ref()?;
    let axis = Vector3::new(
        eval(&axis[0], unknowns).ok()?,
        eval(&axis[1], unknowns).ok()?,
        eval(&axis[2], unknowns).ok()?,
    );
    let valid = inertia >= 0.0 && inertia.is_finite() && ratio.is_finite() && axis.norm() > 0.0;
    valid.then_some((inertia, ratio, axis))
}

/// A rotor on a link that closes a loop (E0827): that link's coordinate is an unknown of the
/// closure, without inertia of its own, which a rotor would have to give one.
fn refuse_on_closing_links(
    mechanism: &Mechanism,
    loops: &[JointModel],
    errors: &mut Vec<Diagnostic>,
) {
    refuse_declared(
        mechanism,
        loops,
        |link| link.rotor().is_declared(),
        |name, span| {
            Diagnostic::error("E0827", format!("`{name}` has a geared rotor but closes a loop"))
                .primary(span, "this join closes a loop of the mechanism")
                .help("put the rotor on another join of the loop (`lsdc tree` shows which joins close loops)")
        },
        errors,
    );
}
