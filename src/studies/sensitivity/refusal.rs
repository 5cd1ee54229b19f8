//! What `lsdc sensitivity` does not handle, refused at the part of the program (E0860): the
//! parts whose runs the sensitivity equations do not follow (see the study's documentation).

use crate::diag::Diagnostic;
use crate::dynamics::joint::JointType;
use crate::elab::mechanism::Mechanism;
use crate::elab::value::JoinId;
use crate::prepare::Prepared;

/// What `lsdc sensitivity` does not handle, and why (see the module's documentation).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Refused {
    Loop,
    Quaternion,
    Mimic,
    Stop,
    Friction,
    Contact,
    EffortInput,
}

impl Refused {
    fn what(self) -> &'static str {
        match self {
            Refused::Loop => "a closed loop",
            Refused::Quaternion => "a spherical or free joint",
            Refused::Mimic => "a coupled (mimic) joint",
            Refused::Stop => "a stop",
            Refused::Friction => "joint friction",
            Refused::Contact => "a contact",
            Refused::EffortInput => "an effort input (`input JOIN.COORD = START;`)",
        }
    }

    fn help(self) -> &'static str {
        match self {
            Refused::Loop | Refused::Mimic => "the run projects the state onto the constraints after each step, and the sensitivities would need that projection's derivative (in the loops' independent coordinates), which is not computed: open the loop, or difference whole runs (`lsdc sweep --grid NAME=...`)",
            Refused::Quaternion => "its orientation is a quaternion, whose sensitivities would live in the group's tangent space: write the joint as a chain of revolutes (`link(a, b, c) dof = ...`)",
            Refused::Stop | Refused::Friction => "its events jump the state, and the sensitivities would jump with the event's time (the saltation matrix), which is not computed: leave it out, or difference whole runs (`lsdc sweep --grid NAME=...`)",
            Refused::Contact => "its rows constrain the velocities, and the sensitivities would need their derivative: difference whole runs instead (`lsdc sweep --grid NAME=...`)",
            Refused::EffortInput => "the sensitivity equations take the program's own efforts, not the inputs' held efforts, which a run adds: apply the start value as an effort of the program (`apply torque ...`), or difference whole runs (`lsdc sweep --grid NAME=...`)",
        }
    }
}

/// E0860 at the first part of the mechanism the study does not handle.
pub fn refusal(mechanism: &Mechanism, prepared: &Prepared) -> Option<Diagnostic> {
    let model = &prepared.model;
    let join_of = |coordinate: &str| -> String {
        (coordinate.rsplit_once('.'))
            .map_or(coordinate, |(join, _)| join)
            .to_string()
    };
    let found: Option<(String, Refused)> = None
        .or_else(|| (model.loops.first()).map(|l| (l.name.clone(), Refused::Loop)))
        .or_else(|| {
            (model.joints.iter().find(|j| j.kind != JointType::Chain))
                .map(|j| (j.chain.name.clone(), Refused::Quaternion))
        })
        .or_else(|| (model.mimics.first()).map(|m| (join_of(&m.coordinate), Refused::Mimic)))
        .or_else(|| (model.stops.first()).map(|s| (join_of(&s.coordinate), Refused::Stop)))
        .or_else(|| (model.frictions.first()).map(|f| (join_of(&f.coordinate), Refused::Friction)))
        .or_else(|| (model.contacts.first()).map(|c| (c.name.clone(), Refused::Contact)))
        .or_else(|| (model.effort_inputs.first()).map(|(c, _)| (join_of(c), Refused::EffortInput)));
    let (name, kind) = found?;
    let mut joins = (0..mechanism.joins.len() as u32).map(JoinId);
    let span = match joins.find(|&id| mechanism.join_name(id) == name) {
        Some(id) => mechanism.join(id).span,
        None => {
            let index =
                (0..mechanism.contacts.len()).find(|&k| mechanism.contact_name(k) == name)?;
            mechanism.contacts[index].span
        }
    };
    Some(
        Diagnostic::error(
            "E0860",
            format!(
                "`lsdc sensitivity` does not handle `{name}`: {}",
                kind.what()
            ),
        )
        .primary(span, kind.what())
        .help(kind.help()),
    )
}
