//! The actuators (`actuate shoulder.q = law`): generalised efforts along coordinates of the
//! tree, whose laws may read the model in the actuated coordinates (`mass_matrix`, `bias`,
//! `gravity_effort`, `inverse_dynamics`; see `reduced_model`). Their laws are one tape of their
//! own, evaluated after the program's other efforts, which the model counts: the model is
//! computed once per evaluation from those, whatever the number of laws that read it.
//!
//! Refused, each where it is written: a coordinate that is not one of a tree joint's own
//! (E0654: a loop-closing join's, an angle of a spherical or free joint), driven or actuated
//! twice; an applied or link effort that reads the model (E0655: the model counts it, so the
//! law would be implicit); a law that reads the model along a coordinate that is not actuated
//! (E0656); the model with contacts or mimic couplings (E0657), whose rows it does not reduce.
//!
//! The rates of states that read the model (`rate current = ... inverse_dynamics(...) ...;`)
//! are roots of the same tape: they are laws of the controller as the actuators' are, read
//! after the model at each evaluation.

use super::compiled::{EffortTape, Link, ModelReads, TapeBuilder};
use super::drives::DrivenCoordinate;
use super::elements::EffortFrame;
use super::joint::{Joint, JointType};
use super::states::StateModel;
use crate::diag::Diagnostic;
use crate::elab::mechanism::{Mechanism, OutputValue};
use crate::elab::model_laws::reads_model;
use crate::elab::value::{JoinId, SExpr, Scalar};
use crate::kinematics::eval::{EvalError, UnknownValues};
use crate::source::Span;

/// An actuated coordinate in the model's numbering.
#[derive(Clone, Debug)]
pub struct ActuatedCoordinate {
    /// `shoulder.q`.
    pub name: String,
    /// Its index among the declared coordinates, and among the state's velocities.
    pub declared: usize,
    pub velocity: usize,
}

/// The program's actuators, compiled.
#[derive(Clone, Debug)]
pub struct Actuation {
    /// In declaration order: the model's coordinates.
    pub coordinates: Vec<ActuatedCoordinate>,
    /// The laws, one root each (in `coordinates`' order).
    pub tape: EffortTape,
    pub roots: Vec<usize>,
    /// The rates of the states that read the model: (the state's index, its root).
    pub state_roots: Vec<(usize, usize)>,
    /// What the laws read of the model.
    pub reads: ModelReads,
}

/// Where the laws and the model are compiled from: the tree, its declared coordinates, the
/// drives, the values of the unknowns and the frames the efforts read.
pub struct Compiling<'a> {
    pub mechanism: &'a Mechanism,
    pub joints: &'a [Joint],
    pub declared_offsets: &'a [usize],
    pub drives: &'a [DrivenCoordinate],
    pub unknowns: &'a UnknownValues,
    pub frames: &'a [EffortFrame],
    /// The program's states: the rates that read the model are compiled with the laws.
    pub states: &'a [StateModel],
    /// Contacts or mimic couplings constrain the tree.
    pub constrained: bool,
}

impl Compiling<'_> {
    /// The declared offset of a join of the tree.
    fn declared_offset(&self, join: JoinId) -> Option<usize> {
        let k = self.joints.iter().position(|j| j.chain.join == join)?;
        Some(self.declared_offsets[k])
    }

    /// The name of a join's coordinate, `shoulder.q`.
    fn coordinate_name(&self, join: JoinId, coordinate: usize) -> String {
        let join_name = self.mechanism.join_name(join);
        let link = self.mechanism.link(self.mechanism.join(join).link);
        match link.coordinates.get(coordinate) {
            Some(name) => format!("{join_name}.{name}"),
            None => format!("{join_name}.#{coordinate}"),
        }
    }
}

