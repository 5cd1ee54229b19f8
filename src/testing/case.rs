//! Running one case: compile its program, make its checks, simulate it with its overrides and
//! settings (the `simulate` pipeline: `prepare`, `run::run`), compare the outputs with its
//! reference.

use std::time::Instant;

use serde::Serialize;

use super::compare::{compare, VariableError};
use super::manifest::{Case, Checks, ExpectedFailure};
use crate::diag::{Diagnostic, Severity};
use crate::driver::{compile_files_perturbed, Compilation};
use crate::load::LoadOptions;
use crate::output::csv::to_csv;
use crate::prepare::{prepare, Prepared, Settings};
use crate::simulate::run::{self, Simulation};
use crate::studies::analysis;
use crate::studies::precision::Reference;

/// How a case ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Status {
    Passed,
    /// The mechanism did not do what the case expects: a comparison or a check failed, or the
    /// program failed where no failure was expected.
    Failed,
    /// The case could not be run as written: a missing program or reference, a reference
    /// without a compared column, settings out of range.
    Error,
}

/// A case's result.
#[derive(Clone, Debug, Serialize)]
pub struct Outcome {
    pub name: String,
    pub manifest: String,
    pub line: usize,
    pub status: Status,
    pub seconds: f64,
    /// What failed, one sentence each (for an error: why the case could not run).
    pub failures: Vec<String>,
    /// The variables beyond their tolerance, worst first.
    pub failed_variables: Vec<VariableError>,
    /// The largest margin over the compared variables (how close a passing case came to its
    /// tolerances).
    pub worst: Option<VariableError>,
    pub compared_variables: usize,
}

/// Why a case stopped before its end: the program failed (to compile, to prepare, to run), or the
/// case itself is wrong.
pub(super) enum Stop {
    Program(String),
    Setup(String),
}

impl From<Stop> for String {
    fn from(stop: Stop) -> String {
        match stop {
            Stop::Program(message) | Stop::Setup(message) => message,
        }
    }
}

/// Runs a case.
pub fn run_case(case: &Case) -> Outcome {
    let start = Instant::now();
    let mut outcome = Outcome {
        name: case.name.clone(),
        manifest: case.manifest.display().to_string(),
        line: case.line,
        status: Status::Passed,
        seconds: 0.0,
        failures: Vec::new(),
        failed_variables: Vec::new(),
        worst: None,
        compared_variables: 0,
    };
    let result = examine(case, &mut outcome);
    settle(case, result, &mut outcome);
    outcome.seconds = start.elapsed().as_secs_f64();
    outcome
}

/// The status from what was found, and from what the case expects of failures.
fn settle(case: &Case, result: Result<(), Stop>, outcome: &mut Outcome) {
    match (result, &case.checks.expect_failure) {
        (Err(Stop::Setup(message)), _) => {
            outcome.status = Status::Error;
            outcome.failures.insert(0, message);
        }
        (Err(Stop::Program(message)), None) => outcome.failures.insert(0, message),
        (Err(Stop::Program(message)), Some(ExpectedFailure::Containing(text)))
            if !message.contains(text.as_str()) =>
        {
            outcome.failures.insert(
                0,
                format!("expected a failure saying `{text}`, got: {message}"),
            )
        }
        (Err(Stop::Program(_)), Some(_)) => {}
        (Ok(()), Some(_)) => outcome
            .failures
            .push("expected a failure, but the program compiled and ran to its end".into()),
        (Ok(()), None) => {}
    }
    if outcome.status == Status::Passed && !outcome.failures.is_empty() {
        outcome.status = Status::Failed;
    }
}

/// Compiles, checks, runs and compares, recording failures in `outcome`. A run that fails where
/// the case expects it is still compared with the reference, up to where it stopped.
fn examine(case: &Case, outcome: &mut Outcome) -> Result<(), Stop> {
    let compilation = compile(case)?;
    let mechanism = compilation
        .mechanism
        .as_ref()
        .expect("compiled without errors");
    outcome
        .failures
        .extend(structure_checks(mechanism, &case.checks));
    let prepared = prepare_case(case, &compilation)?;
    outcome
        .failures
        .extend(assembly_check(&prepared, &case.checks));
    let simulation = run::run(&prepared, &mut |_| {});
    let failure = run_failure(&simulation);
    if failure.is_none() {
        outcome
            .failures
            .extend(run_checks(&simulation, &case.checks));
    }
    if failure.is_none() || case.checks.expect_failure.is_some() {
        compare_with_reference(case, &simulation, outcome)?;
    }
    failure.map_or(Ok(()), |message| Err(Stop::Program(message)))
}

