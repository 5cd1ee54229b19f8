//! Speed against error (`lsdc precision`): the same prepared mechanism simulated by several
//! methods (an integrator at a tolerance, or with a fixed step), each run compared with a
//! reference at the outputs and timed in CPU time over repeats, and the cheapest method that
//! reaches a requested accuracy. Every run is an ordinary `simulate` run (`run::run`).
//!
//! Errors (`docs/commands.md`, *precision*): the largest absolute difference from the reference,
//! over the outputs the reference has a row for, of the declared coordinates (positions, in
//! metres or radians) and of their rates (velocities), each over the columns the reference has;
//! and of the program's outputs (`output` declarations) whose columns the reference has.

use std::fmt;

use serde::Serialize;

use crate::prepare::{Integrator, Prepared};
use crate::simulate::clock::thread_cpu_seconds;
use crate::simulate::run::{self, Simulation};

/// How a method's steps are set: a tolerance (adaptive integrators) or a fixed step (rk4,
/// symplectic).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Setting {
    Tolerance(f64),
    Step(f64),
}

/// An integrator with its setting.
#[derive(Clone, Debug, PartialEq)]
pub struct Method {
    pub integrator: Integrator,
    pub setting: Setting,
}

impl Method {
    /// The prepared mechanism's settings with this method's integrator, tolerance or step.
    fn configure(&self, prepared: &mut Prepared) {
        let settings = &mut prepared.settings;
        settings.integrator = self.integrator.clone();
        match self.setting {
            Setting::Tolerance(tolerance) => {
                (settings.rtol, settings.atol) = (tolerance, tolerance);
                settings.step = None;
            }
            Setting::Step(step) => settings.step = Some(step),
        }
    }
}

impl fmt::Display for Setting {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Setting::Tolerance(t) => write!(f, "tol {t:e}"),
            Setting::Step(h) => write!(f, "step {h:e}"),
        }
    }
}

/// Values to compare with: rows at output times, columns named as lsdc's CSV names them
/// (`join.q` for a coordinate, `join.q'` for its rate).
#[derive(Clone, Debug)]
pub struct Reference {
    pub columns: Vec<String>,
    /// Each row: its time and its values (NaN where a cell is empty), sorted by time.
    pub rows: Vec<(f64, Vec<f64>)>,
    pub source: ReferenceSource,
}

/// Where the reference comes from.
#[derive(Clone, Debug, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum ReferenceSource {
    /// A run of lsdc at a tolerance much tighter than the methods', and the largest difference
    /// of its positions from a run at ten times its tolerance: what its own error is likely
    /// below.
    Computed {
        integrator: String,
        tolerance: f64,
        self_difference: f64,
    },
    /// A file given by the user.
    File { path: String },
}

/// A reference that cannot be used.
#[derive(Clone, Debug, PartialEq)]
pub enum ReferenceError {
    /// The CSV text is not a header and rows of numbers (line, what is wrong).
    Csv { line: usize, message: String },
    /// The reference run failed (its message).
    RunFailed(String),
    /// No column of the reference names a coordinate or rate of the mechanism.
    NoCommonColumn,
    /// No row of the reference is at an output time of the runs.
    NoCommonTime,
}

impl fmt::Display for ReferenceError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ReferenceError::Csv { line, message } => {
                write!(f, "line {line} of the reference: {message}")
            }
            ReferenceError::RunFailed(message) => write!(f, "the reference run failed: {message}"),
            ReferenceError::NoCommonColumn => write!(
                f,
                "no column of the reference names a coordinate (`join.q`) or a rate (`join.q'`) of the mechanism"
            ),
            ReferenceError::NoCommonTime => write!(
                f,
                "no row of the reference is at an output time of the runs (see `--duration` and `--every`)"
            ),
        }
    }
}

impl std::error::Error for ReferenceError {}

impl Reference {
    /// Reads a CSV of lsdc's form: a header with `time` first, one row of numbers per time;
    /// lines starting with `#` and empty cells are allowed, a row of another length is not.
    pub fn from_csv(text: &str, path: &str) -> Result<Reference, ReferenceError> {
        let mut lines = text
            .lines()
            .enumerate()
            .filter(|(_, l)| !l.trim().is_empty() && !l.starts_with('#'));
        let bad = |line: usize, message: &str| ReferenceError::Csv {
            line: line + 1,
            message: message.to_string(),
        };
        let (header_line, header) = lines.next().ok_or(bad(0, "no header"))?;
        let mut names = header.split(',').map(|c| c.trim().to_string());
        if names.next().as_deref() != Some("time") {
            return Err(bad(header_line, "the first column must be `time`"));
        }
        let columns: Vec<String> = names.collect();
        let mut rows = Vec::new();
        for (line, text) in lines {
            let cells: Vec<&str> = text.split(',').map(str::trim).collect();
            if cells.len() != columns.len() + 1 {
                return Err(bad(line, "the row does not have the header's length"));
            }
            let number = |cell: &str| match cell {
                "" => Ok(f64::NAN),
                _ => cell.parse::<f64>().map_err(|_| bad(line, "not a number")),
            };
            let time = number(cells[0])?;
            let values = cells[1..]
                .iter()
                .map(|c| number(c))
                .collect::<Result<_, _>>()?;
            rows.push((time, values));
        }
        rows.sort_by(|a, b| a.0.total_cmp(&b.0));
        let source = ReferenceSource::File {
            path: path.to_string(),
        };
        Ok(Reference {
            columns,
            rows,
            source,
        })
    }

