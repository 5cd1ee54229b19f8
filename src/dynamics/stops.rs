//! Stops on joint coordinates (a link's `lower` and `upper` fields): unilateral constraints
//! q ≥ lower, q ≤ upper that the simulation treats as events. Each bound is one event function,
//! positive while the coordinate is inside its range; where it crosses zero the integrator
//! locates the time and the impact law reverses the coordinate's rate, scaled by the
//! coefficient of restitution e, with the impulse acting through the mass matrix: the stop's
//! row joins the constraint stack for the impact (`rows::impact_velocities`).

use serde::Serialize;

use super::joint::{refuse_declared, Joint, JointType};
use crate::diag::Diagnostic;
use crate::elab::mechanism::{LinkStops, Mechanism};
use crate::kinematics::eval::{eval, UnknownValues};
use crate::kinematics::model::JointModel;

/// Which bound a stop enforces.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Side {
    Lower,
    Upper,
}

/// One impact on a stop, as the run report gives it.
#[derive(Clone, Debug, Serialize)]
pub struct Impact {
    pub time: f64,
    /// `swing.q`, and which of its bounds (at `bound`) was hit.
    pub coordinate: String,
    pub side: Side,
    pub bound: f64,
    pub restitution: f64,
    /// The coordinate's rate just before and just after the impact.
    pub rate_before: f64,
    pub rate_after: f64,
    /// The mechanism's kinetic energy just before and just after.
    pub kinetic_before: f64,
    pub kinetic_after: f64,
    /// Whether the coordinate then rests on the stop, pushed into it (until the contact force
    /// would have to pull, when it is released).
    pub rests: bool,
}

/// One bound on one tree coordinate.
#[derive(Clone, Debug)]
pub struct Stop {
    /// `swing.q`, as the outputs name the coordinate.
    pub coordinate: String,
    pub side: Side,
    pub bound: f64,
    pub restitution: f64,
    /// The coordinate's index among the state's positions, and its rate's among the velocities.
    pub position: usize,
    pub velocity: usize,
}

impl Stop {
    /// The event function: positive inside the range, zero on the bound.
    pub fn distance(&self, q: &[f64]) -> f64 {
        match self.side {
            Side::Lower => q[self.position] - self.bound,
            Side::Upper => self.bound - q[self.position],
        }
    }

    /// The rate at which the coordinate approaches its bound (positive when approaching).
    pub fn approach(&self, v: &[f64]) -> f64 {
        match self.side {
            Side::Lower => -v[self.velocity],
            Side::Upper => v[self.velocity],
        }
    }
}

/// The stops of the tree's links, two per link with both bounds; a link with stops must have
/// one coordinate that the state holds as such (E0450) and be a tree link (not one that closes
/// a loop), and its bounds must be numbers with lower < upper (E0451) and 0 ≤ e ≤ 1 (E0452).
pub fn build(
    mechanism: &Mechanism,
    joints: &[Joint],
    loops: &[JointModel],
    unknowns: &UnknownValues,
    errors: &mut Vec<Diagnostic>,
) -> Vec<Stop> {
    let mut stops = Vec::new();
    refuse_on_loop_closing(mechanism, loops, errors);
    for joint in joints {
        let join = mechanism.join(joint.chain.join);
        let link = mechanism.link(join.link);
        if !link.stops().is_declared() {
            continue;
        }
        if joint.chain.coordinate_count() != 1
            || joint.kind != JointType::Chain
            || joint.nq() != 1
            || joint.nv() != 1
        {
            errors.push(
                Diagnostic::error(
                    "E0450",
                    format!(
                        "`{}` has stops but {} coordinates",
                        joint.chain.name,
                        joint.chain.coordinate_count()
                    ),
                )
                .primary(link.span, "`lower`, `upper` need a link with one coordinate")
.secondary(mechanism.join(joint.chain.join).span, "the join")
                .help("put the stops on a revolute or prismatic link (`limited_revolute`, `limited_prismatic` in `joints`)"),
            );
            continue;
        }
        if let Some(found) = joint_stops(mechanism, joint, link.stops(), unknowns, errors) {
            stops.extend(found);
        }
    }
    stops
}

/// Stops on a link that closes a loop (E0450): its coordinate is not one of the tree's, which
/// the state holds and the stops' rows are written on.
fn refuse_on_loop_closing(
    mechanism: &Mechanism,
    loops: &[JointModel],
    errors: &mut Vec<Diagnostic>,
) {
    refuse_declared(
        mechanism,
        loops,
        |link| link.stops().is_declared(),
        |name, span| {
            Diagnostic::error("E0450", format!("`{name}` has stops but closes a loop"))
                .primary(span, "stops are simulated on the links of the tree")
                .help("put the stops on another link of the loop (`lsdc tree` lists the links that close loops)")
        },
        errors,
    );
}

fn joint_stops(
    mechanism: &Mechanism,
    joint: &Joint,
    declared: &LinkStops,
    unknowns: &UnknownValues,
    errors: &mut Vec<Diagnostic>,
) -> Option<Vec<Stop>> {
    let link = mechanism.link(mechanism.join(joint.chain.join).link);
    let name = &joint.chain.name;
    let number = |value: &Option<crate::elab::value::Scalar>, errors: &mut Vec<Diagnostic>| {
        let value = value.as_ref()?;
        match eval(value, unknowns) {
            Ok(x) if x.is_finite() => Some(Ok(x)),
            _ => {
                errors.push(
                    Diagnostic::error("E0451", format!("a stop of `{name}` is not a number"))
                        .primary(
                            link.span,
                            "its `lower`, `upper` and `restitution` must be numbers",
                        )
                        .secondary(mechanism.join(joint.chain.join).span, "the join")
                        .help("give the unknowns they use values (`--set`)"),
                );
                Some(Err(()))
            }
        }
    };
    let lower = number(&declared.lower, errors).transpose().ok()?;
    let upper = number(&declared.upper, errors).transpose().ok()?;
    let restitution = number(&declared.restitution, errors)
        .transpose()
        .ok()?
        .unwrap_or(0.0);
    if let (Some(lower), Some(upper)) = (lower, upper) {
        if lower >= upper {
            errors.push(
                Diagnostic::error(
                    "E0451",
                    format!("the stops of `{name}` leave no room: lower {lower} ≥ upper {upper}"),
                )
                .primary(link.span, "here")
                .secondary(mechanism.join(joint.chain.join).span, "the join")
                .help("give `lower` a value below `upper`"),
            );
            return None;
        }
    }
    if !(0.0..=1.0).contains(&restitution) {
        errors.push(
            Diagnostic::error(
                "E0452",
                format!("the restitution of `{name}`'s stops is {restitution}, outside [0, 1]"),
            )
            .primary(link.span, "here")
            .secondary(mechanism.join(joint.chain.join).span, "the join")
            .help("0 stops the coordinate dead at the bound, 1 bounces back without loss"),
        );
        return None;
    }
    let coordinate = format!("{}.{}", name, joint.chain.coordinate_names[0]);
    let stop = |side, bound| Stop {
        coordinate: coordinate.clone(),
        side,
        bound,
        restitution,
        position: joint.q_offset,
        velocity: joint.v_offset,
    };
    let mut found = Vec::new();
    found.extend(lower.map(|b| stop(Side::Lower, b)));
    found.extend(upper.map(|b| stop(Side::Upper, b)));
    Some(found)
}
