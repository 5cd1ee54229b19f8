//! Typing of `input swing.q = 0;`: the program's declaration of an input, the generalised
//! effort along a joint coordinate that an importer (an FMI unit's) or a study (`linearize`)
//! sets, with its start value. That the start value is a number and that no coordinate is
//! declared twice is decided with the mechanism (`elab`).

use super::checker::{Checker, Ctx};
use super::types::Ty;
use crate::diag::Diagnostic;
use crate::syntax::ast::{DriveDecl, ExprKind};

impl<'w> Checker<'w> {
    /// `input swing.q = start`: the target a coordinate of a named join (E0481, as a drive's),
    /// the start value a scalar.
    pub(super) fn input(&mut self, input: &'w DriveDecl, ctx: &mut Ctx) {
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
                Diagnostic::error("E0481", "`input` declares the effort along a joint coordinate: `input <join>.<coordinate> = <start value>`")
                    .primary(input.target.span, found)
                    .help("name the join with `join ... with <link> as swing;`, then write `input swing.q = 0`"),
            );
        }
        let value_ty = self.expr(&input.value, ctx);
        self.expect_value(&input.value, value_ty, Ty::Scalar, "an input's start value");
    }
}
