//! `lsdc sensitivity`: how the quantities of a run (the declared coordinates, their rates, the
//! program's states and outputs) depend on parameters (initial values, values of the program),
//! along the run: d(y)(t)/d(p) by the forward sensitivity equations integrated with the run
//! (`augmented`), the parameters named as `lsdc sweep` names what it varies (`parameters`).
//!
//! What is handled: trees whose joints' coordinates move with their rates, with the program's
//! continuous states, geared rotors and any efforts. What is refused, with the reason at the
//! part of the program (E0860): closed loops and couplings (the run projects their state onto
//! the constraints after each step, which the sensitivities would need projected too: the
//! derivative of the projection, in the loops' independent coordinates), spherical and free
//! joints (quaternions: the sensitivities would live in the group's tangent space), stops
//! and friction (their events jump the state, and the sensitivities jump with the event's
//! time: the saltation matrix), contacts, sampled states (E0498). Motions imposed in time are
//! refused by the command as by `lsdc linearize` (E0491).

mod augmented;
pub mod parameters;
mod refusal;

use serde::Serialize;

use self::augmented::{central_step, has_exact_jacobian, Augmented, Preparations, Row, Variant};
pub use self::parameters::Parameter;
use crate::diag::Diagnostic;
use crate::dynamics::sampled;
use crate::elab::mechanism::Mechanism;
use crate::integrate::{integrate, Method, Settings as IntegratorSettings};
use crate::kinematics::unknowns::Override;
use crate::prepare::settings::{Integrator, SettingsChanges};
use crate::prepare::{prepare, Prepared, Settings};
use crate::simulate::clock::thread_cpu_seconds;
use crate::simulate::run::output_names_of;
use crate::simulate::simulator::output_times;
use crate::studies::sweep::runs::Target;

/// How the derivatives are obtained, for people (`method` in the JSON).
pub const METHOD: &str = "forward sensitivity equations integrated with the run, their error \
controlled with the state's; ∂f/∂x S from the analytical derivatives of ABA where the \
rigid-body dynamics under gravity are the whole right-hand side, else by a central difference \
of f along S; ∂f/∂p by a central difference between the mechanism prepared at p ± h; the \
outputs' derivatives by central differences; steps h = ε^(1/3) max(1, |·|)";

/// How ∂f/∂x S is computed (`state_derivatives` in the report).
pub const EXACT: &str = "analytical (ABA derivatives)";
pub const DIFFERENCED: &str = "central differences along S";

/// The name of the column of the derivative of `quantity` with respect to `parameter`.
pub fn column_name(quantity: &str, parameter: &str) -> String {
    format!("d({quantity})/d({parameter})")
}

/// A parameter as the result reports it.
#[derive(Clone, Debug, Serialize)]
pub struct ParameterValue {
    pub name: String,
    /// `initial value` or `value of the program`.
    pub kind: &'static str,
    pub value: f64,
}

/// A sample: the quantities' values, then their derivatives (for each quantity, with respect
/// to each parameter in turn: the order of `Sensitivities::columns`).
#[derive(Clone, Debug, Serialize)]
pub struct SensitivitySample {
    pub time: f64,
    pub values: Vec<f64>,
    pub derivatives: Vec<f64>,
}

/// What the integration cost and how it ended.
#[derive(Clone, Debug, Serialize)]
pub struct SensitivityReport {
    pub integrator: String,
    /// The state's dimension, and the augmented system's (state and sensitivities).
    pub state_dimension: usize,
    pub augmented_dimension: usize,
    /// How ∂f/∂x S was computed: [`EXACT`] or [`DIFFERENCED`].
    pub state_derivatives: &'static str,
    pub steps: usize,
    pub rejected_steps: usize,
    pub function_evaluations: usize,
    pub cpu_seconds: Option<f64>,
    /// When and why the run stopped before its end: the samples before are kept.
    pub failure: Option<SensitivityFailure>,
}

#[derive(Clone, Debug, Serialize)]
pub struct SensitivityFailure {
    pub time: f64,
    pub message: String,
}

/// The sensitivities of a run.
#[derive(Clone, Debug, Serialize)]
pub struct Sensitivities {
    pub parameters: Vec<ParameterValue>,
    /// The quantities, as `lsdc simulate`'s CSV names them.
    pub quantities: Vec<String>,
    /// `d(QUANTITY)/d(PARAMETER)`, for each quantity, each parameter in turn.
    pub columns: Vec<String>,
    pub samples: Vec<SensitivitySample>,
    pub method: &'static str,
    pub report: SensitivityReport,
    /// What preparing the mechanism found worth saying (as for `lsdc simulate`).
    #[serde(skip)]
    pub warnings: Vec<Diagnostic>,
}

