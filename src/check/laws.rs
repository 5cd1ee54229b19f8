//! Typing of the reference laws of time (`quintic(time, t0, q0, t1, q1)`, `spline(time, t0, q0,
//! t1, q1, t2, q2)`) and of `derivative(law)`: a law's positions are all scalars (a joint's
//! law) or all vectors (a point's law), and the law has their type.

use super::calls::arity_error;
use super::checker::Checker;
use super::types::{LawArguments, Ty};
use crate::diag::Diagnostic;
use crate::source::Span;
use crate::syntax::ast::{Arg, Ident};

impl<'w> Checker<'w> {
    /// The type of a call of a reference law: its positions' type.
    pub(super) fn law_call(
        &mut self,
        ident: &Ident,
        arguments: LawArguments,
        args: &'w [Arg],
        arg_types: &[Ty],
        span: Span,
    ) -> Ty {
        let name = &ident.name;
        let fits = match arguments {
            LawArguments::Between(extra) => args.len() == 5 + extra.len(),
            LawArguments::Through => args.len() >= 5 && args.len() % 2 == 1,
        };
        if !fits {
            let diagnostic = match arguments {
                LawArguments::Between(extra) => {
                    arity_error(name, 5 + extra.len(), args.len(), span, None)
                }
                LawArguments::Through => Diagnostic::error(
                    "E0413",
                    format!("`{name}` takes the time then pairs of a time and a position, two pairs at least; {} arguments given", args.len()),
                )
                .primary(span, "in this call")
                .help(format!("`{name}(time, t0, q0, t1, q1, t2, q2)` passes through q1 at t1")),
            };
            self.report(diagnostic);
            return Ty::Error;
        }
        let role = format!("an argument of `{name}`");
        // The positions' kind, from the first that is not the literal `0` (which fits both).
        let mut kind: Option<Ty> = None;
        let mut failed = false;
        for (k, (arg, &ty)) in args.iter().zip(arg_types).enumerate() {
            if !arguments.is_position(k) {
                failed |= !self.expect_value(&arg.value, ty, Ty::Scalar, &role);
                continue;
            }
            let this = match ty {
                Ty::Zero | Ty::Error => continue,
                _ if ty.fits(Ty::Scalar) => Ty::Scalar,
                _ if ty.fits(Ty::Vector) => Ty::Vector,
                _ => {
                    failed = true;
                    self.expect_value(
                        &arg.value,
                        ty,
                        Ty::Scalar,
                        &format!("a position of `{name}`"),
                    );
                    continue;
                }
            };
            match kind {
                None => kind = Some(this),
                Some(first) if first != this => {
                    failed = true;
                    self.report(
                        Diagnostic::error(
                            "E0401",
                            format!("the positions of `{name}` must be all scalars or all vectors, found {} after {}", this.with_article(), first.with_article()),
                        )
                        .primary(arg.value.span, format!("this is {}", this.with_article()))
                        .help("a joint's law goes between scalars, a point's law between vectors `[x, y, z]`"),
                    );
                }
                Some(_) => {}
            }
        }
        match (failed, kind) {
            (true, _) => Ty::Error,
            (false, Some(Ty::Vector)) => Ty::Vector,
            (false, _) => Ty::Scalar,
        }
    }

    /// `derivative(law)`: a scalar's or a vector's derivative has its type.
    pub(super) fn derivative_call(
        &mut self,
        ident: &Ident,
        args: &'w [Arg],
        arg_types: &[Ty],
        span: Span,
    ) -> Ty {
        if args.len() != 1 {
            self.report(arity_error(&ident.name, 1, args.len(), span, None));
            return Ty::Error;
        }
        let ty = arg_types[0];
        if ty.fits(Ty::Vector) && ty != Ty::Zero {
            return Ty::Vector;
        }
        self.expect_value(
            &args[0].value,
            ty,
            Ty::Scalar,
            "the argument of `derivative`",
        );
        Ty::Scalar
    }
}
