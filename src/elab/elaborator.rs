//! The elaborator's state: the values of the names evaluated so far and the mechanism being
//! built. Declarations and expressions are evaluated in `eval.rs`, uniform fields in `fields.rs`.

use rustc_hash::FxHashMap;

use crate::check::scope::ScopeId;
use crate::check::Checked;
use crate::diag::Diagnostic;
use crate::load::{ModuleId, Workspace};
use crate::syntax::ast::Name;

use super::instances::{InstanceId, Instances};
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
    /// Values of declared names, by scope, instance (of an array of packages) and name.
    pub(super) globals: FxHashMap<(ScopeId, InstanceId, Name), Global>,
    pub(super) instances: Instances,
    /// The first name bound to each body by `let name = other_name` (see `point_out_alias`).
    pub(super) aliases: FxHashMap<value::BodyId, (Name, crate::source::Span)>,
    /// Warnings about legal programs that are probably not what was meant.
    pub(super) warnings: Vec<Diagnostic>,
    pub(super) mechanism: Mechanism,
    pub(super) elaborated_modules: Vec<ModuleId>,
    pub(super) depth: usize,
    /// `apply F` declarations of uniform fields, expanded once every body is known.
    pub(super) fields: Vec<(value::EffortId, crate::source::Span)>,
    /// The numbers written in the program, by their bits: one node for each distinct number,
    /// shared by all its occurrences (a generated chain writes the same few numbers per body).
    pub(super) literals: FxHashMap<u64, value::Scalar>,
    /// The named join whose link is being evaluated: its name reads its own coordinates.
    pub(super) own_join: Option<OwnJoin>,
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

/// The named join whose link is being evaluated, and the coordinate names its link read.
pub(super) struct OwnJoin {
    pub(super) id: value::JoinId,
    pub(super) name: Name,
    pub(super) read: Vec<(Name, crate::source::Span)>,
}
