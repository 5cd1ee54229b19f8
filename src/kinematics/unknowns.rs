//! Values of the program's unknowns: from its `given` declarations, then from values given by
//! name on the command line (`--set NAME=VALUE`). Every name an unknown answers to is accepted.

use std::collections::HashMap;

use crate::diag::{suggest, Diagnostic};
use crate::elab::mechanism::{Mechanism, Origin, UnknownKind};
use crate::elab::value::{Scalar, UnknownId};

use super::eval::{eval, UnknownValues};

/// A value given on the command line: `--set NAME=VALUE`.
#[derive(Clone, Debug)]
pub struct Override {
    pub name: String,
    pub value: f64,
}

/// A `NAME=VALUE` that cannot be read.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum OverrideError {
    /// No `=`.
    NoEquals { text: String },
    /// Nothing before the `=`.
    NoName { text: String },
    /// The right-hand side is not a number.
    NotANumber { text: String, value: String },
    /// The right-hand side is not a finite number (`nan`, `inf`, `1e309`).
    NotFinite { text: String, value: String },
}

impl std::fmt::Display for OverrideError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            OverrideError::NoEquals { text } => write!(f, "`--set {text}`: write NAME=VALUE"),
            OverrideError::NoName { text } => {
                write!(f, "`--set {text}`: no name before `=`; write NAME=VALUE")
            }
            OverrideError::NotANumber { text, value } => {
                write!(f, "`--set {text}`: `{value}` is not a number")
            }
            OverrideError::NotFinite { text, value } => {
                write!(f, "`--set {text}`: `{value}` is not a finite number")
            }
        }
    }
}

impl std::error::Error for OverrideError {}

impl std::str::FromStr for Override {
    type Err = OverrideError;

    /// Reads `NAME=VALUE` (the value is the last `=`'s right-hand side, a number).
    fn from_str(text: &str) -> Result<Override, OverrideError> {
        let (name, value) = text
            .rsplit_once('=')
            .ok_or_else(|| OverrideError::NoEquals {
                text: text.to_string(),
            })?;
        let number: f64 = value
            .trim()
            .parse()
            .map_err(|_| OverrideError::NotANumber {
                text: text.to_string(),
                value: value.to_string(),
            })?;
        if name.trim().is_empty() {
            return Err(OverrideError::NoName {
                text: text.to_string(),
            });
        }
        if !number.is_finite() {
            return Err(OverrideError::NotFinite {
                text: text.to_string(),
                value: value.to_string(),
            });
        }
        Ok(Override {
            name: name.trim().to_string(),
            value: number,
        })
    }
}

pub fn constant(s: &Scalar, values: &UnknownValues) -> Option<f64> {
    eval(s, values).ok()
}

/// Values of the unknowns from the program's `given` declarations.
pub fn given_values(mechanism: &Mechanism) -> Result<UnknownValues, Vec<Diagnostic>> {
    unknown_values(mechanism, &HashMap::new(), &[])
}

/// Values of the unknowns from `given` declarations, then the command line.
pub fn unknown_values(
    mechanism: &Mechanism,
    generated: &HashMap<UnknownId, String>,
    overrides: &[Override],
) -> Result<UnknownValues, Vec<Diagnostic>> {
    let mut values = UnknownValues::new();
    let mut errors = Vec::new();
    for (id, value, span) in &mechanism.given {
        match constant(value, &values) {
            Some(v) => {
                values.insert(*id, v);
            }
            None => errors.push(
                Diagnostic::error("E0810", "a given value must be a number").primary(*span, "here"),
            ),
        }
    }
    let mut by_name: HashMap<String, UnknownId> = HashMap::new();
    for index in 0..mechanism.unknowns.len() {
        let id = UnknownId(index as u32);
        for name in names_of(mechanism, generated, id) {
            by_name.entry(name).or_insert(id);
        }
    }
    for o in overrides {
        match by_name.get(&o.name) {
            Some(&id) if mechanism.unknowns[id.0 as usize].kind == UnknownKind::Function => {
                errors.push(
                    Diagnostic::error("E0811", format!("`--set {}`: an unknown function takes a law, not a value", o.name))
                        .help("write the law in the program, for example `torque = [-k * x - c * x', 0, 0]`"),
                );
            }
            Some(&id) => {
                values.insert(id, o.value);
            }
            None => {
                let help = suggest::did_you_mean(&o.name, by_name.keys().map(String::as_str))
                    .map(|s| format!("did you mean `{s}`?"))
                    .unwrap_or_else(|| {
                        "`lsdc compile FILE --emit notation` lists the generated names".to_string()
                    });
                errors.push(
                    Diagnostic::error(
                        "E0811",
                        format!(
                            "`--set {}`: the program has no unknown of that name",
                            o.name
                        ),
                    )
                    .help(help),
                );
            }
        }
    }
    if errors.is_empty() {
        Ok(values)
    } else {
        Err(errors)
    }
}

/// Every name an unknown answers to: its `let` name, its generated name, its generic name.
pub fn names_of(
    mechanism: &Mechanism,
    generated: &HashMap<UnknownId, String>,
    id: UnknownId,
) -> Vec<String> {
    let unknown = &mechanism.unknowns[id.0 as usize];
    let mut names = Vec::new();
    if let Some(name) = &unknown.name {
        names.push(name.to_string());
    }
    if unknown.origin != Origin::Written {
        names.push(mechanism.generic_name(unknown.origin));
    }
    if let Some(name) = generated.get(&id) {
        names.push(name.clone());
    }
    if names.is_empty() {
        // Written somewhere the notation table does not name (an applied effort): number it.
        names.push(format!("unknown{}", id.0 + 1));
    }
    names.dedup();
    names
}
