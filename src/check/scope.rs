//! Scopes: the names a file, a package or the standard library defines, in declaration order.
//! A name is visible after its declaration; a parameterised definition sees the names declared
//! before it, whenever it is instantiated.

use rustc_hash::FxHashMap;

pub use super::types::ScopeId;
use super::types::Ty;
use crate::source::Span;
use crate::syntax::ast::Name;

#[derive(Clone, Debug)]
pub struct Entry {
    pub ty: Ty,
    pub span: Span,
    /// Position in the scope's declaration order.
    pub index: u32,
}

#[derive(Debug)]
pub struct Scope {
    pub names: FxHashMap<Name, Entry>,
    /// Names in declaration order.
    pub order: Vec<Name>,
    /// The enclosing scope (a package's file) and how many of its names were visible then.
    pub parent: Option<(ScopeId, u32)>,
    /// The index of an array of packages (`i` in `package P[i in 1 .. 4]`): its declarations
    /// are evaluated once per instance.
    pub index: Option<Name>,
    /// Modules opened by a plain `import`, with the number of this scope's names declared before.
    pub opened: Vec<(ScopeId, u32)>,
    /// Names declared later in this scope, with the span of the name and the extent of their
    /// declaration: a use before the declaration gets a precise message. Made when a name is
    /// first found missing (`None` before), then kept as names are declared.
    pub declared_later: Option<FxHashMap<Name, (Span, Span)>>,
    /// Where the scope's declarations are in the syntax tree.
    pub decls: DeclsAt,
}

/// Where a scope's declarations are: a module's top level, or a package declared in another
/// scope.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DeclsAt {
    Module(crate::load::ModuleId),
    /// The package declared by the `decl`-th declaration of the scope `parent`.
    Package {
        parent: ScopeId,
        decl: u32,
    },
}

impl Scope {
    pub fn new(parent: Option<(ScopeId, u32)>, decls: DeclsAt) -> Scope {
        Scope {
            names: FxHashMap::default(),
            order: Vec::new(),
            parent,
            index: None,
            opened: Vec::new(),
            declared_later: None,
            decls,
        }
    }

    pub fn len(&self) -> u32 {
        self.order.len() as u32
    }

    #[cfg(lsdc_internals)]
    pub fn is_empty(&self) -> bool {
        self.order.is_empty()
    }

    /// The entry for `name` if it was declared among the first `limit` names.
    pub fn get(&self, name: &str, limit: u32) -> Option<&Entry> {
        self.names.get(name).filter(|e| e.index < limit)
    }

    pub fn insert(&mut self, name: Name, ty: Ty, span: Span) {
        let index = self.len();
        if let Some(later) = &mut self.declared_later {
            later.remove(&name);
        }
        self.order.push(name);
        self.names.insert(name, Entry { ty, span, index });
    }
}

/// Where a name use was resolved; the elaborator follows these instead of resolving again.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Target {
    /// A parameter, link coordinate or `local` binding: the innermost local of that name.
    Local,
    /// A declaration of a file or package scope.
    Global(ScopeId),
    /// `pi`, `earth`, `sin`, …
    Builtin,
}