/// Compiles the actuators (`None` without any); refusals go to `errors`.
pub fn build(compiling: &Compiling<'_>, errors: &mut Vec<Diagnostic>) -> Option<Actuation> {
    refuse_implicit_efforts(compiling.mechanism, errors);
    let actuators = &compiling.mechanism.actuators;
    let model_rates: Vec<(usize, &StateModel)> = (compiling.states.iter().enumerate())
        .filter(|(_, state)| state.reads_model)
        .collect();
    if actuators.is_empty() {
        for (_, state) in &model_rates {
            refuse_unactuated(compiling, &[], &state.rate, state.rate_span, errors);
        }
        return None;
    }
    let mut coordinates: Vec<ActuatedCoordinate> = Vec::new();
    for actuator in actuators {
        let name = compiling.coordinate_name(actuator.join, actuator.coordinate);
        match actuated(compiling, actuator.join, actuator.coordinate, &name) {
            Ok(velocity) => {
                let declared = compiling.declared_offset(actuator.join).unwrap_or(0)
                    + actuator.coordinate;
                let refusal = match coordinates.iter().any(|c| c.velocity == velocity) {
                    true => Some("actuated twice: one coordinate has one actuator"),
                    false => compiling
                        .drives
                        .iter()
                        .any(|d| d.velocity == velocity)
                        .then_some("driven: its motion is imposed, an effort cannot move it"),
                };
                match refusal {
                    Some(why) => errors.push(
                        Diagnostic::error("E0654", format!("`{name}` cannot be actuated"))
                            .primary(actuator.span, why)
                            .help("give each free coordinate of the tree one `actuate` law"),
                    ),
                    None => coordinates.push(ActuatedCoordinate {
                        name,
                        declared,
                        velocity,
                    }),
                }
            }
            Err(why) => errors.push(
                Diagnostic::error("E0654", format!("`{name}` cannot be actuated"))
                    .primary(actuator.span, why)
                    .help("actuate a coordinate of a revolute, prismatic or other joint of the tree written with its own coordinates"),
            ),
        }
    }
    let reading: Vec<(&Scalar, Span)> = (actuators.iter().map(|a| (&a.law, a.law_span)))
        .chain(model_rates.iter().map(|(_, s)| (&s.rate, s.rate_span)))
        .collect();
    let declared: Vec<usize> = coordinates.iter().map(|c| c.declared).collect();
    for (law, span) in &reading {
        refuse_unactuated(compiling, &declared, law, *span, errors);
    }
    if !errors.is_empty() {
        return None;
    }
    let offset = |join| compiling.declared_offset(join);
    let mut builder = TapeBuilder::new(compiling.unknowns, compiling.frames, &offset)
        .reading_model(declared.clone());
    let roots: Result<Vec<usize>, EvalError> = reading
        .iter()
        .map(|(law, _)| builder.scalar(law, Link(None)))
        .collect();
    let tape = builder.build();
    let mut roots = match roots {
        Ok(roots) => roots,
        Err(error) => {
            errors.push(
                Diagnostic::error("E0654", "an actuator's law cannot be evaluated").primary(
                    actuators[0].law_span,
                    crate::kinematics::eval::describe(&error, compiling.mechanism),
                ),
            );
            return None;
        }
    };
    let rate_roots = roots.split_off(actuators.len());
    let state_roots = (model_rates.iter().map(|(k, _)| *k))
        .zip(rate_roots)
        .collect();
    // The model is computed once per evaluation for the laws and the outputs alike.
    let mut reads = tape.model_reads(declared.len());
    for output in &compiling.mechanism.outputs {
        match &output.value {
            OutputValue::Scalar(s) => reads.add_calls(s),
            OutputValue::Vector(v) => v.iter().for_each(|s| reads.add_calls(s)),
            OutputValue::Matrix(m) => m.iter().flatten().for_each(|s| reads.add_calls(s)),
            OutputValue::Frame(_) => {}
        }
    }
    Some(Actuation {
        coordinates,
        tape,
        roots,
        state_roots,
        reads,
    })
}

