//! Sampled states in the dynamic model (`let u = sample(period, x0); update u = f;`): a
//! discrete-time controller's states, held between their sampling instants (a zero-order hold)
//! and given a new value at each instant by their update, x\[k+1\] = f(x\[k\], measurements at
//! t_k). The model keeps each one's period with the states (`states::Sampling`); the run
//! lands on the instants and applies the updates (`simulate::sampling`). What cannot take them
//! says so here, at the `sample` call.

use super::model::Model;
use crate::diag::Diagnostic;

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
