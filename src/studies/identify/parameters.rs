//! The parameters `lsdc identify` estimates, named as the program names what they belong to:
//! a body's ten inertial parameters about the origin of its frame, in its axes
//! (`upper.mass`, `upper.mx` … `upper.mz` for the first moments m c, `upper.Ixx` … `upper.Izz`
//! for the rotational inertia; `upper` alone for all ten), and a joint's friction (`elbow.friction`,
//! the dry force or torque F_c, and `elbow.damping`, the viscous coefficient c, as the link's
//! fields; `elbow` alone for both). All enter inverse dynamics linearly. What enters it otherwise (a length, a centre of
//! mass, principal moments and their frame, an unknown of the program) is refused here: its
//! fit is nonlinear (`identify::nonlinear`, on the runs' sensitivities).

use serde::Serialize;

use crate::diag::suggest::did_you_mean;
use crate::dynamics::algorithms::regressor::{INERTIAL_PARAMETERS, PARAMETERS_PER_BODY};
use crate::dynamics::model::Model;
use crate::elab::mechanism::Mechanism;
use crate::source::Span;

/// The friction parameters of a joint of one coordinate, as the link's fields name them.
pub const FRICTION_PARAMETERS: [&str; 2] = ["friction", "damping"];

/// What a parameter is, as a column of the regression.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Parameter {
    /// Parameter `index` of [`INERTIAL_PARAMETERS`] of body `body` (1..n).
    Inertial { body: usize, index: usize },
    /// Dry friction (F_c, opposing the rate) of the coordinate of velocity `velocity`.
    Dry { velocity: usize },
    /// Viscous friction (c) of the coordinate of velocity `velocity`.
    Viscous { velocity: usize },
}

/// Why a name is not a parameter `identify` estimates.
#[derive(Clone, Debug, PartialEq)]
pub enum NameError {
    /// Neither a body nor a joint of one coordinate with that parameter; the closest name.
    Unknown {
        name: String,
        suggestion: Option<String>,
    },
    /// A quantity of a body that enters the dynamics nonlinearly (`upper.inertia`).
    NonlinearBody { name: String, body: String },
    /// A named unknown of the program, declared at `span`: it may enter the dynamics
    /// nonlinearly (a length), and its fit needs the sensitivities.
    ProgramUnknown { name: String, span: Span },
    /// Friction on a joint that does not have one coordinate.
    NotOneCoordinate { name: String, join: String },
}

impl std::fmt::Display for NameError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            NameError::Unknown { name, suggestion } => {
                write!(f, "`--parameters {name}`: no body or joint of the mechanism has a parameter `{name}`")?;
                match suggestion {
                    Some(s) => write!(f, "; did you mean `{s}`?"),
                    None => write!(f, " (a body's `mass`, `mx`, `my`, `mz`, `Ixx`, `Ixy`, `Ixz`, `Iyy`, `Iyz`, `Izz`, or the body's name for all ten; a joint's `friction` or `damping`, or its name for both)"),
                }
            }
            NameError::NonlinearBody { name, body } => write!(f, "`--parameters {name}`: the centre of mass, the principal moments and their frame enter the dynamics nonlinearly; identify `{body}` (its mass, first moments `{body}.mx` … and inertia `{body}.Ixx` … about its frame's origin, which enter linearly, and from which they follow)"),
            NameError::ProgramUnknown { name, .. } => write!(f, "`--parameters {name}`: `{name}` is an unknown of the program, which may enter the dynamics nonlinearly (a length, an angle); `identify` fits the parameters that enter linearly (bodies' inertial parameters, joints' friction); it is fitted to measured motion by the nonlinear fit (`identify::nonlinear`), apart from these"),
            NameError::NotOneCoordinate { name, join } => write!(f, "`--parameters {name}`: `{join}` does not have one coordinate: friction is identified on revolute and prismatic joints"),
        }
    }
}

impl std::error::Error for NameError {}

/// The name of a parameter: `upper.Ixx`, `elbow.friction`.
pub fn parameter_name(model: &Model, parameter: Parameter) -> String {
    match parameter {
        Parameter::Inertial { body, index } => {
            format!(
                "{}.{}",
                model.body_names[body - 1],
                INERTIAL_PARAMETERS[index]
            )
        }
        Parameter::Dry { velocity } => format!("{}.friction", joint_name(model, velocity)),
        Parameter::Viscous { velocity } => format!("{}.damping", joint_name(model, velocity)),
    }
}

fn joint_name(model: &Model, velocity: usize) -> &str {
    model
        .joint_of_velocity(velocity)
        .map_or("", |j| j.chain.name.as_str())
}

