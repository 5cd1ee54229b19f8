//! The fit of parameters that enter the dynamics nonlinearly (a length `let L = ?s;`, a
//! stiffness, a damping coefficient, an initial value) to measured quantities of a run (its
//! coordinates, rates, outputs), by minimising the output error of the whole run:
//!
//! ```text
//! min over p of  Σ_k Σ_c w_c² (y_c(t_k) − ŷ_c(t_k; p))²
//! ```
//!
//! with ŷ the run's quantities at the measurements' times. Levenberg–Marquardt (Levenberg, "A
//! method for the solution of certain non-linear problems in least squares", Quart. Appl.
//! Math. 2, 1944; Marquardt, "An algorithm for least-squares estimation of nonlinear
//! parameters", SIAM J. Appl. Math. 11, 1963) in Moré's scaled form ("The Levenberg–Marquardt
//! algorithm: implementation and theory", Numerical Analysis, LNM 630, 1978): each step solves
//! min |J δ − r|² + λ |D δ|² with D the largest column norms of J seen so far, by a singular
//! value decomposition of [J; √λ D]; λ follows the ratio ρ of the actual to the predicted
//! reduction (Nielsen's update, "Damping parameter in Marquardt's method", IMM-REP 1999-05).
//! J = ∂ŷ/∂p is the run's forward sensitivities (`studies::sensitivity`), integrated with the
//! run to its tolerance: no differences of whole runs.
//!
//! Each measured quantity has its own units and noise: a first fit weights them all alike, then
//! each column's σ_c from its residual weights a second fit from the first's solution (as the
//! linear fit does, Gautier & Poignet 2001), unless the residual is at the runs' accuracy
//! (noise-free data). The standard deviations are σ (J_wᵀ J_w)⁻¹ᐟ² with σ² = |r_w|² / (equations −
//! parameters) at the solution (Bard, Nonlinear Parameter Estimation, 1974, ch. 7: the
//! linearised covariance, errors independent).

use nalgebra::{DMatrix, DVector};
use serde::ser::SerializeMap;
use serde::{Serialize, Serializer};

use super::Residual;
use crate::diag::Diagnostic;
use crate::elab::mechanism::Mechanism;
use crate::kinematics::unknowns::Override;
use crate::linalg::svd;
use crate::prepare::settings::SettingsChanges;
use crate::simulate::clock::thread_cpu_seconds;
use crate::studies::sensitivity::parameters::{resolve, Parameter};
use crate::studies::sensitivity::{sensitivities_at, Sensitivities, SensitivityError};
use crate::studies::sweep::runs::{with_initial_values, Target};

/// How the estimates are found, for people (`method` in the JSON).
pub const METHOD: &str = "Levenberg–Marquardt (Moré's scaled form) on the output error of whole \
runs, the Jacobian from the forward sensitivity equations integrated with the run";

/// The most iterations (accepted or rejected steps) of one fit.
const MAX_ITERATIONS: usize = 100;

/// The fit has converged when a step changes the scaled parameters by at most this, relative
/// (Moré's xtol), or the sum of squares by at most this fraction of it.
const STEP_TOLERANCE: f64 = 1e-10;
const COST_TOLERANCE: f64 = 1e-14;

/// Singular values of the Jacobian (columns scaled to unit norm) at most this fraction of the
/// largest are taken as zero: the sensitivities carry the run's integration error, far above
/// round-off, so exact dependencies between parameters show there, not at 1e-15.
pub const RANK_TOLERANCE: f64 = 1e-6;

/// Columns of a right singular vector of a zero singular value at least this large name the
/// parameters that act only together.
const NULL_SHARE: f64 = 0.1;

/// One parameter's estimate.
#[derive(Clone, Debug, Serialize)]
pub struct NonlinearEstimate {
    #[serde(skip)]
    pub name: String,
    /// `initial value` or `value of the program`.
    pub kind: &'static str,
    pub value: f64,
    pub std: f64,
    /// The program's value, from which the fit starts.
    pub model: f64,
}

