//! A run's outputs against a reference, variable by variable: the run is interpolated onto the
//! reference's times (`Reference::at`), each difference is measured against the variable's
//! tolerance, and each variable's worst place is kept.

use serde::Serialize;

use super::manifest::{Case, Measure, Tolerance};
use crate::studies::precision::Reference;

/// One variable's error under its measure, where it is worst.
#[derive(Clone, Debug, Serialize)]
pub struct VariableError {
    pub variable: String,
    pub measure: Measure,
    /// The reference time of the largest difference.
    pub time: f64,
    /// The run's and the reference's values there.
    pub actual: f64,
    pub reference: f64,
    /// The measured difference (at that time for `max` and `final`, the root mean square for
    /// `l2`) and what the tolerance allows of it.
    pub difference: f64,
    pub allowed: f64,
    /// difference / allowed: above 1 the variable fails.
    pub margin: f64,
}

impl VariableError {
    pub fn fails(&self) -> bool {
        // A NaN margin (a NaN difference) fails too.
        self.margin.is_nan() || self.margin > 1.0
    }

    /// Orders errors by how near they come to failing, or beyond: by margin, then (between
    /// margins alike, as the infinite ones of a zero tolerance) by difference.
    pub fn closeness(&self, other: &VariableError) -> std::cmp::Ordering {
        (self.margin.total_cmp(&other.margin)).then(self.difference.total_cmp(&other.difference))
    }
}

/// The values of a run and of its reference at the reference's times, for the compared
/// variables.
struct Aligned {
    times: Vec<f64>,
    /// Per variable, per time: (run, reference).
    values: Vec<Vec<(f64, f64)>>,
}

/// Compares a run (its outputs read as a table) with the case's reference. `Err` says why the
/// two cannot be compared: a missing column, a run that ended before the reference's last time.
pub fn compare(
    run: &Reference,
    reference: &Reference,
    case: &Case,
) -> Result<Vec<VariableError>, String> {
    let names = compared_names(reference, case)?;
    let aligned = align(run, reference, &names)?;
    Ok(names
        .iter()
        .zip(&aligned.values)
        .map(|(name, values)| measure(name, &aligned.times, values, case.tolerance_of(name)))
        .collect())
}

/// The case's `outputs`, or every column of the reference; every variable given a tolerance of
/// its own must be among them.
fn compared_names(reference: &Reference, case: &Case) -> Result<Vec<String>, String> {
    let names = case
        .outputs
        .clone()
        .unwrap_or_else(|| reference.columns.clone());
    if let Some(missing) = names.iter().find(|n| !reference.columns.contains(n)) {
        return Err(format!("the reference has no column `{missing}`"));
    }
    if let Some(stray) = case.variables.keys().find(|v| !names.contains(v)) {
        return Err(format!("`{stray}` has a tolerance but is not compared (not an output, or not in the reference)"));
    }
    Ok(names)
}

fn align(run: &Reference, reference: &Reference, names: &[String]) -> Result<Aligned, String> {
    let column = |table: &Reference, name: &String| table.columns.iter().position(|c| c == name);
    let mut pairs = Vec::new();
    for name in names {
        let ours = column(run, name).ok_or_else(|| format!("the run has no output `{name}`"))?;
        pairs.push((ours, column(reference, name).expect("checked")));
    }
    let mut aligned = Aligned {
        times: Vec::new(),
        values: vec![Vec::new(); names.len()],
    };
    for (time, row) in &reference.rows {
        let ours = run.at(*time).ok_or_else(|| ended_before(run, *time))?;
        aligned.times.push(*time);
        for (values, &(c_run, c_ref)) in aligned.values.iter_mut().zip(&pairs) {
            values.push((ours[c_run], row[c_ref]));
        }
    }
    Ok(aligned)
}

fn ended_before(run: &Reference, time: f64) -> String {
    let span = |r: Option<&(f64, Vec<f64>)>| r.map_or(f64::NAN, |(t, _)| *t);
    format!(
        "the run's outputs span t = {} to {}, the reference has a row at t = {time}",
        span(run.rows.first()),
        span(run.rows.last())
    )
}

/// |actual − reference|: 0 where the reference has no value (an empty cell), infinite where the
/// run has none.
fn difference(actual: f64, reference: f64) -> f64 {
    match (reference.is_nan(), actual.is_finite()) {
        (true, _) => 0.0,
        (false, false) => f64::INFINITY,
        (false, true) => (actual - reference).abs(),
    }
}

/// difference / allowed; 0 for no difference, even against a zero tolerance.
fn margin(difference: f64, allowed: f64) -> f64 {
    if difference == 0.0 {
        0.0
    } else {
        difference / allowed
    }
}

/// One variable's error under its tolerance's measure.
fn measure(
    name: &str,
    times: &[f64],
    values: &[(f64, f64)],
    tolerance: Tolerance,
) -> VariableError {
    let at = |i: usize| {
        let (actual, reference) = values[i];
        let difference = difference(actual, reference);
        let allowed = tolerance.allowed(actual.abs().max(reference.abs()));
        VariableError {
            variable: name.to_string(),
            measure: tolerance.measure,
            time: times[i],
            actual,
            reference,
            difference,
            allowed,
            margin: margin(difference, allowed),
        }
    };
    let worst = |candidates: &mut dyn Iterator<Item = VariableError>| {
        candidates
            .max_by(VariableError::closeness)
            .unwrap_or_else(|| nothing_compared(name, tolerance))
    };
    match tolerance.measure {
        Measure::Max => worst(&mut (0..times.len()).map(at)),
        Measure::Final => worst(&mut (times.len().checked_sub(1)).into_iter().map(at)),
        Measure::L2 => root_mean_square(name, times, values, tolerance),
    }
}

/// The root mean square of the differences against the tolerance applied to the root mean
/// square of the values (the larger of the run's and the reference's at each time); reported at
/// the time of the largest difference.
fn root_mean_square(
    name: &str,
    times: &[f64],
    values: &[(f64, f64)],
    tolerance: Tolerance,
) -> VariableError {
    let compared: Vec<usize> = (0..times.len())
        .filter(|&i| !values[i].1.is_nan())
        .collect();
    let Some(&largest) = compared.iter().max_by(|&&a, &&b| {
        let d = |i: usize| difference(values[i].0, values[i].1);
        d(a).total_cmp(&d(b))
    }) else {
        return nothing_compared(name, tolerance);
    };
    let rms = |f: &dyn Fn(usize) -> f64| {
        (compared.iter().map(|&i| f(i).powi(2)).sum::<f64>() / compared.len() as f64).sqrt()
    };
    let rms_difference = rms(&|i| difference(values[i].0, values[i].1));
    let scale = rms(&|i| values[i].0.abs().max(values[i].1.abs()));
    let allowed = tolerance.allowed(scale);
    let (actual, reference) = values[largest];
    VariableError {
        variable: name.to_string(),
        measure: Measure::L2,
        time: times[largest],
        actual,
        reference,
        difference: rms_difference,
        allowed,
        margin: margin(rms_difference, allowed),
    }
}

/// A variable without a single value in the reference: nothing fails.
fn nothing_compared(name: &str, tolerance: Tolerance) -> VariableError {
    VariableError {
        variable: name.to_string(),
        measure: tolerance.measure,
        time: f64::NAN,
        actual: f64::NAN,
        reference: f64::NAN,
        difference: 0.0,
        allowed: tolerance.absolute,
        margin: 0.0,
    }
}
