//! The program's states in the dynamic model (`let s = state(x0); rate s = f;`): each one's
//! starting value, evaluated with the values of the unknowns (`given`, `--set`), and its rate,
//! lowered into the efforts' tape (`compiled`) beside the efforts that read it, so that one
//! evaluation of the tape gives the efforts and the states' rates at a state of the run. A rate
//! that reads the model (`mass_matrix`, `inverse_dynamics`, …: a backstepping law's voltage, an
//! estimator's update) is lowered into the actuators' tape instead, evaluated after the model.

use crate::diag::Diagnostic;
use crate::elab::mechanism::Mechanism;
use crate::elab::model_laws::reads_model;
use crate::elab::value::Scalar;
use crate::kinematics::eval::{eval, EvalError, UnknownValues};
use crate::source::Span;

/// One state of the model.
#[derive(Clone, Debug)]
pub struct StateModel {
    /// Its column among the outputs: the name it is bound to (`integral`).
    pub name: String,
    /// Its value at the start of a run.
    pub initial: f64,
    /// Its rate, as written, and where.
    pub rate: Scalar,
    pub rate_span: Span,
    /// The rate reads the model: it is a root of the actuators' tape, not the efforts'.
    pub reads_model: bool,
    /// The rate's root in the efforts' tape (set when the efforts are compiled), or in the
    /// actuators' tape when it reads the model (set when the actuators are compiled).
    pub rate_root: usize,
}

/// Why a value the model needs is not a number, in the model's words (E0806, E0807): what,
/// and where it was written.
pub type Missing<'a> = &'a dyn Fn(EvalError, &str, Span) -> Diagnostic;

/// The mechanism's states, in the order they were made: E0488 for a state without `rate`,
/// and `missing` for a starting value that is not a number.
pub fn build(
    mechanism: &Mechanism,
    unknowns: &UnknownValues,
    missing: Missing<'_>,
    errors: &mut Vec<Diagnostic>,
) -> Vec<StateModel> {
    let mut states = Vec::new();
    for (index, state) in mechanism.states.iter().enumerate() {
        let name = state.label(index);
        let Some((rate, rate_span)) = &state.rate else {
            errors.push(
                Diagnostic::error("E0488", format!("the state `{name}` has no rate"))
                    .primary(state.span, "made here")
                    .help(format!(
                        "give its derivative: `rate {name} = ...;` (a constant state has `rate {name} = 0;`)"
                    )),
            );
            continue;
        };
        let what = format!("the starting value of state `{name}`");
        match eval(&state.initial, unknowns) {
            Ok(initial) => states.push(StateModel {
                name,
                initial,
                rate: rate.clone(),
                rate_span: *rate_span,
                reads_model: reads_model(rate),
                rate_root: 0,
            }),
            Err(e) => errors.push(missing(e, &what, state.span)),
        }
    }
    states
}
