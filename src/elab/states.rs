//! States: variables with their own differential equations (an integral of an error, a motor's
//! current, an estimate), made by `state(x0)` and given their derivative by `rate s = f;`.
//! Their values are symbols of the expressions (`SExpr::State`) that efforts, outputs and other
//! states' rates read; the run integrates them with the motion (`simulate::system::states`).

use std::sync::Arc;

use super::elaborator::{internal, Elaborator};
use super::eval::Locals;
use super::mechanism::StateVariable;
use super::operations::as_scalar;
use super::value::{SExpr, StateId, Value};
use crate::diag::Diagnostic;
use crate::source::Span;
use crate::syntax::ast::DriveDecl;

type Result<T> = std::result::Result<T, Diagnostic>;

impl Elaborator<'_, '_> {
    /// `state(x0)`: a new state starting at `x0` (each call makes one, as `?s` makes an
    /// unknown; `let` names it).
    pub(super) fn new_state(&mut self, values: Vec<Value>, span: Span) -> Result<Value> {
        let initial = values
            .into_iter()
            .next()
            .ok_or_else(|| internal("`state` without its initial value"))?;
        let initial = as_scalar(initial, span)?;
        let id = StateId(self.mechanism.states.len() as u32);
        self.mechanism.states.push(StateVariable {
            name: None,
            initial,
            rate: None,
            span,
        });
        Ok(Value::Scalar(Arc::new(SExpr::State(id))))
    }

    /// `rate s = f;`: the derivative of state `s` (E0486 when `s` is not a state, E0487 when
    /// it has one already).
    pub(super) fn rate_decl(&mut self, decl: &DriveDecl, locals: &mut Locals) -> Result<()> {
        let target = self.expr(&decl.target, locals)?;
        let Value::Scalar(target) = target else {
            return Err(not_a_state(decl.target.span));
        };
        let SExpr::State(id) = *target else {
            return Err(not_a_state(decl.target.span));
        };
        let rate = self
            .expr(&decl.value, locals)
            .and_then(|v| as_scalar(v, decl.value.span))?;
        let state = &mut self.mechanism.states[id.0 as usize];
        if let Some((_, first)) = &state.rate {
            let name = state.label(id.0 as usize);
            return Err(Diagnostic::error(
                "E0487",
                format!("the state `{name}` is given two rates"),
            )
            .primary(decl.target.span, "second rate")
            .secondary(*first, "first rate")
            .help("a state has one differential equation: keep one `rate` declaration"));
        }
        state.rate = Some((rate, decl.value.span));
        Ok(())
    }
}

fn not_a_state(span: Span) -> Diagnostic {
    Diagnostic::error("E0486", "`rate` gives the derivative of a state")
        .primary(span, "not a state")
        .help("make the state first, `let integral = state(0);`, then write `rate integral = ...;`")
}
