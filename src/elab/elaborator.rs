//! The elaborator's state: the values of the names evaluated so far and the mechanism being
//! built. Declarations and expressions are evaluated in `eval.rs`, uniform fields in `fields.rs`.

use rustc_hash::FxHashMap;

use crate::check::resolutions::Cursor;
use crate::check::scope::ScopeId;
use crate::check::Checked;
use crate::diag::Diagnostic;
use crate::load::{ModuleId, Workspace};
use crate::syntax::ast::Name;

use super::instances::{InstanceId, Instances};
use super::mechanism::Mechanism;
use super::owned::OwnedDecls;
use super::value::{self, Value};

/// A declared name's value. `let` bindings are evaluated when first used, so a library costs
/// only what the mechanism takes from it.
pub(super) enum Global {
    Ready(Value),
    InProgress,
}

pub struct Elaborator<'c, 'w> {
    pub(super) workspace: &'w Workspace,
    pub(super) checked: &'c Checked,
    /// The top-level declarations of the root files, by module, when the elaborator owns them
    /// and frees each once it is done with it (`decls.rs`); the others are read in `workspace`.
    pub(super) owned: Vec<Option<OwnedDecls>>,
    /// Values of declared names, by scope, instance (of an array of packages) and name.
    pub(super) globals: FxHashMap<(ScopeId, InstanceId, Name), Global>,
    pub(super) instances: Instances,
    /// Where the last name resolution was found (see
    /// [`Resolutions::get_near`](crate::check::resolutions::Resolutions::get_near)).
    pub(super) resolved: Cursor,
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
    /// How the numbers written with a decimal point are moved (`lsdc test --perturb`).
    pub(super) perturbation: Option<Perturbation>,
    /// The applied efforts the selected scene keeps (`None`: all of them).
    pub(super) effort_filter: Option<super::effort_choice::EffortFilter>,
    /// The packages and instances of arrays around the declaration being elaborated,
    /// outermost first (`arm[1]`): the groups an `apply` answers to.
    pub(super) enclosing_groups: Vec<String>,
}

/// A round-off probe of a program's own numbers: each number written with a decimal point
/// (`0.3`, `1.0`, `2e-3`) moved by `relative` of itself, up or down as a pseudo-random function
/// of the number and `seed` decides: the same number moves the same way everywhere in a run.
/// Integers are left alone: they are exact, and some count or index.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Perturbation {
    pub relative: f64,
    pub seed: u64,
}

impl Perturbation {
    pub fn apply(&self, number: f64) -> f64 {
        // SplitMix64 of the number's bits and the seed: its lowest bit is the direction.
        let mut z = (number.to_bits() ^ self.seed.wrapping_mul(0x9E37_79B9_7F4A_7C15))
            .wrapping_add(0x9E37_79B9_7F4A_7C15);
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        let direction = if z & 1 == 0 { 1.0 } else { -1.0 };
        number + direction * self.relative * number.abs()
    }
}

impl<'c, 'w> Elaborator<'c, 'w> {
    /// An elaborator that has evaluated nothing yet.
    pub(super) fn new(workspace: &'w Workspace, checked: &'c Checked) -> Self {
        Elaborator {
            workspace,
            checked,
            owned: Vec::new(),
            globals: FxHashMap::default(),
            mechanism: Mechanism::default(),
            elaborated_modules: Vec::new(),
            depth: 0,
            fields: Vec::new(),
            literals: FxHashMap::default(),
            own_join: None,
            perturbation: None,
            instances: Default::default(),
            resolved: Cursor::default(),
            aliases: FxHashMap::default(),
            warnings: Vec::new(),
            effort_filter: super::effort_choice::EffortFilter::new(&workspace.scenes.efforts),
            enclosing_groups: Vec::new(),
        }
    }

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