/// What the nonlinear fit finds.
#[derive(Clone, Debug, Serialize)]
pub struct NonlinearIdentification {
    #[serde(serialize_with = "by_name")]
    pub parameters: Vec<NonlinearEstimate>,
    /// The condition number of the Jacobian of the weighted residuals at the solution, its
    /// columns scaled to unit norm.
    pub condition: f64,
    pub residual: Residual,
    pub samples: usize,
    pub equations: usize,
    /// The measured quantities fitted, as the file's columns name them.
    pub fitted: Vec<String>,
    pub method: &'static str,
    /// The steps tried (accepted or not) and the sensitivity runs they took.
    pub iterations: usize,
    pub runs: usize,
    pub cpu_seconds: Option<f64>,
}

fn by_name<S: Serializer>(
    estimates: &[NonlinearEstimate],
    serializer: S,
) -> Result<S::Ok, S::Error> {
    let mut map = serializer.serialize_map(Some(estimates.len()))?;
    for e in estimates {
        map.serialize_entry(&e.name, e)?;
    }
    map.end()
}

/// Why the nonlinear fit fails.
#[derive(Debug)]
pub enum NonlinearError {
    /// The program or the parameters' names (`lsdc sensitivity`'s diagnostics).
    Program(Vec<Diagnostic>),
    /// The measurements' file (file, line and column in the message) or the settings.
    Usage(String),
    /// Parameters that have no effect on the measured quantities, and groups of parameters
    /// that act only together, at the start: names.
    Unidentifiable {
        without_effect: Vec<String>,
        together: Vec<String>,
    },
    TooFewSamples {
        equations: usize,
        parameters: usize,
    },
    /// The run at the start fails (its time and reason).
    RunFailed {
        time: f64,
        why: String,
    },
    NotConverged {
        iterations: usize,
    },
}

impl std::fmt::Display for NonlinearError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let quoted = |names: &[String]| super::quoted(names);
        match self {
            NonlinearError::Program(diagnostics) => {
                let messages: Vec<&str> = diagnostics.iter().map(|d| d.message.as_str()).collect();
                write!(f, "{}", messages.join("; "))
            }
            NonlinearError::Usage(why) => write!(f, "{why}"),
            NonlinearError::Unidentifiable { without_effect, together } => {
                write!(f, "the measured quantities do not determine the parameters: ")?;
                if !without_effect.is_empty() {
                    write!(f, "{} {} no effect on them", quoted(without_effect), match without_effect.len() { 1 => "has", _ => "have" })?;
                }
                if !together.is_empty() {
                    if !without_effect.is_empty() {
                        write!(f, ", and ")?;
                    }
                    write!(f, "{} act on them only together (their sensitivities are dependent: the Jacobian's condition number is above {:e})", quoted(together), 1.0 / RANK_TOLERANCE)?;
                }
                write!(f, "; fix some of them with `--set`, or measure other quantities")
            }
            NonlinearError::TooFewSamples { equations, parameters } => write!(
                f,
                "{equations} measurements for {parameters} parameters: at least {} are needed (one more than the parameters, for the residual's variance)",
                parameters + 1
            ),
            NonlinearError::RunFailed { time, why } => write!(f, "the run at the starting values fails at t = {time}: {why}"),
            NonlinearError::NotConverged { iterations } => write!(f, "the fit has not converged in {iterations} steps: start nearer the solution (`--set NAME=VALUE`)"),
        }
    }
}

impl std::error::Error for NonlinearError {}

impl From<SensitivityError> for NonlinearError {
    fn from(error: SensitivityError) -> Self {
        match error {
            SensitivityError::Program(diagnostics) => NonlinearError::Program(diagnostics),
            SensitivityError::Settings(why) => NonlinearError::Usage(why),
        }
    }
}