/// The parameters asked for, in order, each once.
#[derive(Clone, Debug, PartialEq)]
pub struct Asked {
    pub parameters: Vec<Parameter>,
    /// Per parameter, whether it was named itself (`upper.Ixx`), not through its body's or
    /// joint's name (`upper`): a parameter named itself that cannot be identified is refused,
    /// one asked for through a name of several is reported without effect.
    pub explicit: Vec<bool>,
}

/// The parameters named by `names` (a body's name gives its ten, a joint's its two).
pub fn resolve(model: &Model, mechanism: &Mechanism, names: &[String]) -> Result<Asked, NameError> {
    let mut asked = Asked {
        parameters: Vec::new(),
        explicit: Vec::new(),
    };
    for name in names {
        let found = resolve_one(model, mechanism, name)?;
        let explicit = found.len() == 1;
        for parameter in found {
            match asked.parameters.iter().position(|p| *p == parameter) {
                Some(k) => asked.explicit[k] |= explicit,
                None => {
                    asked.parameters.push(parameter);
                    asked.explicit.push(explicit);
                }
            }
        }
    }
    Ok(asked)
}

fn resolve_one(
    model: &Model,
    mechanism: &Mechanism,
    name: &str,
) -> Result<Vec<Parameter>, NameError> {
    let body = |b: &str| model.body_names.iter().position(|n| n == b).map(|i| i + 1);
    if let Some(b) = body(name) {
        let all = (0..PARAMETERS_PER_BODY).map(|index| Parameter::Inertial { body: b, index });
        return Ok(all.collect());
    }
    let joint = |j: &str| model.joints.iter().find(|joint| joint.chain.name == j);
    if let Some(joint) = joint(name).filter(|j| j.is_single_coordinate()) {
        let velocity = joint.v_offset;
        return Ok(vec![
            Parameter::Dry { velocity },
            Parameter::Viscous { velocity },
        ]);
    }
    if let Some((owner, field)) = name.rsplit_once('.') {
        if let Some(b) = body(owner) {
            if let Some(index) = INERTIAL_PARAMETERS.iter().position(|p| *p == field) {
                return Ok(vec![Parameter::Inertial { body: b, index }]);
            }
            if ["com", "iframe", "inertia", "centre"].contains(&field) {
                return Err(NameError::NonlinearBody {
                    name: name.to_string(),
                    body: owner.to_string(),
                });
            }
        }
        if let (Some(joint), Some(k)) = (
            joint(owner),
            FRICTION_PARAMETERS.iter().position(|p| *p == field),
        ) {
            if !joint.is_single_coordinate() {
                return Err(NameError::NotOneCoordinate {
                    name: name.to_string(),
                    join: owner.to_string(),
                });
            }
            let velocity = joint.v_offset;
            return Ok(vec![match k {
                0 => Parameter::Dry { velocity },
                _ => Parameter::Viscous { velocity },
            }]);
        }
    }
    let unknown =
        (mechanism.unknowns.iter()).find(|u| u.name.as_ref().is_some_and(|n| n.as_str() == name));
    if let Some(unknown) = unknown {
        return Err(NameError::ProgramUnknown {
            name: name.to_string(),
            span: unknown.span,
        });
    }
    let candidates = every_name(model);
    let suggestion = did_you_mean(name, candidates.iter().map(String::as_str)).map(String::from);
    Err(NameError::Unknown {
        name: name.to_string(),
        suggestion,
    })
}

/// Every name `resolve` takes: the bodies, their parameters and the joints' friction.
fn every_name(model: &Model) -> Vec<String> {
    let mut names = Vec::new();
    for body in &model.body_names {
        names.push(body.clone());
        names.extend(INERTIAL_PARAMETERS.iter().map(|p| format!("{body}.{p}")));
    }
    for joint in model.joints.iter().filter(|j| j.is_single_coordinate()) {
        let join = &joint.chain.name;
        names.push(join.clone());
        names.extend(FRICTION_PARAMETERS.iter().map(|p| format!("{join}.{p}")));
    }
    names
}

/// The model's value of `parameter`: the body's, or the joint's friction (0 without any).
pub fn model_value(model: &Model, parameter: Parameter) -> f64 {
    let friction = |velocity: usize| model.frictions.iter().find(|f| f.velocity == velocity);
    match parameter {
        Parameter::Inertial { body, index } => {
            crate::dynamics::algorithms::regressor::parameters_of(&model.bodies[body - 1].rigid)
                [index]
        }
        Parameter::Dry { velocity } => friction(velocity).map_or(0.0, |f| f.dry),
        Parameter::Viscous { velocity } => friction(velocity).map_or(0.0, |f| f.viscous),
    }
}
