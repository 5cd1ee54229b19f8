//! The checker's state: what checking produces (`Checked`), the definitions it instantiates,
//! and the context an expression is checked in. The checking itself is in the sibling files:
//! declarations (`mod.rs`), expressions (`expr.rs`) and calls (`calls.rs`).

use rustc_hash::FxHashMap;

use crate::diag::Diagnostics;
use crate::load::{ModuleId, Workspace};
use crate::source::Span;
use crate::syntax::ast::{Expr, Name, Param};

use super::resolutions::Resolutions;
use super::scope::Scope;
use super::types::{DefId, ScopeId, Ty};

/// A parameterised definition `let f(a, b) = body`.
pub struct Definition {
    pub name: Name,
    pub span: Span,
    /// The scope it was defined in and how many of that scope's names it sees.
    pub scope: ScopeId,
    pub limit: u32,
    /// Its declaration's position among its scope's declarations (see [`Scope::decls`]).
    pub decl: u32,
}

/// Where a `let` binding is: its declaration's position among its scope's declarations, and
/// its position among that declaration's bindings.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BindingAt {
    pub decl: u32,
    pub binding: u32,
}

/// The result of checking: scopes, definitions and name resolutions, for the elaborator.
/// Its tables are keyed by spans and names, hashed with the fast non-keyed hasher of
/// `rustc-hash`: they are the front end's hottest look-ups (every name use, several per body of
/// a large program), and a program cannot choose its keys to collide.
///
/// It holds no reference into the syntax tree, only positions in it, so that the elaborator
/// may free each declaration once it is done with it (see `elab::elaborate_consuming`).
pub struct Checked {
    pub scopes: Vec<Scope>,
    pub definitions: Vec<Definition>,
    pub resolutions: Resolutions,
    pub module_scopes: FxHashMap<ModuleId, ScopeId>,
    pub package_scopes: FxHashMap<Span, ScopeId>,
    /// Where the `let` binding of each declared name is, by the span of the name.
    pub bindings: FxHashMap<Span, BindingAt>,
}

impl Checked {
    pub fn scope(&self, id: ScopeId) -> &Scope {
        &self.scopes[id.0 as usize]
    }
}

/// A parameter, link coordinate or `local` binding in scope while checking an expression.
#[derive(Clone, Debug)]
pub(super) struct Local {
    pub(super) name: Name,
    pub(super) ty: Ty,
    /// Link coordinates are time-dependent: only they may be primed (`x'`).
    pub(super) coordinate: bool,
}

/// Where an expression is being checked.
pub(super) struct Ctx {
    pub(super) scope: ScopeId,
    pub(super) limit: u32,
    pub(super) locals: Vec<Local>,
}

pub struct Checker<'w> {
    pub(super) workspace: &'w Workspace,
    pub(super) out: Checked,
    /// The parameters and body of each definition, by its `DefId`: instantiations check them
    /// again.
    pub(super) definition_trees: Vec<(&'w [Param], &'w Expr)>,
    pub(super) diagnostics: Diagnostics,
    /// Use sites of the definitions being instantiated, innermost last.
    pub(super) instantiations: Vec<(Span, Name)>,
    pub(super) memo: FxHashMap<(DefId, Vec<Ty>), Ty>,
    pub(super) modules_in_progress: Vec<ModuleId>,
    pub(super) simulate_seen: Option<Span>,
    /// The outputs declared so far, by scope and name: a name is one group of columns.
    pub(super) outputs: std::collections::HashMap<(ScopeId, crate::syntax::ast::Name), Span>,
    /// How many more unknown names get a did-you-mean search (see [`MAX_SUGGESTIONS`]).
    pub(super) suggestions_left: std::cell::Cell<usize>,
    /// The (definition, name) pairs W0402 has warned about: once each.
    pub(super) shadow_warned: std::collections::HashSet<(crate::syntax::ast::Name, String)>,
    /// The names declared by value inputs (`input voltage = 0;`), by their spans: a second
    /// declaration of one is reported as an input declared twice.
    pub(super) value_inputs: std::collections::HashSet<Span>,
}

pub(super) const MAX_INSTANTIATION_DEPTH: usize = 64;

/// Unknown names that get a did-you-mean suggestion in one compilation: each search compares
/// the name with every visible one, so that without a bound a file of n misspelt names costs
/// n² comparisons; the first ones are those a reader fixes first.
pub(super) const MAX_SUGGESTIONS: usize = 100;