/// The measurements' file: its header and rows, each field's value (NaN where it is not a
/// number, refused only in the columns fitted) and where it starts.
pub struct Table {
    file: String,
    header_line: usize,
    columns: Vec<String>,
    /// Per row: its line (1-based), its fields' values and their first characters.
    rows: Vec<(usize, Vec<f64>, Vec<usize>)>,
}

/// The first character (1-based) of each field of `line`.
fn field_starts(line: &str) -> Vec<usize> {
    std::iter::once(1)
        .chain(
            line.match_indices(',')
                .map(|(i, _)| line[..i].chars().count() + 2),
        )
        .collect()
}

impl Table {
    /// Reads the CSV `text` (named `file` in the errors): a header line, then rows of as many
    /// fields; blank lines and lines starting with `#` are skipped.
    pub fn read(text: &str, file: &str) -> Result<Table, String> {
        let mut lines = (text.lines().enumerate())
            .filter(|(_, l)| !l.trim().is_empty() && !l.trim_start().starts_with('#'));
        let Some((header_index, header)) = lines.next() else {
            return Err(format!("{file}: no header line"));
        };
        let columns: Vec<String> = header.split(',').map(|c| c.trim().to_string()).collect();
        let mut rows = Vec::new();
        for (index, line) in lines {
            let fields: Vec<f64> = (line.split(','))
                .map(|f| f.trim().parse::<f64>().unwrap_or(f64::NAN))
                .collect();
            if fields.len() != columns.len() {
                return Err(format!(
                    "{file}:{}:1: {} fields for {} columns",
                    index + 1,
                    fields.len(),
                    columns.len()
                ));
            }
            rows.push((index + 1, fields, field_starts(line)));
        }
        Ok(Table {
            file: file.to_string(),
            header_line: header_index + 1,
            columns,
            rows,
        })
    }

    fn find(&self, name: &str) -> Option<usize> {
        self.columns.iter().position(|c| c == name)
    }

    /// Column `k` of every row, refused at the first field that is not a finite number.
    fn column(&self, k: usize) -> Result<Vec<f64>, String> {
        let mut values = Vec::with_capacity(self.rows.len());
        for (line, fields, starts) in &self.rows {
            if !fields[k].is_finite() {
                return Err(format!(
                    "{}:{line}:{}: not a finite number (column `{}`)",
                    self.file, starts[k], self.columns[k]
                ));
            }
            values.push(fields[k]);
        }
        Ok(values)
    }

    /// The times: a `time` column, increasing from 0 on.
    fn times(&self) -> Result<Vec<f64>, String> {
        let at_header = |message: &str| format!("{}:{}:1: {message}", self.file, self.header_line);
        let k = self
            .find("time")
            .ok_or_else(|| at_header("no `time` column"))?;
        let times = self.column(k)?;
        for (s, pair) in times.windows(2).enumerate() {
            if pair[1] <= pair[0] {
                let (line, _, starts) = &self.rows[s + 1];
                return Err(format!(
                    "{}:{line}:{}: the time {} does not follow {}: times must increase",
                    self.file, starts[k], pair[1], pair[0]
                ));
            }
        }
        if let Some(&first) = times.first().filter(|&&t| t < 0.0) {
            let (line, _, starts) = &self.rows[0];
            return Err(format!(
                "{}:{line}:{}: the time {first} is before the run's start, 0",
                self.file, starts[k]
            ));
        }
        Ok(times)
    }
}

/// The fit's problem: the program, its values, the runs' settings, the parameters and the
/// measurements.
pub struct Problem<'a> {
    pub mechanism: &'a Mechanism,
    pub overrides: &'a [Override],
    pub changes: &'a SettingsChanges,
    pub names: &'a [String],
}

/// The residuals and the Jacobian of the run at one point, weighted.
struct Point {
    p: Vec<f64>,
    /// Measured less predicted, per equation (sample-major, the fitted columns in turn).
    r: DVector<f64>,
    /// ∂(predicted)/∂p, per equation.
    j: DMatrix<f64>,
}