    /// The reference made of a simulation's outputs.
    fn from_simulation(simulation: &Simulation, source: ReferenceSource) -> Reference {
        let names = &simulation.coordinate_names;
        let columns = names
            .iter()
            .cloned()
            .chain(names.iter().map(|n| format!("{n}'")))
            .chain(simulation.output_names.iter().cloned())
            .collect();
        let rows = simulation
            .samples
            .iter()
            .map(|s| {
                let values = s.coordinates.iter().chain(&s.rates).chain(&s.outputs);
                (s.time, values.copied().collect())
            })
            .collect();
        Reference {
            columns,
            rows,
            source,
        }
    }

    /// The row at `time`, if there is one (to a relative 1e-9 of the time).
    fn row_at(&self, time: f64) -> Option<&[f64]> {
        let tolerance = 1e-9 * time.abs().max(1.0);
        let index = self.rows.partition_point(|(t, _)| *t < time - tolerance);
        let (t, values) = self.rows.get(index)?;
        ((t - time).abs() <= tolerance).then_some(&values[..])
    }

    /// Every column at `time`, between the first and the last row: the row at that time if
    /// there is one, else interpolated between the rows around it. A column whose rate is a
    /// column too (`x` and `x'`) is interpolated by the cubic Hermite polynomial of its values
    /// and rates at both rows (the error of a step's fourth power, as fine as the outputs of an
    /// integrator), any other linearly.
    pub fn at(&self, time: f64) -> Option<Vec<f64>> {
        if let Some(row) = self.row_at(time) {
            return Some(row.to_vec());
        }
        let after = self.rows.partition_point(|(t, _)| *t < time);
        let ((t0, before), (t1, next)) =
            (self.rows.get(after.checked_sub(1)?)?, self.rows.get(after)?);
        let h = t1 - t0;
        let s = (time - t0) / h;
        let rates = self.rate_columns();
        let value = |c: usize| match rates[c] {
            Some(r) => hermite(s, h, [before[c], before[r]], [next[c], next[r]]),
            None => before[c] + s * (next[c] - before[c]),
        };
        Some((0..self.columns.len()).map(value).collect())
    }

    /// For each column, the column of its rate (`x'` for `x`), if there is one.
    fn rate_columns(&self) -> Vec<Option<usize>> {
        let find = |name: String| self.columns.iter().position(|c| *c == name);
        (self.columns.iter())
            .map(|c| find(format!("{c}'")))
            .collect()
    }

    /// For each coordinate of `names`, the reference's columns of its value and of its rate.
    fn columns_of(&self, names: &[String]) -> Vec<(Option<usize>, Option<usize>)> {
        let find = |name: &str| self.columns.iter().position(|c| c == name);
        names
            .iter()
            .map(|n| (find(n), find(&format!("{n}'"))))
            .collect()
    }
}

/// The cubic Hermite interpolant at `s` ∈ [0, 1] of a step of length `h` between (value, rate)
/// pairs.
fn hermite(s: f64, h: f64, [y0, d0]: [f64; 2], [y1, d1]: [f64; 2]) -> f64 {
    let (s2, s3) = (s * s, s * s * s);
    (2.0 * s3 - 3.0 * s2 + 1.0) * y0
        + (s3 - 2.0 * s2 + s) * h * d0
        + (-2.0 * s3 + 3.0 * s2) * y1
        + (s3 - s2) * h * d1
}

/// A run's distance from the reference.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct Errors {
    /// Largest |q − q_ref| over the compared outputs and coordinates.
    pub position: f64,
    /// Largest |q' − q'_ref|.
    pub velocity: f64,
    /// Largest |o − o_ref| over the program's outputs the reference has (absolute, in each
    /// output's own unit); `None` when it has none of them.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub outputs: Option<f64>,
    /// How many outputs had a reference row.
    pub compared_outputs: usize,
}

