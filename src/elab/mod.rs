//! Elaboration: evaluates a checked program into a [`Mechanism`]. Runs only on programs without
//! errors, following the checker's name resolutions. Each `?s` occurrence evaluated creates a
//! fresh unknown; a `let` evaluates its value once, when first used, so `let L = ?s;` is one
//! shared unknown and an unused definition costs nothing.

mod eval;
mod fields;
pub mod mechanism;
mod operations;
pub mod value;

use std::collections::HashMap;

use crate::check::scope::ScopeId;
use crate::check::Checked;
use crate::diag::Diagnostic;
use crate::load::{ModuleId, Workspace};
use crate::syntax::ast::Name;
pub use mechanism::{Mechanism, Summary};
use value::Value;

/// A declared name's value. `let` bindings are evaluated when first used, so a library costs
/// only what the mechanism takes from it.
enum Global {
    Ready(Value),
    InProgress,
}

pub struct Elaborator<'c, 'w> {
    workspace: &'w Workspace,
    checked: &'c Checked<'w>,
    globals: HashMap<(ScopeId, Name), Global>,
    mechanism: Mechanism,
    elaborated_modules: Vec<ModuleId>,
    depth: usize,
    /// `apply F` declarations of uniform fields, expanded once every body is known.
    fields: Vec<(value::EffortId, crate::source::Span)>,
}

/// Evaluates every module of a checked workspace into one mechanism.
pub fn elaborate(workspace: &Workspace, checked: &Checked<'_>) -> Result<Mechanism, Diagnostic> {
    let mut elaborator = Elaborator {
        workspace,
        checked,
        globals: HashMap::new(),
        mechanism: Mechanism::default(),
        elaborated_modules: Vec::new(),
        depth: 0,
        fields: Vec::new(),
    };
    for &root in &workspace.roots {
        elaborator.module(root)?;
    }
    elaborator.apply_fields()?;
    Ok(elaborator.mechanism)
}

/// An inconsistency between checker and elaborator: reported, never a panic.
fn internal(message: impl Into<String>) -> Diagnostic {
    Diagnostic::error(
        "E0900",
        format!("internal error during elaboration: {}", message.into()),
    )
    .note("this is a bug in lsdc; please report it with the program that triggers it")
}