impl Point {
    fn weighted(&self, weights: &[f64]) -> (DVector<f64>, DMatrix<f64>) {
        let c = weights.len();
        let r = DVector::from_fn(self.r.len(), |k, _| self.r[k] * weights[k % c]);
        let j = DMatrix::from_fn(self.j.nrows(), self.j.ncols(), |k, i| {
            self.j[(k, i)] * weights[k % c]
        });
        (r, j)
    }
}

/// The runs the fit makes, and what they are compared with.
struct Runs<'a> {
    problem: &'a Problem<'a>,
    parameters: Vec<Parameter>,
    times: Vec<f64>,
    /// Per sample, the measured values of the fitted quantities.
    measured: Vec<Vec<f64>>,
    /// The fitted quantities' indices among the run's.
    quantities: Vec<usize>,
    runs: usize,
    /// The settings of the trial runs: the problem's, their steps bounded (a trial of
    /// parameters far off, a negative damping, can make the motion blow up and the run crawl;
    /// failing, it is a step too long).
    trial_changes: SettingsChanges,
}

impl Runs<'_> {
    /// The run at `p`: its residuals and sensitivities; `Err` with the run's failure.
    fn at(&mut self, p: &[f64]) -> Result<Point, NonlinearError> {
        let mut overrides = self.problem.overrides.to_vec();
        let mut initial = Vec::new();
        for (parameter, &value) in self.parameters.iter().zip(p) {
            match parameter.target {
                Target::Value => overrides.push(Override {
                    name: parameter.name.clone(),
                    value,
                }),
                Target::Initial {
                    join,
                    coordinate,
                    order,
                } => initial.push((join, coordinate, order, value)),
            }
        }
        let mechanism = with_initial_values(self.problem.mechanism, &initial);
        self.runs += 1;
        let found = sensitivities_at(
            &mechanism,
            &overrides,
            &self.trial_changes,
            self.problem.names,
            Some(&self.times),
        )?;
        self.point(p, &found)
    }

    /// The residuals and sensitivities of the run `found` at `p`.
    fn point(&self, p: &[f64], found: &Sensitivities) -> Result<Point, NonlinearError> {
        if let Some(failure) = &found.report.failure {
            return Err(NonlinearError::RunFailed {
                time: failure.time,
                why: failure.message.clone(),
            });
        }
        let (columns, count) = (self.quantities.len(), p.len());
        let equations = self.times.len() * columns;
        let mut r = DVector::zeros(equations);
        let mut j = DMatrix::zeros(equations, count);
        for (s, sample) in found.samples.iter().enumerate() {
            for (c, &q) in self.quantities.iter().enumerate() {
                let row = s * columns + c;
                r[row] = self.measured[s][c] - sample.values[q];
                for i in 0..count {
                    j[(row, i)] = sample.derivatives[q * count + i];
                }
            }
        }
        Ok(Point {
            p: p.to_vec(),
            r,
            j,
        })
    }
}