/// Compares a simulation's outputs with the reference where it has rows and columns.
pub fn errors(simulation: &Simulation, reference: &Reference) -> Result<Errors, ReferenceError> {
    let columns = reference.columns_of(&simulation.coordinate_names);
    let find = |name: &String| reference.columns.iter().position(|c| c == name);
    let outputs: Vec<Option<usize>> = simulation.output_names.iter().map(find).collect();
    let has_outputs = outputs.iter().any(Option::is_some);
    if columns.iter().all(|c| *c == (None, None)) && !has_outputs {
        return Err(ReferenceError::NoCommonColumn);
    }
    let mut errors = Errors {
        outputs: has_outputs.then_some(0.0),
        ..Errors::default()
    };
    for sample in &simulation.samples {
        let Some(row) = reference.row_at(sample.time) else {
            continue;
        };
        errors.compared_outputs += 1;
        for (i, (value, rate)) in columns.iter().enumerate() {
            let difference =
                |column: Option<usize>, ours: f64| column.map_or(0.0, |c| distance(ours, row[c]));
            errors.position = errors
                .position
                .max(difference(*value, sample.coordinates[i]));
            errors.velocity = errors.velocity.max(difference(*rate, sample.rates[i]));
        }
        for (column, &ours) in outputs.iter().zip(&sample.outputs) {
            if let (Some(c), Some(largest)) = (column, errors.outputs.as_mut()) {
                *largest = largest.max(distance(ours, row[*c]));
            }
        }
    }
    Ok(errors)
}

/// |a − b|, infinite when a is not finite; 0 where the reference has no value (NaN).
fn distance(ours: f64, reference: f64) -> f64 {
    match (ours.is_finite(), reference.is_nan()) {
        (_, true) => 0.0,
        (false, false) => f64::INFINITY,
        (true, false) => (ours - reference).abs(),
    }
}

/// Computes the reference with `integrator` at `tolerance`, and checks it against a run at ten
/// times that tolerance.
pub fn computed_reference(
    prepared: &mut Prepared,
    integrator: &Integrator,
    tolerance: f64,
) -> Result<Reference, ReferenceError> {
    let run_at = |prepared: &mut Prepared, tolerance: f64| {
        let method = Method {
            integrator: integrator.clone(),
            setting: Setting::Tolerance(tolerance),
        };
        method.configure(prepared);
        let simulation = run::run(prepared, &mut |_| {});
        match &simulation.report.failure {
            Some(failure) => Err(ReferenceError::RunFailed(format!(
                "at t = {}: {}",
                failure.time, failure.message
            ))),
            None => Ok(simulation),
        }
    };
    let tight = run_at(prepared, tolerance)?;
    let looser = run_at(prepared, 10.0 * tolerance)?;
    let source = ReferenceSource::Computed {
        integrator: integrator.name().to_string(),
        tolerance,
        self_difference: f64::NAN,
    };
    let mut reference = Reference::from_simulation(&tight, source);
    let difference = errors(&looser, &reference)?.position;
    if let ReferenceSource::Computed {
        self_difference, ..
    } = &mut reference.source
    {
        *self_difference = difference;
    }
    Ok(reference)
}

/// One method's measurements.
#[derive(Clone, Debug, Serialize)]
pub struct Measurement {
    pub integrator: String,
    pub setting: Setting,
    pub errors: Errors,
    /// Largest loop residual (positions) the integration reached before projecting, over the
    /// run: how far its steps leave the constraints (mechanisms with loops).
    pub closure_residual: Option<f64>,
    /// The run report's relative energy drift, or its energy balance for a mechanism with
    /// non-conservative efforts.
    pub energy_drift: Option<f64>,
    pub steps: usize,
    pub rejected_steps: usize,
    pub function_evaluations: usize,
    /// CPU time of the run's thread over the repeats: the least and the median, in seconds.
    pub cpu_seconds_min: f64,
    pub cpu_seconds_median: f64,
    pub repeats: usize,
    /// Why the run stopped early, if it did (its errors are over the outputs before).
    pub failure: Option<String>,
}

/// Simulates with `method` `repeats` times (at least once) and measures the last run.
pub fn measure(
    prepared: &mut Prepared,
    method: &Method,
    reference: &Reference,
    repeats: usize,
) -> Result<Measurement, ReferenceError> {
    method.configure(prepared);
    let mut times = Vec::new();
    let mut simulation = None;
    // NaN where the clock cannot be read: the time is then reported as unknown.
    let now = || thread_cpu_seconds().unwrap_or(f64::NAN);
    for _ in 0..repeats.max(1) {
        let start = now();
        let run = run::run(prepared, &mut |_| {});
        times.push(now() - start);
        simulation = Some(run);
    }
    let simulation = simulation.expect("at least one run");
    times.sort_by(f64::total_cmp);
    let report = &simulation.report;
    Ok(Measurement {
        integrator: report.integrator.clone(),
        setting: method.setting,
        errors: errors(&simulation, reference)?,
        closure_residual: (report.constraints.as_ref()).map(|c| {
            c.position_residual_before_projection
                .max(c.position_residual)
        }),
        energy_drift: report.energy_drift.or(report.energy_balance),
        steps: report.steps,
        rejected_steps: report.rejected_steps,
        function_evaluations: report.function_evaluations,
        cpu_seconds_min: times[0],
        cpu_seconds_median: times[times.len() / 2],
        repeats: times.len(),
        failure: (report.failure.as_ref()).map(|f| format!("at t = {}: {}", f.time, f.message)),
    })
}

