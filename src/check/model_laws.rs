//! Typing of the laws that read the model (`mass_matrix(a.q, b.q)`, `bias(a.q)`,
//! `gravity_effort(a.q)`, `inverse_dynamics(a.q, a.q, acc_a, b.q, acc_b)`) and of the
//! `actuate crank.q = law;` declaration whose laws may read them. That their coordinates are
//! joins' coordinates is known once evaluated (`elab::model_laws`), that they are the actuated
//! ones once the mechanism is built (`dynamics::actuators`).

use super::calls::arity_error;
use super::checker::{Checker, Ctx};
use super::types::Ty;
use crate::diag::Diagnostic;
use crate::source::Span;
use crate::syntax::ast::{Arg, DriveDecl, ExprKind, Ident};

impl<'w> Checker<'w> {
    /// `inverse_dynamics(c, c1, a1, ..., cm, am)`: a coordinate, then pairs of a coordinate and
    /// its acceleration, all scalars; the effort is a scalar.
    pub(super) fn inverse_dynamics_call(
        &mut self,
        ident: &Ident,
        args: &'w [Arg],
        arg_types: &[Ty],
        span: Span,
    ) -> Ty {
        if args.len() < 3 || args.len().is_multiple_of(2) {
            let diagnostic = match args.len() {
                0 => arity_error(&ident.name, 3, 0, span, None),
                _ => Diagnostic::error(
                    "E0413",
                    format!("`inverse_dynamics` takes a coordinate, then pairs of an actuated coordinate and its acceleration; {} arguments given", args.len()),
                )
                .primary(span, "in this call")
                .help("`inverse_dynamics(shoulder.q, shoulder.q, a1, elbow.q, a2)` is the effort along `shoulder.q` that gives the actuated coordinates the accelerations a1 and a2"),
            };
            self.report(diagnostic);
            return Ty::Error;
        }
        let mut failed = false;
        for (arg, &ty) in args.iter().zip(arg_types) {
            failed |= !self.expect_value(
                &arg.value,
                ty,
                Ty::Scalar,
                "an argument of `inverse_dynamics`",
            );
        }
        match failed {
            true => Ty::Error,
            false => Ty::Scalar,
        }
    }

    /// `actuate crank.q = law`: the target a coordinate of a named join (E0481, as a drive's),
    /// the law a scalar.
    pub(super) fn actuate(&mut self, actuate: &'w DriveDecl, ctx: &mut Ctx) {
        let ty = self.expr(&actuate.target, ctx);
        let on_join = match &actuate.target.kind {
            ExprKind::Field(access) => self.expr_type_silently(&access.target, ctx) == Ty::Join,
            _ => false,
        };
        if !on_join && ty != Ty::Error {
            self.report(
                Diagnostic::error("E0481", "`actuate` gives the effort along a joint coordinate: `actuate <join>.<coordinate> = <law>`")
                    .primary(actuate.target.span, "not a coordinate of a named join")
                    .help("name the join with `join ... with <link> as shoulder;`, then write `actuate shoulder.q = ...`"),
            );
        }
        let value_ty = self.expr(&actuate.value, ctx);
        self.expect_value(
            &actuate.value,
            value_ty,
            Ty::Scalar,
            "the law of an actuator",
        );
    }
}