/// Why a run stopped before its end, in one sentence, if it did.
pub(super) fn run_failure(simulation: &Simulation) -> Option<String> {
    (simulation.report.failure.as_ref())
        .map(|f| format!("the run failed at t = {}: {}", f.time, f.message))
}

fn compare_with_reference(
    case: &Case,
    simulation: &Simulation,
    outcome: &mut Outcome,
) -> Result<(), Stop> {
    if let Some(path) = &case.reference {
        let reference = read_reference(path)?;
        let errors = compare(&as_table(simulation), &reference, case).map_err(Stop::Setup)?;
        let digits = std::fs::read_to_string(path)
            .ok()
            .and_then(|text| stated_digits(&text));
        record_comparison(errors, digits, outcome);
    }
    Ok(())
}

/// The failure of a variable, and the reason when its difference is no larger than the
/// rounding of a reference recorded to `digits` significant digits: the tolerance is finer
/// than the reference can tell.
fn record_comparison(mut errors: Vec<VariableError>, digits: Option<usize>, outcome: &mut Outcome) {
    errors.sort_by(|a, b| b.closeness(a));
    outcome.compared_variables = errors.len();
    outcome.worst = errors.first().cloned();
    outcome.failed_variables = errors.into_iter().filter(VariableError::fails).collect();
    if let Some(worst) = outcome.failed_variables.first() {
        outcome.failures.push(format!(
            "{} of {} variables beyond their tolerance; worst: {}",
            outcome.failed_variables.len(),
            outcome.compared_variables,
            describe(worst)
        ));
        let within_rounding = |e: &&VariableError| {
            digits.is_some_and(|d| e.difference <= rounding_of(e.reference, d))
        };
        if let (Some(d), Some(e)) = (
            digits,
            outcome.failed_variables.iter().find(within_rounding),
        ) {
            outcome.failures.push(format!(
                "`{}` differs by {:.3e}, no more than the reference's rounding to {d} significant \
                 digits: record it again with a larger `precision` (17 keeps every bit), or \
                 allow at least that much",
                e.variable, e.difference
            ));
        }
    }
}

/// The largest change that rounding `x` to `digits` significant digits makes: half a unit of
/// its last digit.
fn rounding_of(x: f64, digits: usize) -> f64 {
    if x == 0.0 || !x.is_finite() {
        return 0.0;
    }
    0.5 * 10f64.powi(x.abs().log10().floor() as i32 + 1 - digits as i32)
}

/// A variable's error in one line: where, by how much, against what.
pub fn describe(error: &VariableError) -> String {
    let measure = match error.measure {
        super::manifest::Measure::Max => "max over time",
        super::manifest::Measure::Final => "at the final time",
        super::manifest::Measure::L2 => "root mean square over time",
    };
    let value = |x: f64| match x.is_nan() {
        true => "no value".to_string(),
        false => crate::diag::number::shortest(x),
    };
    format!(
        "`{}` at t = {}: {} against {} in the reference, difference {:.3e} ({measure}), allowed {:.3e} (margin {:.3})",
        error.variable,
        value(error.time),
        value(error.actual),
        value(error.reference),
        error.difference,
        error.allowed,
        error.margin
    )
}

/// The program compiled; its diagnostics make a `Stop::Program` when it has errors.
pub(super) fn compile(case: &Case) -> Result<Compilation, Stop> {
    let options = LoadOptions {
        scene: case.scene.clone(),
        ..LoadOptions::default()
    };
    let program = std::slice::from_ref(&case.program);
    let compilation = compile_files_perturbed(program, &options, case.numbers)
        .map_err(|error| Stop::Setup(format!("{}: {error}", case.program.display())))?;
    if compilation.has_errors() || compilation.mechanism.is_none() {
        return Err(Stop::Program(summary(&compilation.diagnostics)));
    }
    Ok(compilation)
}

