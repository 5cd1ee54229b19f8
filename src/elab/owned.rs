//! The declarations of the root files that the elaborator owns, and a declaration being read
//! by it; how they are read, kept and freed is in `decls.rs`.

use std::ops::Deref;
use std::rc::Rc;

use rustc_hash::FxHashMap;

use crate::syntax::ast::Decl;

/// A declaration being read.
pub(super) enum DeclRef<'w> {
    /// In the workspace's syntax tree.
    Tree(&'w Decl),
    /// Taken out of a root file the elaborator owns: given back (`Elaborator::give_back`) to be
    /// kept or freed.
    Taken(Decl),
    /// A definition or package of a root file the elaborator owns, kept for the whole
    /// elaboration.
    Shared(Rc<Decl>),
}

impl Deref for DeclRef<'_> {
    type Target = Decl;

    fn deref(&self) -> &Decl {
        match self {
            DeclRef::Tree(decl) => decl,
            DeclRef::Taken(decl) => decl,
            DeclRef::Shared(decl) => decl,
        }
    }
}

/// The top-level declarations of a root file, owned by the elaborator. A declaration taken out
/// leaves an error declaration (`DeclKind::Error`) with its span in its place, until it is put
/// back; one that was freed leaves it for good.
#[derive(Default)]
pub(super) struct OwnedDecls {
    pub(super) decls: Vec<Decl>,
    /// Definitions and packages, by position, once first read.
    pub(super) shared: FxHashMap<u32, Rc<Decl>>,
}

impl OwnedDecls {
    pub(super) fn new(decls: Vec<Decl>) -> OwnedDecls {
        OwnedDecls {
            decls,
            shared: FxHashMap::default(),
        }
    }
}