/// Fits the parameters `problem.names` to the measured quantities of `table` (every column
/// named as a quantity of the run).
pub fn identify_nonlinear(
    problem: &Problem<'_>,
    table: &Table,
) -> Result<NonlinearIdentification, NonlinearError> {
    let cpu_started = thread_cpu_seconds();
    let parameters = resolve(problem.mechanism, problem.overrides, problem.names)
        .map_err(NonlinearError::Program)?;
    let times = table.times().map_err(NonlinearError::Usage)?;
    // The run at the program's values: its quantities' names, the initial values' values.
    let first = sensitivities_at(
        problem.mechanism,
        problem.overrides,
        problem.changes,
        problem.names,
        Some(&times),
    )?;
    let fitted: Vec<(usize, usize)> = (first.quantities.iter().enumerate())
        .filter_map(|(q, name)| table.find(name).map(|k| (q, k)))
        .collect();
    if fitted.is_empty() {
        return Err(NonlinearError::Usage(format!(
            "{}:{}:1: no column names a quantity of the run: give one at least of {}",
            table.file,
            table.header_line,
            super::quoted(&first.quantities)
        )));
    }
    let mut columns = Vec::new();
    for &(_, k) in &fitted {
        columns.push(table.column(k).map_err(NonlinearError::Usage)?);
    }
    let measured: Vec<Vec<f64>> = (0..times.len())
        .map(|s| columns.iter().map(|c| c[s]).collect())
        .collect();
    let count = parameters.len();
    let equations = times.len() * fitted.len();
    if equations <= count {
        return Err(NonlinearError::TooFewSamples {
            equations,
            parameters: count,
        });
    }
    let start: Vec<f64> = first.parameters.iter().map(|p| p.value).collect();
    let trial_changes = SettingsChanges {
        max_steps: (problem.changes.max_steps).or(Some(
            (TRIAL_STEPS * first.report.steps).max(MIN_TRIAL_STEPS),
        )),
        ..problem.changes.clone()
    };
    let mut runs = Runs {
        trial_changes,
        problem,
        parameters,
        times,
        measured,
        quantities: fitted.iter().map(|&(q, _)| q).collect(),
        runs: 1,
    };
    let names: Vec<String> = problem.names.to_vec();
    let mut point = runs.point(&start, &first)?;
    refuse_unidentifiable(&point.j, &names)?;
    let c = fitted.len();
    let mut weights = vec![1.0; c];
    let mut iterations = 0;
    point = levenberg_marquardt(&mut runs, point, &weights, &mut iterations)?;
    // Each column's σ from the residual of the fit weighted alike; at the runs' accuracy the
    // data are noise-free, and weights of the residuals' ratios mean nothing.
    let samples = runs.times.len();
    let sigmas: Vec<f64> = (0..c)
        .map(|col| {
            let squares: f64 = (col..equations)
                .step_by(c)
                .map(|k| point.r[k].powi(2))
                .sum();
            (squares / samples.saturating_sub(count).max(1) as f64).sqrt()
        })
        .collect();
    let scale = (0..c).map(|col| (runs.measured.iter().map(|m| m[col].abs())).fold(0.0, f64::max));
    let noise_free = sigmas
        .iter()
        .zip(scale)
        .any(|(&s, m)| s <= NOISE_FREE * m.max(f64::MIN_POSITIVE));
    let sigmas = match noise_free {
        true => Vec::new(),
        false => {
            weights = sigmas.iter().map(|s| 1.0 / s).collect();
            point = levenberg_marquardt(&mut runs, point, &weights, &mut iterations)?;
            sigmas
        }
    };
    let (rw, jw) = point.weighted(&weights);
    let (std, condition) = deviations(&rw, &jw);
    let sum_squares = point.r.norm_squared();
    let measured_norm = (runs.measured.iter().flatten())
        .map(|x| x * x)
        .sum::<f64>()
        .sqrt();
    let residual = Residual {
        rms: (sum_squares / equations as f64).sqrt(),
        relative: sum_squares.sqrt() / measured_norm.max(f64::MIN_POSITIVE),
        sigma: (sum_squares / (equations - count) as f64).sqrt(),
        sigmas,
    };
    let estimates = (0..count)
        .map(|i| NonlinearEstimate {
            name: names[i].clone(),
            kind: first.parameters[i].kind,
            value: point.p[i],
            std: std[i],
            model: start[i],
        })
        .collect();
    let cpu_seconds = thread_cpu_seconds()
        .zip(cpu_started)
        .map(|(now, then)| now - then);
    Ok(NonlinearIdentification {
        parameters: estimates,
        condition,
        residual,
        samples,
        equations,
        fitted: fitted
            .iter()
            .map(|&(q, _)| first.quantities[q].clone())
            .collect(),
        method: METHOD,
        iterations,
        runs: runs.runs,
        cpu_seconds,
    })
}

/// A column's σ at most this fraction of its largest measurement is the runs' own error: the
/// data are noise-free.
const NOISE_FREE: f64 = 1e-9;

