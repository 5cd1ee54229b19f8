//! The elaborator's state: the values of the names evaluated so far and the mechanism being
//! built. Declarations and expressions are evaluated in `eval.rs`, uniform fields in `fields.rs`.

use rustc_hash::FxHashMap;

use crate::check::scope::ScopeId;
use crate::check::Checked;
use crate::diag::Diagnostic;
use crate::load::{ModuleId, Workspace};
use crate::syntax::ast::Name;

use super::mechanism::Mechanism;
use super::value::{self, Value};

/// A declared name's value. `let` bindings are evaluated when first used, so a library costs
/// only what the mechanism takes from it.
pub(super) enum Global {
    Ready(Value),
    InProgress,
}

pub struct Elaborator<'c, 'w> {
    pub(super) workspace: &'w Workspace,
    pub(super) checked: &'c Checked<'w>,
    pub(super) globals: FxHashMap<(ScopeId, Name), Global>,
    pub(super) mechanism: Mechanism,
    pub(super) elaborated_modules: Vec<ModuleId>,
    pub(super) depth: usize,
    /// `apply F` declarations of uniform fields, expanded once every body is known.
    pub(super) fields: Vec<(value::EffortId, crate::source::Span)>,
    /// The numbers written in the program, by their bits: one node for each distinct number,
    /// shared by all its occurrences (a generated chain writes the same few numbers per body).
    pub(super) literals: FxHashMap<u64, value::Scalar>,
}

impl Elaborator<'_, '_> {
    /// The scalar of a number written in the program.
    pub(super) fn literal(&mut self, number: f64) -> value::Scalar {
        self.literals
            .entry(number.to_bits())
            .or_insert_with(|| value::num(number))
            .clone()
    }
}

/// An inconsistency between checker and elaborator: reported, never a panic.
pub(super) fn internal(message: impl Into<String>) -> Diagnostic {
    Diagnostic::error(
        "E0900",
        format!("internal error during elaboration: {}", message.into()),
    )
    .note("this is a bug in lsdc; please report it with the program that triggers it")
}