impl Sensitivities {
    /// The derivatives at the last sample, by column name.
    pub fn final_values(&self) -> Vec<(&str, f64)> {
        let Some(last) = self.samples.last() else {
            return Vec::new();
        };
        (self.columns.iter().map(String::as_str))
            .zip(last.derivatives.iter().copied())
            .collect()
    }
}

/// Why the sensitivities cannot be computed.
#[derive(Debug)]
pub enum SensitivityError {
    /// Errors in the program or its parameters (E0861, E0862), or a part of it the study does
    /// not handle (E0860), located.
    Program(Vec<Diagnostic>),
    /// The settings cannot be used (an integrator that does not apply).
    Settings(String),
}

impl From<Vec<Diagnostic>> for SensitivityError {
    fn from(diagnostics: Vec<Diagnostic>) -> Self {
        SensitivityError::Program(diagnostics)
    }
}

/// The sensitivities of the run of `mechanism` (values `overrides`, settings `changes`) with
/// respect to the parameters named `names`.
pub fn sensitivities(
    mechanism: &Mechanism,
    overrides: &[Override],
    changes: &SettingsChanges,
    names: &[String],
) -> Result<Sensitivities, SensitivityError> {
    sensitivities_at(mechanism, overrides, changes, names, None)
}

/// [`sensitivities`] at the output times `times` (increasing, from 0 on) when given, instead
/// of the settings' grid: the run then ends at the last of them (`lsdc identify` compares the
/// run with measurements at the measurements' times).
pub fn sensitivities_at(
    mechanism: &Mechanism,
    overrides: &[Override],
    changes: &SettingsChanges,
    names: &[String],
    times: Option<&[f64]>,
) -> Result<Sensitivities, SensitivityError> {
    let mut parameters = parameters::resolve(mechanism, overrides, names)?;
    let prepare_with = |overrides: &[Override]| -> Result<Prepared, SensitivityError> {
        let mut prepared = prepare(mechanism, overrides, &Settings::default())?;
        let changed = prepared.settings.apply(changes);
        changed.map_err(|e| SensitivityError::Settings(e.to_string()))?;
        Ok(prepared)
    };
    let nominal = prepare_with(overrides)?;
    let sampled = "a sampled state is held between its instants and jumps on them: the sensitivities would jump too; write its law as a continuous one";
    let refused = (refusal::refusal(mechanism, &nominal))
        .or_else(|| sampled::refusal(&nominal.model, "`lsdc sensitivity`", sampled));
    if let Some(refusal) = refused {
        return Err(SensitivityError::Program(vec![refusal]));
    }
    let method = method(&nominal.settings)?;
    // The mechanism prepared at each value of the program ± h.
    let mut shifted = Vec::new();
    for parameter in &parameters {
        if parameter.target != Target::Value {
            continue;
        }
        let h = central_step(parameter.value);
        let at = |value: f64| {
            let mut moved = overrides.to_vec();
            moved.push(Override {
                name: parameter.name.clone(),
                value,
            });
            prepare_with(&moved)
        };
        let (plus, minus) = (parameter.value + h, parameter.value - h);
        shifted.push(Preparations {
            plus: at(plus)?,
            minus: at(minus)?,
            width: plus - minus,
        });
    }
    let start = starts(&nominal, &mut parameters, &shifted)?;
    let mut system = Augmented::new(&nominal, &parameters, &shifted);
    let settings = &nominal.settings;
    let integrator_settings = IntegratorSettings {
        rtol: settings.rtol,
        atol: settings.atol,
        initial_step: settings.step,
        max_step: settings.max_step,
        max_steps: settings.max_steps,
        ..IntegratorSettings::default()
    };
    let (outputs, duration) = match times {
        Some(times) => (times.to_vec(), times.last().copied().unwrap_or(0.0)),
        None => (
            output_times(settings.duration, settings.output),
            settings.duration,
        ),
    };
    let cpu_started = thread_cpu_seconds();
    let integrated = integrate(
        &method,
        &mut system,
        0.0,
        &start,
        duration,
        &outputs,
        &integrator_settings,
        &mut |_, _| Ok(()),
    );
    let cpu_seconds = thread_cpu_seconds()
        .zip(cpu_started)
        .map(|(now, then)| now - then);
    let (stats, failure) = match integrated {
        Ok((_, stats)) => (stats, None),
        Err(error) => {
            let failure = SensitivityFailure {
                time: error.time,
                message: error.failure.to_string(),
            };
            (*error.stats, Some(failure))
        }
    };
    let quantities = quantity_names(&nominal);
    let columns = (quantities.iter())
        .flat_map(|q| parameters.iter().map(move |p| column_name(q, &p.name)))
        .collect();
    let n = system.nominal.dimension();
    Ok(Sensitivities {
        parameters: parameters.iter().map(reported).collect(),
        quantities,
        columns,
        samples: system.rows.drain(..).map(sample).collect(),
        method: METHOD,
        warnings: nominal.warnings.clone(),
        report: SensitivityReport {
            integrator: settings.integrator.name().to_string(),
            state_dimension: n,
            augmented_dimension: n * (1 + parameters.len()),
            state_derivatives: match has_exact_jacobian(&nominal) {
                true => EXACT,
                false => DIFFERENCED,
            },
            steps: stats.steps,
            rejected_steps: stats.rejected,
            function_evaluations: stats.rhs_evaluations,
            cpu_seconds,
            failure,
        },
    })
}

