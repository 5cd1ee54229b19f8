//! States: variables with their own differential equations (an integral of an error, a motor's
//! current, an estimate), made by `state(x0)` and given their derivative by `rate s = f;`.
//! Their values are symbols of the expressions (`SExpr::State`) that efforts, outputs and other
//! states' rates read; the run integrates them with the motion (`simulate::system::states`).
//! A sampled state, made by `sample(period, x0)` and given its next value by `update u = f;`,
//! is one of them whose value is held between its sampling instants (`simulate::sampling`).

use std::sync::Arc;

use super::elaborator::{internal, Elaborator};
use super::eval::Locals;
use super::mechanism::StateVariable;
use super::operations::as_scalar;
use super::value::{SExpr, Scalar, StateId, Value};
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
        self.push_state(as_scalar(initial, span)?, None, span)
    }

    /// `sample(period, x0)`: a new sampled state, `x0` before its first instant, one `period`
    /// after the start.
    pub(super) fn new_sampled_state(&mut self, values: Vec<Value>, span: Span) -> Result<Value> {
        let [period, initial]: [Value; 2] = values
            .try_into()
            .map_err(|_| internal("`sample` without its period and initial value"))?;
        let period = as_scalar(period, span)?;
        self.push_state(as_scalar(initial, span)?, Some(period), span)
    }

    fn push_state(&mut self, initial: Scalar, period: Option<Scalar>, span: Span) -> Result<Value> {
        let id = StateId(self.mechanism.states.len() as u32);
        self.mechanism.states.push(StateVariable {
            name: None,
            initial,
            rate: None,
            period,
            span,
            input: false,
        });
        Ok(Value::Scalar(Arc::new(SExpr::State(id))))
    }

    /// `rate s = f;`, the derivative of state `s`, and `update u = f;`, the next value of
    /// sampled state `u` (E0486 when `s` is not a state, E0495 when `u` is not a sampled one,
    /// E0496 for the rate of a sampled state, E0487 when it has one already).
    pub(super) fn rate_decl(&mut self, decl: &DriveDecl, locals: &mut Locals) -> Result<()> {
        let update = decl.word.name.as_str() == "update";
        let not_a_state = |span| match update {
            true => not_a_sampled_state(span),
            false => not_a_state(span),
        };
        let target = self.expr(&decl.target, locals)?;
        let Value::Scalar(target) = target else {
            return Err(not_a_state(decl.target.span));
        };
        let SExpr::State(id) = *target else {
            return Err(not_a_state(decl.target.span));
        };
        let law = self
            .expr(&decl.value, locals)
            .and_then(|v| as_scalar(v, decl.value.span))?;
        let state = &mut self.mechanism.states[id.0 as usize];
        let name = state.label(id.0 as usize);
        match (update, state.period.is_some()) {
            (true, false) => return Err(not_a_sampled_state(decl.target.span)),
            (false, true) => return Err(rate_of_sampled_state(&name, decl, state.span)),
            _ => {}
        }
        if let Some((_, first)) = &state.rate {
            let (laws, law, help) = match update {
                true => (
                    "updates",
                    "update",
                    "a sampled state has one difference equation: keep one `update` declaration",
                ),
                false => (
                    "rates",
                    "rate",
                    "a state has one differential equation: keep one `rate` declaration",
                ),
            };
            return Err(Diagnostic::error(
                "E0487",
                format!("the state `{name}` is given two {laws}"),
            )
            .primary(decl.target.span, format!("second {law}"))
            .secondary(*first, format!("first {law}"))
            .help(help));
        }
        state.rate = Some((law, decl.value.span));
        Ok(())
    }
}

fn not_a_sampled_state(span: Span) -> Diagnostic {
    Diagnostic::error("E0495", "`update` gives the next value of a sampled state")
        .primary(span, "not a sampled state")
        .help("make the sampled state first, `let u = sample(0.01, 0);` (its period, its value before the first instant), then write `update u = ...;`")
}

fn rate_of_sampled_state(name: &str, decl: &DriveDecl, made: Span) -> Diagnostic {
    Diagnostic::error(
        "E0496",
        format!("the sampled state `{name}` has no rate: its value is held between its instants"),
    )
    .primary(decl.word.span, "a derivative")
    .secondary(made, "sampled here")
    .help(format!(
        "give its value after each sampling instant, `update {name} = ...;`, or make a state that moves continuously with `state(x0)`"
    ))
}

fn not_a_state(span: Span) -> Diagnostic {
    Diagnostic::error("E0486", "`rate` gives the derivative of a state")
        .primary(span, "not a state")
        .help("make the state first, `let integral = state(0);`, then write `rate integral = ...;`")
}
