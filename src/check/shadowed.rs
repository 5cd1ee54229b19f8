//! W0402: a library definition that reads a library name the program declares again. The
//! definition reads the library's own (`weight` of `import gravity;` weighs with the library's
//! `g`, 9.80665), whatever the program's `let g = 1.62;` says, so the program's value silently
//! does not reach it.

use super::checker::{Checker, Ctx};
use super::scope::{ScopeId, Target};
use crate::diag::Diagnostic;
use crate::source::Span;
use crate::syntax::ast::Ident;

impl<'w> Checker<'w> {
    /// Warns, once per definition and name, when `ident`, found in the opened module `library`,
    /// names a definition that reads a name of `library` that the scope of the use declares too.
    pub(super) fn warn_if_shadowed(&mut self, ident: &Ident, library: ScopeId, ctx: &Ctx) {
        let Some(extent) = self.declaration_extent(library, ident) else {
            return;
        };
        let uses = self.out.resolutions.global_uses_within(extent, library);
        for read in uses {
            let read_name = self.source(read).to_string();
            if read_name == ident.name.as_ref() {
                continue;
            }
            let Some((Target::Global(own), _)) =
                self.lookup_global(&read_name, ctx.scope, ctx.limit)
            else {
                continue;
            };
            if own == library || !self.shadow_warned.insert((ident.name, read_name.clone())) {
                continue;
            }
            let Some(own_entry) = self.out.scope(own).names.get(read_name.as_str()) else {
                continue;
            };
            let name = &ident.name;
            let diagnostic = Diagnostic::warning(
                "W0402",
                format!("`{name}` reads the library's `{read_name}`, not this program's"),
            )
            .primary(ident.span, format!("uses the library's `{read_name}`"))
            .secondary(
                own_entry.span,
                "this declaration does not reach the library",
            )
            .help(self.shadow_help(name, &read_name, library));
            self.report(diagnostic);
        }
    }

    /// The extent of the declaration of `ident`'s name in `scope`: the declaration around the
    /// name's.
    fn declaration_extent(&self, scope: ScopeId, ident: &Ident) -> Option<Span> {
        let name = self.out.scope(scope).names.get(&ident.name)?.span;
        self.scope_decls(scope)
            .iter()
            .map(|decl| decl.span)
            .find(|extent| {
                extent.file() == name.file()
                    && extent.start() <= name.start()
                    && name.end() <= extent.end()
            })
    }

    /// How to pass the program's value: a library definition with it as a parameter, where the
    /// library has one (the gravity library's `weight_in` and `uniform_field`).
    fn shadow_help(&self, name: &str, read_name: &str, library: ScopeId) -> String {
        let has = |n: &str| self.out.scope(library).names.contains_key(n);
        match (name, read_name) {
            ("weight", "g") if has("weight_in") => {
                "pass the acceleration as an argument: `weight_in(b, [0, 0, -g])` weighs `b` with this program's `g`".to_string()
            }
            ("gravity_field", "g") if has("uniform_field") => {
                "pass the acceleration as an argument: `uniform_field([0, 0, -g])` weighs every body with this program's `g`".to_string()
            }
            _ => format!("a library's definitions read its own names: pass `{read_name}` as an argument of a definition of yours, or rename this program's `{read_name}` if it means something else"),
        }
    }
}

/// Whether the name was found in a module opened by `import` rather than in `ctx`'s scopes.
pub(super) fn found_in_opened_module(checker: &Checker, found: ScopeId, ctx: &Ctx) -> bool {
    let mut current = Some(ctx.scope);
    while let Some(id) = current {
        if id == found {
            return false;
        }
        current = checker.out.scope(id).parent.map(|(parent, _)| parent);
    }
    true
}
