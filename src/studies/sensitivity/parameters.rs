//! The parameters of a sensitivity study, named as `lsdc sweep` names what it varies: an
//! initial value (`swing.q`, its rate `swing.q'`) or a value of the program (an unknown or a
//! `given` value, by any name `--set` accepts: `L`, `mass(rod)`). A name that is neither is
//! refused at the declaration whose name is nearest (E0861), a name of something that is not
//! a number (a body, a join, an unknown function) at that thing's declaration (E0862).

use std::collections::HashMap;

use crate::diag::{suggest, Diagnostic};
use crate::elab::mechanism::{Mechanism, UnknownKind};
use crate::elab::value::{JoinId, UnknownId};
use crate::kinematics::unknowns::{names_of, unknown_values, Override};
use crate::source::Span;
use crate::studies::sweep::runs::{coordinate_targets, Target};
use crate::topology::{self, notation};

/// A parameter: its name, what it sets, and its value in the program (with `--set`).
#[derive(Clone, Debug)]
pub struct Parameter {
    pub name: String,
    pub target: Target,
    pub value: f64,
}

/// Resolves `names` against the mechanism (values from `given` and `overrides`); the
/// initial values' values are the prepared start's, filled in by the caller (`start_values`).
pub fn resolve(
    mechanism: &Mechanism,
    overrides: &[Override],
    names: &[String],
) -> Result<Vec<Parameter>, Vec<Diagnostic>> {
    let coordinates = coordinate_targets(mechanism);
    let topology = topology::build(mechanism)?;
    let generated = notation::unknown_names(mechanism, &topology);
    let values = unknown_values(mechanism, &generated, overrides)?;
    let unknowns = unknowns_by_name(mechanism, &generated);
    let mut parameters = Vec::new();
    let mut errors = Vec::new();
    for (index, name) in names.iter().enumerate() {
        if names[..index].contains(name) {
            errors.push(Diagnostic::error(
                "E0861",
                format!("the parameter `{name}` is named twice"),
            ));
            continue;
        }
        if let Some(&target) = coordinates.get(name) {
            parameters.push(Parameter {
                name: name.clone(),
                target,
                value: f64::NAN,
            });
            continue;
        }
        match unknowns.get(name) {
            Some(&id) => match not_a_number(mechanism, name, id) {
                Some(refusal) => errors.push(refusal),
                None => parameters.push(Parameter {
                    name: name.clone(),
                    target: Target::Value,
                    value: values.get(&id).copied().unwrap_or(f64::NAN),
                }),
            },
            None => errors.push(unknown_parameter(mechanism, name, &unknowns)),
        }
    }
    match errors.is_empty() {
        true => Ok(parameters),
        false => Err(errors),
    }
}

/// Every name an unknown answers to (as `--set` reads them), the first unknown of a name kept.
fn unknowns_by_name(
    mechanism: &Mechanism,
    generated: &HashMap<UnknownId, String>,
) -> HashMap<String, UnknownId> {
    let mut by_name = HashMap::new();
    for index in 0..mechanism.unknowns.len() {
        let id = UnknownId(index as u32);
        for name in names_of(mechanism, generated, id) {
            by_name.entry(name).or_insert(id);
        }
    }
    by_name
}

/// E0862 for an unknown that is not a number: an unknown function.
fn not_a_number(mechanism: &Mechanism, name: &str, id: UnknownId) -> Option<Diagnostic> {
    let unknown = &mechanism.unknowns[id.0 as usize];
    let (what, help) = match unknown.kind {
        UnknownKind::Function => (
            "an unknown function",
            "a sensitivity is a derivative with respect to a number: write the law in the program with unknown numbers in it (`let k = ?s;` … `-k * x`) and name those",
        ),
        // A vector's component is one number, a parameter like any scalar unknown.
        UnknownKind::Scalar | UnknownKind::Vector | UnknownKind::Generic => return None,
    };
    Some(refused(name, what, unknown.span).help(help))
}

fn refused(name: &str, what: &str, span: Span) -> Diagnostic {
    Diagnostic::error(
        "E0862",
        format!("the parameter `{name}` is {what}, not a number"),
    )
    .primary(span, format!("`{name}` is declared here"))
}

/// E0862 when `name` is a body or a join (a number of it is meant), else E0861 at the
/// declaration of the parameter whose name is nearest, or without a place when none is near.
fn unknown_parameter(
    mechanism: &Mechanism,
    name: &str,
    unknowns: &HashMap<String, UnknownId>,
) -> Diagnostic {
    let joins = (0..mechanism.joins.len() as u32).map(JoinId);
    let mut declared: Vec<(String, Span)> = Vec::new();
    for id in joins {
        let join = mechanism.join(id);
        let link = mechanism.link(join.link);
        let join_name = mechanism.join_name(id);
        if join_name == name {
            let coordinates: Vec<String> = (link.coordinates.iter())
                .map(|c| format!("`{name}.{}`", &**c))
                .collect();
            return refused(name, "a join", join.span).help(format!(
                "its coordinates' initial values are parameters: {}",
                coordinates.join(", ")
            ));
        }
        for coordinate in &link.coordinates {
            let coordinate = format!("{join_name}.{}", &**coordinate);
            declared.push((format!("{coordinate}'"), join.span));
            declared.push((coordinate, join.span));
        }
    }
    let body = (mechanism.bodies.iter()).find(|b| b.name.as_deref() == Some(name));
    if let Some(body) = body {
        return refused(name, "a body", body.span).help(format!(
            "its mass and inertia are parameters when the program leaves them unknown (`mass = ?s`, or no mass at all): name them `mass({name})`, `inertia_x({name})`"
        ));
    }
    for (unknown, &id) in unknowns {
        let span = mechanism.unknowns[id.0 as usize].span;
        declared.push((unknown.clone(), span));
    }
    declared.sort();
    let message = format!("the program has no parameter `{name}`");
    // `given` writes a body's generic quantities `rod.mass`; `--set` and sweeps `mass(rod)`.
    let generic = (name.rsplit_once('.')).map(|(owner, field)| format!("{field}({owner})"));
    let nearest = match generic.filter(|g| declared.iter().any(|(n, _)| n == g)) {
        Some(generic) => Some(generic),
        None => suggest::did_you_mean(name, declared.iter().map(|(n, _)| n.as_str()))
            .map(str::to_string),
    };
    let listed = || {
        let names: Vec<String> = declared.iter().map(|(n, _)| format!("`{n}`")).collect();
        names.join(", ")
    };
    match nearest.and_then(|n| declared.iter().find(|(d, _)| *d == n)) {
        Some((nearest, span)) => Diagnostic::error("E0861", message)
            .primary(*span, format!("`{nearest}` is declared here"))
            .help(format!("did you mean `{nearest}`?")),
        None => Diagnostic::error("E0861", message).help(format!(
            "a parameter is an initial value (`JOIN.COORD`, its rate `JOIN.COORD'`) or an unknown of the program; this one's are {}",
            listed()
        )),
    }
}