/// The state velocity of an actuated coordinate: one of a chain joint of the tree.
fn actuated(
    compiling: &Compiling<'_>,
    join: JoinId,
    coordinate: usize,
    name: &str,
) -> Result<usize, String> {
    let Some(joint) = compiling.joints.iter().find(|j| j.chain.join == join) else {
        return Err(format!(
            "`{name}` is a coordinate of a join that closes a loop: the loop's closure decides it"
        ));
    };
    match joint.kind {
        JointType::Chain => Ok(joint.v_offset + coordinate),
        _ => {
            Err("an angle of a spherical or free joint, which no actuator turns alone".to_string())
        }
    }
}

/// The model counts every applied and link effort: one that reads it would be implicit (E0655).
fn refuse_implicit_efforts(mechanism: &Mechanism, errors: &mut Vec<Diagnostic>) {
    let help = "write the law as an actuator, `actuate <join>.<coordinate> = <law>;`: the model counts every other effort, so an effort that reads it would depend on itself";
    for application in &mechanism.applications {
        let effort = &mechanism.efforts[application.effort.0 as usize];
        if effort.value.value().iter().any(|s| reads_model(s)) {
            errors.push(
                Diagnostic::error(
                    "E0655",
                    "an applied effort reads the model, which counts it: the law would be implicit",
                )
                .primary(application.span, "this effort's value reads the model")
                .help(help),
            );
        }
    }
    for join in &mechanism.joins {
        let link = mechanism.link(join.link);
        let values = link
            .forces
            .iter()
            .chain(&link.torques)
            .flat_map(|(_, v)| v.iter());
        if values.chain(&link.potential).any(|s| reads_model(s)) {
            errors.push(
                Diagnostic::error(
                    "E0655",
                    "a link's effort reads the model, which counts it: the law would be implicit",
                )
                .primary(
                    join.span,
                    "this join's link has an effort that reads the model",
                )
                .help(help),
            );
        }
    }
}

/// A law (of an actuator or an output) that reads the model along a coordinate that is not
/// actuated (E0656); `declared`, the actuated coordinates' declared indices.
pub fn refuse_unactuated(
    compiling: &Compiling<'_>,
    declared: &[usize],
    law: &Scalar,
    span: Span,
    errors: &mut Vec<Diagnostic>,
) {
    if !reads_model(law) {
        return;
    }
    if compiling.constrained {
        errors.push(
            Diagnostic::error(
                "E0657",
                "the model's quantities are not available with contacts or mimic couplings",
            )
            .primary(span, "reads the model")
            .help("the model is reduced to the actuated coordinates through the loops only"),
        );
        return;
    }
    // The coordinates the model is read along, collected through a cell: `any` takes a `Fn`.
    let read = std::cell::RefCell::new(Vec::new());
    law.any(&|e| {
        if let SExpr::Call(call) = e {
            if crate::elab::model_laws::is_model_function(call.function) {
                for arg in &call.args {
                    if let SExpr::JoinCoordinate { join, index, .. } = **arg {
                        read.borrow_mut().push((join, index as usize));
                    }
                }
            }
        }
        false
    });
    let unactuated = read.into_inner().into_iter().find_map(|(join, index)| {
        let at = compiling.declared_offset(join).map(|o| o + index);
        at.is_none_or(|at| !declared.contains(&at))
            .then(|| compiling.coordinate_name(join, index))
    });
    if let Some(name) = unactuated {
        let actuated: Vec<String> = compiling
            .mechanism
            .actuators
            .iter()
            .map(|a| format!("`{}`", compiling.coordinate_name(a.join, a.coordinate)))
            .collect();
        let note = match actuated.is_empty() {
            true => "the program actuates no coordinate".to_string(),
            false => format!("the actuated coordinates: {}", actuated.join(", ")),
        };
        errors.push(
            Diagnostic::error("E0656", format!("the model is read along `{name}`, which is not actuated"))
                .primary(span, "reads the model along it")
                .note(note)
                .help(format!("the model is written in the actuated coordinates: `actuate {name} = ...;` adds it to them")),
        );
    }
}