/// The work-precision table of a mechanism, and the method it recommends.
#[derive(Clone, Debug, Serialize)]
pub struct Table {
    pub duration: f64,
    pub output_interval: f64,
    pub reference: ReferenceSource,
    pub measurements: Vec<Measurement>,
    /// The accuracy asked for (positions), and the cheapest method that reached it.
    pub accuracy: Option<f64>,
    pub recommendation: Option<Recommendation>,
}

/// The method to use for an accuracy, and why.
#[derive(Clone, Debug, Serialize)]
pub struct Recommendation {
    /// Index of the recommended measurement, or `None` when no run reached the accuracy.
    pub measurement: Option<usize>,
    pub message: String,
}

/// Measures every method against the reference.
pub fn table(
    prepared: &mut Prepared,
    methods: &[Method],
    reference: Reference,
    repeats: usize,
    accuracy: Option<f64>,
) -> Result<Table, ReferenceError> {
    let measurements = methods
        .iter()
        .map(|method| measure(prepared, method, &reference, repeats))
        .collect::<Result<Vec<_>, _>>()?;
    if measurements.iter().all(|m| m.errors.compared_outputs == 0) {
        return Err(ReferenceError::NoCommonTime);
    }
    let recommendation = accuracy.map(|a| recommend(&measurements, a));
    Ok(Table {
        duration: prepared.settings.duration,
        output_interval: prepared.settings.output,
        reference: reference.source,
        measurements,
        accuracy,
        recommendation,
    })
}

/// Fewer repeats than this cannot tell a difference of CPU times from timing noise (identical
/// runs measured 15.06 and 15.47 ms).
pub const TIMED_REPEATS: usize = 3;

/// The cheapest run that finished with a position error at most `accuracy`: the least CPU time
/// (least of its repeats), unless the times cannot tell the runs apart (fewer than
/// [`TIMED_REPEATS`] repeats, or times that differ by less than their spread, median − least):
/// then the fewest function evaluations among those runs, and the message says why.
pub fn recommend(measurements: &[Measurement], accuracy: f64) -> Recommendation {
    let reached: Vec<(usize, &Measurement)> = (measurements.iter().enumerate())
        .filter(|(_, m)| {
            m.failure.is_none() && m.errors.compared_outputs > 0 && m.errors.position <= accuracy
        })
        .collect();
    let by_time = |a: &&(usize, &Measurement), b: &&(usize, &Measurement)| {
        a.1.cpu_seconds_min.total_cmp(&b.1.cpu_seconds_min)
    };
    let Some(&(_, fastest)) = reached.iter().min_by(by_time) else {
        return Recommendation {
            measurement: None,
            message: format!(
                "no run reached positions within {accuracy:e}: tighten the tolerances or shorten the steps"
            ),
        };
    };
    let timed = fastest.repeats >= TIMED_REPEATS;
    let spread = |m: &Measurement| m.cpu_seconds_median - m.cpu_seconds_min;
    let indistinct: Vec<&(usize, &Measurement)> = (reached.iter())
        .filter(|(_, m)| {
            !timed || m.cpu_seconds_min - fastest.cpu_seconds_min <= spread(m).max(spread(fastest))
        })
        .collect();
    let chosen = (indistinct.iter().copied())
        .min_by(|a, b| {
            (a.1.function_evaluations.cmp(&b.1.function_evaluations)).then(by_time(a, b))
        })
        .filter(|_| indistinct.len() > 1);
    let (index, m) = *chosen.unwrap_or_else(|| reached.iter().min_by(by_time).expect("one"));
    let mut message = format!(
        "for positions within {accuracy:e}: {} at {} (error {:.1e}, {:.3} ms of CPU, {} function evaluations)",
        m.integrator,
        m.setting,
        m.errors.position,
        m.cpu_seconds_min * 1e3,
        m.function_evaluations
    );
    if chosen.is_some() {
        message += &match timed {
            false => format!(
                "; ranked by function evaluations, not by CPU time: {} repeat(s) cannot tell a \
                 difference from timing noise (--repeats {TIMED_REPEATS} or more)",
                m.repeats
            ),
            true => format!(
                "; ranked by function evaluations, not by CPU time: {} runs that reached it have \
                 CPU times closer than their spread (median − least over the repeats)",
                indistinct.len()
            ),
        };
    }
    Recommendation {
        measurement: Some(index),
        message,
    }
}
