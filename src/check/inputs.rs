//! Typing of `input`: the program's declarations of its inputs, which an importer (an FMI
//! unit's), a caller stepping the run (`Simulator::set_input`) or a study (`linearize`) sets,
//! each with its start value. `input swing.q = 0;` declares the generalised effort along a
//! joint coordinate; `input voltage = 0;` declares a value, a new scalar name that the
//! expressions after it read. That the start value is a number and that no coordinate is
//! declared twice is decided with the mechanism (`elab`).

use super::checker::{Checker, Ctx};
use super::types::{ScopeId, Ty};
use crate::diag::Diagnostic;
use crate::syntax::ast::{DriveDecl, ExprKind, Ident};

impl<'w> Checker<'w> {
    /// `input swing.q = start`: the target a coordinate of a named join (E0481, as a drive's),
    /// the start value a scalar; `input voltage = start`: a new name (see
    /// [`Checker::value_input`]).
    pub(super) fn input(&mut self, input: &'w DriveDecl, scope: ScopeId, ctx: &mut Ctx) {
        if let Some(name) = input.value_input_name() {
            return self.value_input(input, &name, scope, ctx);
        }
        let ty = self.expr(&input.target, ctx);
        let on_join = match &input.target.kind {
            ExprKind::Field(access) => self.expr_type_silently(&access.target, ctx) == Ty::Join,
            _ => false,
        };
        if !on_join && ty != Ty::Error {
            let found = match &input.target.kind {
                ExprKind::Prime(_) => "a rate: an input is an effort along a coordinate",
                _ => "not a coordinate of a named join",
            };
            self.report(
                Diagnostic::error("E0481", "`input` declares the effort along a joint coordinate (`input <join>.<coordinate> = <start value>`) or a value (`input <name> = <start value>`)")
                    .primary(input.target.span, found)
                    .help("name the join with `join ... with <link> as swing;`, then write `input swing.q = 0`; a value the program reads is `input voltage = 0`"),
            );
        }
        let value_ty = self.expr(&input.value, ctx);
        self.expect_value(&input.value, value_ty, Ty::Scalar, "an input's start value");
    }

    /// `input voltage = start`: declares `voltage`, a scalar that the declarations after it
    /// read (as they read a state), in the scope's name space. A name declared an input twice
    /// is E0423, a name the scope already declares otherwise (a `let`, a join) E0302. The start
    /// value is checked before the name is declared: it cannot read the input itself.
    fn value_input(&mut self, input: &'w DriveDecl, name: &Ident, scope: ScopeId, ctx: &mut Ctx) {
        let value_ty = self.expr(&input.value, ctx);
        self.expect_value(&input.value, value_ty, Ty::Scalar, "an input's start value");
        let Some(previous) = self.out.scope(scope).names.get(&name.name) else {
            self.value_inputs.insert(name.span);
            self.scope_mut(scope)
                .insert(name.name, Ty::Scalar, name.span);
            return;
        };
        let previous = previous.span;
        let diagnostic = match self.value_inputs.contains(&previous) {
            true => Diagnostic::error("E0423", format!("`{}` is declared an input twice", name.name))
                .primary(name.span, "second declaration")
                .secondary(previous, "first declaration")
                .help("a value is one input: keep one `input` declaration"),
            false => Diagnostic::error("E0302", format!("`{}` is already defined", name.name))
                .primary(name.span, "declared an input here")
                .secondary(previous, "first defined here")
                .help(format!("`input {0} = ...` declares a new name; give the input another name, or, to set the value `{0}` from outside, replace its `let` with the `input` declaration", name.name)),
        };
        self.report(diagnostic);
    }
}