fn reported(parameter: &Parameter) -> ParameterValue {
    ParameterValue {
        name: parameter.name.clone(),
        kind: match parameter.target {
            Target::Initial { .. } => "initial value",
            Target::Value => "value of the program",
        },
        value: parameter.value,
    }
}

fn sample(row: Row) -> SensitivitySample {
    SensitivitySample {
        time: row.time,
        values: row.values,
        derivatives: row.derivatives,
    }
}

/// The quantities of a sample: the declared coordinates, their rates (`name'`), the program's
/// states and outputs.
fn quantity_names(prepared: &Prepared) -> Vec<String> {
    let coordinates = prepared.coordinate_names.iter().cloned();
    let rates = prepared.coordinate_names.iter().map(|n| format!("{n}'"));
    coordinates
        .chain(rates)
        .chain(output_names_of(prepared))
        .collect()
}

/// The integration method of the run's settings; the variational integrator's steps are its
/// own, not an ODE method's that the sensitivities could ride along with.
fn method(settings: &Settings) -> Result<Method, SensitivityError> {
    Ok(match settings.integrator {
        Integrator::Rk4 => Method::Rk4 {
            step: settings.step.unwrap_or(settings.output.min(1e-3)),
        },
        Integrator::DormandPrince => Method::DormandPrince,
        Integrator::Dop853 => Method::Dop853,
        Integrator::Implicit => Method::Automatic,
        Integrator::Symplectic => {
            return Err(SensitivityError::Settings(
                "the symplectic integrator's steps are its own, not an ODE method's that the sensitivities could ride along with: choose `--integrator dopri5`, `dop853`, `rk4` or `implicit`".to_string(),
            ))
        }
    })
}

/// The augmented start (x₀, S₁(0), …): S_j(0) = ∂x₀/∂p_j, a unit for an initial value (by a
/// central difference of the start, exact for these linear maps), a central difference between
/// the shifted models' starts for a value of the program. Fills in the initial values'
/// values.
fn starts(
    nominal: &Prepared,
    parameters: &mut [Parameter],
    shifted: &[Preparations],
) -> Result<Vec<f64>, SensitivityError> {
    let variant = Variant::new(nominal);
    let start_of = |variant: &Variant, coordinates: &[f64], rates: &[f64]| {
        (variant.start(coordinates, rates)).map_err(|e| evaluation_error(&e.to_string()))
    };
    let mut start = start_of(&variant, &nominal.coordinates, &nominal.rates)?;
    let mut models = shifted.iter();
    for parameter in parameters.iter_mut() {
        let column: Vec<f64> = match parameter.target {
            Target::Initial {
                join,
                coordinate,
                order,
            } => {
                let offset = nominal.model.declared_offset(join).map(|o| o + coordinate);
                let Some(offset) = offset else {
                    return Err(SensitivityError::Settings(format!(
                        "`{}` is a coordinate of a join the scene leaves out of the model: nothing depends on it",
                        parameter.name
                    )));
                };
                let start_at = |value: f64| {
                    let (mut coordinates, mut rates) =
                        (nominal.coordinates.clone(), nominal.rates.clone());
                    match order {
                        0 => coordinates[offset] = value,
                        _ => rates[offset] = value,
                    }
                    start_of(&variant, &coordinates, &rates)
                };
                parameter.value = match order {
                    0 => nominal.coordinates[offset],
                    _ => nominal.rates[offset],
                };
                let h = central_step(parameter.value);
                let (plus, minus) = (parameter.value + h, parameter.value - h);
                difference(&start_at(plus)?, &start_at(minus)?, plus - minus)
            }
            Target::Value => {
                let models = models.next().expect("a model per value");
                let (plus, minus) = (&models.plus, &models.minus);
                let plus = start_of(&Variant::new(plus), &plus.coordinates, &plus.rates)?;
                let minus = start_of(&Variant::new(minus), &minus.coordinates, &minus.rates)?;
                difference(&plus, &minus, models.width)
            }
        };
        start.extend(column);
    }
    Ok(start)
}

/// (plus − minus) / width, component by component.
fn difference(plus: &[f64], minus: &[f64], width: f64) -> Vec<f64> {
    (plus.iter().zip(minus))
        .map(|(a, b)| (a - b) / width)
        .collect()
}

fn evaluation_error(message: &str) -> SensitivityError {
    SensitivityError::Settings(format!("the initial state cannot be evaluated: {message}"))
}