/// Refuses a Jacobian whose columns (scaled to unit norm) are zero or dependent, naming the
/// parameters: those without effect, and those of the right singular vectors of the singular
/// values at most [`RANK_TOLERANCE`] of the largest.
fn refuse_unidentifiable(j: &DMatrix<f64>, names: &[String]) -> Result<(), NonlinearError> {
    let norms: Vec<f64> = j.column_iter().map(|c| c.norm()).collect();
    let largest = norms.iter().copied().fold(0.0, f64::max);
    let (effective, without): (Vec<usize>, Vec<usize>) =
        (0..j.ncols()).partition(|&i| largest > 0.0 && norms[i] > RANK_TOLERANCE * largest);
    let scaled = DMatrix::from_fn(j.nrows(), effective.len(), |k, i| {
        j[(k, effective[i])] / norms[effective[i]]
    });
    let mut together = Vec::new();
    if !effective.is_empty() {
        let decomposition = svd(scaled, false, true);
        let Some((singular, v_t)) = decomposition
            .as_ref()
            .and_then(|d| d.v_t.as_ref().map(|v| (&d.singular_values, v)))
        else {
            return Err(NonlinearError::Unidentifiable {
                without_effect: Vec::new(),
                together: names.to_vec(),
            });
        };
        let top = singular.max();
        for (k, &value) in singular.iter().enumerate() {
            if value <= RANK_TOLERANCE * top {
                for (i, &column) in effective.iter().enumerate() {
                    if v_t[(k, i)].abs() >= NULL_SHARE && !together.contains(&column) {
                        together.push(column);
                    }
                }
            }
        }
    }
    together.sort_unstable();
    if without.is_empty() && together.is_empty() {
        return Ok(());
    }
    Err(NonlinearError::Unidentifiable {
        without_effect: without.iter().map(|&i| names[i].clone()).collect(),
        together: together.iter().map(|&i| names[i].clone()).collect(),
    })
}

/// Levenberg–Marquardt from `point` with the columns' `weights` (see the module's
/// documentation); `iterations` counts the steps tried.
fn levenberg_marquardt(
    runs: &mut Runs<'_>,
    mut point: Point,
    weights: &[f64],
    iterations: &mut usize,
) -> Result<Point, NonlinearError> {
    let count = point.p.len();
    let (mut r, mut j) = point.weighted(weights);
    let mut cost = r.norm_squared();
    // Moré's scaling: the largest column norms seen, so that a column that vanishes at one
    // point does not lose its scale.
    let mut scaling: Vec<f64> = j.column_iter().map(|c| c.norm()).collect();
    let mut lambda = LAMBDA_START;
    let mut growth = 2.0;
    for _ in 0..MAX_ITERATIONS {
        if cost == 0.0 {
            return Ok(point);
        }
        for (d, column) in scaling.iter_mut().zip(j.column_iter()) {
            *d = d.max(column.norm());
            if *d == 0.0 {
                *d = 1.0;
            }
        }
        *iterations += 1;
        let Some(step) = damped_step(&j, &r, &scaling, lambda) else {
            lambda *= growth;
            growth *= 2.0;
            continue;
        };
        let scaled_step: f64 = (0..count)
            .map(|i| (scaling[i] * step[i]).powi(2))
            .sum::<f64>()
            .sqrt();
        let scaled_p: f64 = (0..count)
            .map(|i| (scaling[i] * point.p[i]).powi(2))
            .sum::<f64>()
            .sqrt();
        let trial_p: Vec<f64> = (0..count).map(|i| point.p[i] + step[i]).collect();
        // The reduction the linear model predicts: |r|² − |r − J δ|².
        let predicted = cost - (&r - &j * &step).norm_squared();
        let trial = match runs.at(&trial_p) {
            Ok(trial) => Some(trial),
            // A step to values where the program cannot be prepared or run is too long.
            Err(NonlinearError::RunFailed { .. })
            | Err(NonlinearError::Program(_))
            | Err(NonlinearError::Usage(_)) => None,
            Err(other) => return Err(other),
        };
        let accepted = trial.and_then(|trial| {
            let (trial_r, trial_j) = trial.weighted(weights);
            let trial_cost = trial_r.norm_squared();
            let rho = (cost - trial_cost) / predicted;
            (predicted > 0.0 && rho > 0.0).then_some((trial, trial_r, trial_j, trial_cost, rho))
        });
        match accepted {
            Some((trial, trial_r, trial_j, trial_cost, rho)) => {
                let reduction = cost - trial_cost;
                (point, r, j, cost) = (trial, trial_r, trial_j, trial_cost);
                lambda *= (1.0f64 / 3.0).max(1.0 - (2.0 * rho - 1.0).powi(3));
                growth = 2.0;
                if reduction <= COST_TOLERANCE * cost
                    || scaled_step <= STEP_TOLERANCE * (scaled_p + STEP_TOLERANCE)
                {
                    return Ok(point);
                }
            }
            None => {
                // A step already at the parameters' round-off cannot do better.
                if scaled_step <= STEP_TOLERANCE * (scaled_p + STEP_TOLERANCE) {
                    return Ok(point);
                }
                lambda *= growth;
                growth *= 2.0;
            }
        }
    }
    Err(NonlinearError::NotConverged {
        iterations: *iterations,
    })
}

