//! Sampled states in the dynamic model (`let u = sample(period, x0); update u = f;`): a
//! discrete-time controller's states, held between their sampling instants (a zero-order hold)
//! and given a new value at each instant by their update, x\[k+1\] = f(x\[k\], measurements at
//! t_k). The model keeps each one's period; the run lands on the instants and applies the
//! updates (`simulate::sampling`). What cannot take them says so here, at the `sample` call.

use super::model::Model;
use super::states::Missing;
use crate::diag::Diagnostic;
use crate::elab::value::Scalar;
use crate::kinematics::eval::{eval, UnknownValues};
use crate::source::Span;

/// The sampling of one sampled state.
#[derive(Clone, Copy, Debug)]
pub struct Sampling {
    /// Seconds between two instants; the first is one period after the start.
    pub period: f64,
    /// The call `sample(period, x0)` that made the state.
    pub span: Span,
}

/// The period of sampled state `name`, a positive number (E0497; `missing` when it is not a
/// number).
pub(super) fn period(
    name: &str,
    period: &Scalar,
    unknowns: &UnknownValues,
    missing: Missing<'_>,
    span: Span,
) -> Result<f64, Diagnostic> {
    let what = format!("the period of sampled state `{name}`");
    let value = eval(period, unknowns).map_err(|e| missing(e, &what, span))?;
    if value > 0.0 && value.is_finite() {
        return Ok(value);
    }
    Err(Diagnostic::error(
        "E0497",
        format!("the period of sampled state `{name}` is {value}: it must be a positive number of seconds"),
    )
    .primary(span, "sampled here")
    .help("`sample(0.01, 0)` takes its update every 10 ms and holds 0 until the first instant"))
}

/// E0498, at the first sampled state of `model`, when `what` (a command, an integrator) does
/// not take sampled states; `help` says what to do instead.
pub fn refusal(model: &Model, what: &str, help: &str) -> Option<Diagnostic> {
    let (state, sampling) =
        (model.states.iter()).find_map(|state| state.sampling.map(|sampling| (state, sampling)))?;
    Some(
        Diagnostic::error(
            "E0498",
            format!(
                "{what} does not take sampled states (`sample`), and `{}` is one",
                state.name
            ),
        )
        .primary(sampling.span, "sampled here")
        .help(help.to_string()),
    )
}
