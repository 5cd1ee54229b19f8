//! Where the elaborator reads declarations: the workspace's syntax tree, or the declarations of
//! the root files when the elaborator owns them (`elaborate_consuming`), so that each is freed
//! once it has been elaborated and the syntax tree shrinks while the mechanism grows: the
//! front end's peak is then the larger of the two, not their sum.
//!
//! What is freed, and when: a `join`, `apply`, `given`, `initial`, `output`, `simulate` or
//! `import` once it is elaborated; a `let` once each of its names has its value (a `let` is
//! evaluated at its first use, see `Elaborator::global`). Definitions and packages are kept:
//! they are read again at each use, and while they are being evaluated (a definition's body may
//! call it again, a package's names are read from its own declarations). Only the top level of
//! a root file is owned: the declarations of packages and of imported libraries are read in
//! place.

use std::rc::Rc;

use super::elaborator::{internal, Elaborator, Global};
use super::instances::ROOT;
use super::owned::{DeclRef, OwnedDecls};
use crate::check::scope::{DeclsAt, ScopeId};
use crate::diag::Diagnostic;
use crate::load::ModuleId;
use crate::syntax::ast::{Decl, DeclKind};

type Result<T> = std::result::Result<T, Diagnostic>;

impl<'w> Elaborator<'_, 'w> {
    /// How many declarations a scope has.
    pub(super) fn decl_count(&self, scope: ScopeId) -> Result<u32> {
        match self.checked.scope(scope).decls {
            DeclsAt::Module(module) => Ok(match self.owned_decls(module) {
                Some(owned) => owned.decls.len(),
                None => self.workspace.module(module).program.decls.len(),
            } as u32),
            DeclsAt::Package { .. } => Err(internal("a package's declarations counted")),
        }
    }

    /// Runs `f` on the `index`-th declaration of `scope`, then gives it back (see
    /// [`Elaborator::give_back`]).
    pub(super) fn with_decl<T>(
        &mut self,
        scope: ScopeId,
        index: u32,
        f: impl FnOnce(&mut Self, &Decl) -> Result<T>,
    ) -> Result<T> {
        if let DeclsAt::Module(module) = self.checked.scope(scope).decls {
            let decl = self.top_decl(module, index)?;
            let result = f(self, &decl);
            self.give_back(module, index, decl);
            return result;
        }
        // The top-level declaration the package is in, and the positions that lead from it
        // through packages to the declaration asked for.
        let mut path = vec![index];
        let mut at = scope;
        let module = loop {
            match self.checked.scope(at).decls {
                DeclsAt::Module(module) => break module,
                DeclsAt::Package { parent, decl } => {
                    path.push(decl);
                    at = parent;
                }
            }
        };
        let top_index = path.pop().unwrap_or(index);
        let top = self.top_decl(module, top_index)?;
        let mut decl: &Decl = &top;
        for &position in path.iter().rev() {
            let DeclKind::Package(package) = &decl.kind else {
                return Err(internal("a package's declarations outside a package"));
            };
            decl = package
                .decls
                .get(position as usize)
                .ok_or_else(|| internal("a declaration past its package's end"))?;
        }
        let result = f(self, decl);
        self.give_back(module, top_index, top);
        result
    }

    /// The declarations of `module` if the elaborator owns them.
    fn owned_decls(&self, module: ModuleId) -> Option<&OwnedDecls> {
        self.owned.get(module.0 as usize)?.as_ref()
    }

    /// The `index`-th top-level declaration of `module`.
    fn top_decl(&mut self, module: ModuleId, index: u32) -> Result<DeclRef<'w>> {
        let Some(owned) = self
            .owned
            .get_mut(module.0 as usize)
            .and_then(Option::as_mut)
        else {
            let decls = &self.workspace.module(module).program.decls;
            return (decls.get(index as usize))
                .map(DeclRef::Tree)
                .ok_or_else(|| internal("a declaration past its file's end"));
        };
        let slot = (owned.decls.get_mut(index as usize))
            .ok_or_else(|| internal("a declaration past its file's end"))?;
        if matches!(slot.kind, DeclKind::Error) {
            return match owned.shared.get(&index) {
                Some(shared) => Ok(DeclRef::Shared(shared.clone())),
                None => Err(internal("a declaration read after it was freed")),
            };
        }
        let span = slot.span;
        let decl = std::mem::replace(
            slot,
            Decl {
                kind: DeclKind::Error,
                span,
            },
        );
        if !matches!(decl.kind, DeclKind::Define(_) | DeclKind::Package(_)) {
            return Ok(DeclRef::Taken(decl));
        }
        let shared = Rc::new(decl);
        owned.shared.insert(index, shared.clone());
        Ok(DeclRef::Shared(shared))
    }

    /// Gives back a declaration taken out of a root file: a `let` some of whose names have no
    /// value yet is put back in its place; any other is freed.
    fn give_back(&mut self, module: ModuleId, index: u32, decl: DeclRef<'w>) {
        let DeclRef::Taken(decl) = decl else {
            return;
        };
        if let DeclKind::Let(bindings) = &decl.kind {
            let scope = self.checked.module_scopes.get(&module).copied();
            let evaluated = |name| {
                let value = scope.and_then(|scope| self.globals.get(&(scope, ROOT, name)));
                matches!(value, Some(Global::Ready(_)))
            };
            if !bindings.iter().all(|b| evaluated(b.name.name)) {
                if let Some(Some(owned)) = self.owned.get_mut(module.0 as usize) {
                    owned.decls[index as usize] = decl;
                }
            }
        }
    }
}