/// A trial run may take this many times the steps of the run at the start, and at least
/// [`MIN_TRIAL_STEPS`].
const TRIAL_STEPS: usize = 4;
const MIN_TRIAL_STEPS: usize = 1_000;

/// λ at the start, relative to the scaled problem (Marquardt's 1e-3 … 1e-2).
const LAMBDA_START: f64 = 1e-3;

/// δ minimising |J δ − r|² + λ |D δ|², by the SVD of [J; √λ D] (the normal equations would
/// square the condition).
fn damped_step(
    j: &DMatrix<f64>,
    r: &DVector<f64>,
    scaling: &[f64],
    lambda: f64,
) -> Option<DVector<f64>> {
    let (m, n) = j.shape();
    let mut stacked = DMatrix::zeros(m + n, n);
    stacked.view_mut((0, 0), (m, n)).copy_from(j);
    for i in 0..n {
        stacked[(m + i, i)] = lambda.sqrt() * scaling[i];
    }
    let mut side = DVector::zeros(m + n);
    side.rows_mut(0, m).copy_from(r);
    let decomposition = svd(stacked, true, true)?;
    let step = decomposition.solve(&side, 0.0).ok()?;
    step.iter().all(|x| x.is_finite()).then_some(step)
}

/// The standard deviations σ √diag((JᵀJ)⁻¹) of the weighted problem, and the condition
/// number of J with its columns scaled to unit norm.
fn deviations(r: &DVector<f64>, j: &DMatrix<f64>) -> (Vec<f64>, f64) {
    let (m, n) = j.shape();
    let norms: Vec<f64> = j
        .column_iter()
        .map(|c| c.norm().max(f64::MIN_POSITIVE))
        .collect();
    let scaled = DMatrix::from_fn(m, n, |k, i| j[(k, i)] / norms[i]);
    let Some(decomposition) = svd(scaled, false, true) else {
        return (vec![f64::NAN; n], f64::INFINITY);
    };
    let singular = &decomposition.singular_values;
    let condition = singular.max() / singular.min();
    let Some(v_t) = decomposition.v_t.as_ref() else {
        return (vec![f64::NAN; n], condition);
    };
    let variance = r.norm_squared() / (m - n) as f64;
    let std = (0..n)
        .map(|i| {
            let spread: f64 = (0..n).map(|k| (v_t[(k, i)] / singular[k]).powi(2)).sum();
            (variance * spread).sqrt() / norms[i]
        })
        .collect();
    (std, condition)
}
