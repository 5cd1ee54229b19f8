//! The laws that read the model at the current state: `mass_matrix(a.q, b.q)`, `bias(a.q)`,
//! `gravity_effort(a.q)` become calls whose arguments are join coordinates, resolved to the
//! model's quantities when the laws are compiled (`dynamics::actuators`); `inverse_dynamics(c,
//! c1, a1, ..., cm, am)` is written with them, Σₖ M(c, cₖ) aₖ + bias(c), so that the model is
//! computed once per evaluation however many laws read it.

use std::sync::Arc;

use super::elaborator::internal;
use super::operations::as_scalar;
use super::value::{arith, SExpr, Scalar, Value};
use crate::diag::Diagnostic;
use crate::source::Span;

type Result<T> = std::result::Result<T, Diagnostic>;

/// The built-in functions that read the model.
pub const MODEL_FUNCTIONS: [&str; 4] =
    ["mass_matrix", "bias", "gravity_effort", "inverse_dynamics"];

/// Whether a call of `name` reads the model.
pub fn is_model_function(name: &str) -> bool {
    MODEL_FUNCTIONS.contains(&name)
}

/// A call of one of [`MODEL_FUNCTIONS`] with its arguments' values and spans.
pub(super) fn model_call(
    name: &str,
    values: Vec<Value>,
    spans: &[Span],
    span: Span,
) -> Result<Value> {
    let scalars = values
        .into_iter()
        .map(|v| as_scalar(v, span))
        .collect::<Result<Vec<Scalar>>>()?;
    let function: &'static str = match name {
        "mass_matrix" => "mass_matrix",
        "bias" => "bias",
        "gravity_effort" => "gravity_effort",
        "inverse_dynamics" => return inverse_dynamics(&scalars, spans),
        _ => return Err(internal(format!("`{name}` does not read the model"))),
    };
    for (scalar, &at) in scalars.iter().zip(spans) {
        coordinate(scalar, at, function)?;
    }
    Ok(Value::Scalar(Arc::new(SExpr::call(function, scalars))))
}

/// Σₖ mass_matrix(c, cₖ) aₖ + bias(c), the coordinates cₖ each named once.
fn inverse_dynamics(scalars: &[Scalar], spans: &[Span]) -> Result<Value> {
    let along = &scalars[0];
    coordinate(along, spans[0], "inverse_dynamics")?;
    let mut effort = Arc::new(SExpr::call("bias", vec![along.clone()]));
    let mut named: Vec<&Scalar> = Vec::new();
    for pair in (1..scalars.len()).step_by(2) {
        let (other, acceleration) = (&scalars[pair], &scalars[pair + 1]);
        coordinate(other, spans[pair], "inverse_dynamics")?;
        if named.contains(&other) {
            return Err(Diagnostic::error(
                "E0653",
                "`inverse_dynamics` names this coordinate's acceleration twice",
            )
            .primary(spans[pair], "named again here")
            .help("give each actuated coordinate's acceleration once"));
        }
        named.push(other);
        let mass = Arc::new(SExpr::call(
            "mass_matrix",
            vec![along.clone(), other.clone()],
        ));
        effort = arith('+', &effort, &arith('*', &mass, acceleration));
    }
    Ok(Value::Scalar(effort))
}

/// Refuses an argument that is not a join's coordinate (a rate, a number, an expression).
fn coordinate(scalar: &Scalar, span: Span, function: &str) -> Result<()> {
    match **scalar {
        SExpr::JoinCoordinate { order: 0, .. } => Ok(()),
        _ => Err(Diagnostic::error(
            "E0653",
            format!("`{function}` reads the model along a coordinate of a named join"),
        )
        .primary(span, "not a join's coordinate")
        .help("write the coordinate itself, `shoulder.q`: the model's quantities are along coordinates, at the current state")),
    }
}

/// Whether `s` reads the model (a call of `mass_matrix`, `bias` or `gravity_effort`).
pub fn reads_model(s: &SExpr) -> bool {
    s.any(&|e| matches!(e, SExpr::Call(call) if is_model_function(call.function)))
}