/// The errors among diagnostics, one line each.
fn summary(diagnostics: &[Diagnostic]) -> String {
    let errors: Vec<String> = (diagnostics.iter())
        .filter(|d| d.severity == Severity::Error)
        .map(|d| format!("{}: {}", d.code, d.message))
        .collect();
    errors.join("; ")
}

/// The prepared mechanism with the case's overrides and settings.
pub(super) fn prepare_case(case: &Case, compilation: &Compilation) -> Result<Prepared, Stop> {
    let mechanism = compilation
        .mechanism
        .as_ref()
        .expect("compiled without errors");
    let mut prepared = prepare(mechanism, &case.overrides, &Settings::default())
        .map_err(|d| Stop::Program(summary(&d)))?;
    (prepared.settings)
        .apply(&case.settings)
        .map_err(|e| Stop::Setup(format!("[case.simulate]: {e}")))?;
    Ok(prepared)
}

/// The case's program compiled and prepared, or why it could not be.
pub(super) fn compile_and_prepare(case: &Case) -> Result<Prepared, String> {
    let compilation = compile(case)?;
    Ok(prepare_case(case, &compilation)?)
}

/// The outputs of a run as a table, the form references are read in.
pub(super) fn as_table(simulation: &Simulation) -> Reference {
    Reference::from_csv(&to_csv(simulation), "the run").expect("lsdc writes its own CSV")
}

/// The first line of a recorded reference begins so, then states its digits.
pub(super) const HEADER_START: &str = "# lsdc test reference: ";

/// The significant digits a reference's first line states, if it states them (a reference
/// written by hand may not): `None` also when some values were written in full.
fn stated_digits(text: &str) -> Option<usize> {
    let line = text.lines().next()?.strip_prefix(HEADER_START)?;
    let digits = line.strip_suffix(" significant digits")?;
    digits.parse().ok()
}

pub(super) fn read_reference(path: &std::path::Path) -> Result<Reference, Stop> {
    let shown = path.display().to_string();
    let text = std::fs::read_to_string(path)
        .map_err(|e| Stop::Setup(format!("cannot read the reference {shown}: {e}")))?;
    Reference::from_csv(&text, &shown).map_err(|e| Stop::Setup(format!("{shown}: {e}")))
}

/// The mobility check, made on the program's own values at its assembled configuration.
fn structure_checks(mechanism: &crate::elab::Mechanism, checks: &Checks) -> Vec<String> {
    let Some(expected) = checks.mobility else {
        return Vec::new();
    };
    let found = analysis::tree(mechanism)
        .ok()
        .and_then(|tree| tree.mobility)
        .map(|m| m.mobility);
    match found {
        Some(mobility) if mobility == expected => Vec::new(),
        Some(mobility) => vec![format!("mobility {mobility}, expected {expected}")],
        None => vec![format!(
            "the mobility could not be computed (expected {expected})"
        )],
    }
}

/// Whether the mechanism assembled without moving a given value (W0801), as the case expects.
fn assembly_check(prepared: &Prepared, checks: &Checks) -> Vec<String> {
    let Some(expected) = checks.assembly else {
        return Vec::new();
    };
    let moved = prepared.warnings.iter().find(|w| w.code == "W0801");
    match (expected, moved) {
        (true, Some(warning)) => vec![format!("assembly moved given values: {}", warning.message)],
        (false, None) => vec!["expected assembly to move given values, none moved".into()],
        _ => Vec::new(),
    }
}

/// The energy drift and closure residual bounds.
fn run_checks(simulation: &Simulation, checks: &Checks) -> Vec<String> {
    let report = &simulation.report;
    let mut failures = Vec::new();
    if let Some(bound) = checks.energy_drift {
        match report.energy_drift.or(report.energy_balance) {
            Some(drift) if drift <= bound => {}
            Some(drift) => failures.push(format!("energy drift {drift:.3e} > bound {bound:.3e}")),
            None => {
                failures.push("no energy drift to check: the energies are not all known".into())
            }
        }
    }
    if let Some(bound) = checks.closure_residual {
        let residual = (report.constraints.as_ref()).map(|c| {
            c.position_residual_before_projection
                .max(c.position_residual)
        });
        match residual {
            Some(r) if r <= bound => {}
            Some(r) => failures.push(format!("closure residual {r:.3e} > bound {bound:.3e}")),
            None => failures.push("no closure residual to check: the mechanism has no loop".into()),
        }
    }
    failures
}
