//! The program's states in the dynamic model (`let s = state(x0); rate s = f;`): each one's
//! starting value, evaluated with the values of the unknowns (`given`, `--set`), and its rate,
//! lowered into the efforts' tape (`compiled`) beside the efforts that read it, so that one
//! evaluation of the tape gives the efforts and the states' rates at a state of the run. A
//! sampled state (`let u = sample(period, x0); update u = f;`) is one of them with its period,
//! its update in place of the rate (`dynamics::sampled`). A rate
//! or update that reads the model (`mass_matrix`, `inverse_dynamics`, …: a backstepping law's
//! voltage, an estimator's update) is lowered into the actuators' tape instead, evaluated after
//! the model.

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
    /// Its rate, as written, and where; for a sampled state, its update (its value after each
    /// instant).
    pub rate: Scalar,
    pub rate_span: Span,
    /// The rate reads the model: it is a root of the actuators' tape, not the efforts'.
    pub reads_model: bool,
    /// The rate's root in the efforts' tape (set when the efforts are compiled), or in the
    /// actuators' tape when it reads the model (set when the actuators are compiled).
    pub rate_root: usize,
    /// For a sampled state (`sample(period, x0)`), its period and where it was made: its rate
    /// in the run is zero, its update applied at each instant (`simulate::sampling`).
    pub sampling: Option<Sampling>,
    /// A value input (`input voltage = 0;`): held at its value (its rate zero) until the
    /// run's caller sets it (`Simulator::set_input`).
    pub input: bool,
}

impl StateModel {
    /// Whether it moves continuously, by its rate (not a sampled state).
    pub fn continuous(&self) -> bool {
        self.sampling.is_none()
    }
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
            errors.push(without_law(&name, state.period.is_some(), state.span));
            continue;
        };
        let sampling = match &state.period {
            Some(period) => match self::period(&name, period, unknowns, missing, state.span) {
                Ok(period) => Some(Sampling {
                    period,
                    span: state.span,
                }),
                Err(error) => {
                    errors.push(error);
                    continue;
                }
            },
            None => None,
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
                sampling,
                input: state.input,
            }),
            Err(e) => errors.push(missing(e, &what, state.span)),
        }
    }
    states
}

/// E0488: a state without its law (`rate`, or `update` for a sampled one).
fn without_law(name: &str, sampled: bool, made: Span) -> Diagnostic {
    let (message, help) = match sampled {
        true => (
            format!("the sampled state `{name}` has no update"),
            format!("give its value after each sampling instant: `update {name} = ...;` (a held value has `update {name} = {name};`)"),
        ),
        false => (
            format!("the state `{name}` has no rate"),
            format!("give its derivative: `rate {name} = ...;` (a constant state has `rate {name} = 0;`)"),
        ),
    };
    Diagnostic::error("E0488", message)
        .primary(made, "made here")
        .help(help)
}

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
fn period(
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
