//! `lsdc test --update`: records a case's reference from a run, and says what moved against the
//! reference it replaces. References are CSV (lsdc's columns, or the case's `outputs`), each
//! value rounded to the manifest's `precision` significant digits and written in its shortest
//! form: a stated precision, and files a few times smaller than every bit of every double.

use std::fmt::Write;

use serde::Serialize;

use super::case::{as_table, compile_and_prepare, read_reference, run_failure, HEADER_START};
use super::compare::{compare, VariableError};
use super::manifest::Case;
use crate::diag::number::shortest;
use crate::simulate::run;
use crate::studies::precision::Reference;

/// What `--update` did to a case's reference.
#[derive(Clone, Debug, Serialize)]
pub struct Recorded {
    pub name: String,
    pub path: String,
    /// Whether there was a reference before (else the diff fields are empty).
    pub replaced: bool,
    pub added_columns: Vec<String>,
    pub removed_columns: Vec<String>,
    pub rows_before: usize,
    pub rows_after: usize,
    /// The variables that moved beyond their tolerance, largest margin first, and the largest
    /// change of all.
    pub moved: Vec<VariableError>,
    pub largest: Option<VariableError>,
}

/// Runs the case and writes its reference: the outputs of a run to its end, or up to its failure
/// when the case expects one.
pub fn record(case: &Case) -> Result<Recorded, String> {
    let path = (case.reference.as_ref()).ok_or("the case has no `reference` to record")?;
    let simulation = run::run(&compile_and_prepare(case)?, &mut |_| {});
    if let Some(failure) = run_failure(&simulation) {
        if case.checks.expect_failure.is_none() {
            return Err(format!("{failure}; nothing recorded"));
        }
    }
    let run = as_table(&simulation);
    let columns = case.outputs.clone().unwrap_or_else(|| run.columns.clone());
    let text = to_csv(&run, &columns, case)?;
    let old = (path.exists().then(|| read_reference(path)).transpose()).map_err(String::from)?;
    let new = Reference::from_csv(&text, "the new reference").map_err(|e| e.to_string())?;
    // The documented pattern puts references in a folder of their own (`expected/`).
    if let Some(folder) = path.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(folder)
            .map_err(|e| format!("cannot create {}: {e}", folder.display()))?;
    }
    std::fs::write(path, &text).map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    Ok(summary(case, path, old.as_ref(), &new))
}

/// The run's `columns` as CSV at the case's `precision` significant digits, the precision
/// stated in a first comment line. A value whose rounding would use more than half of its
/// variable's tolerance is written in full (shortest round-trip form) instead, so that the run
/// just recorded passes against its reference; the first line then says so.
fn to_csv(run: &Reference, columns: &[String], case: &Case) -> Result<String, String> {
    let digits = case.precision;
    let indices = (columns.iter())
        .map(|name| {
            (run.columns.iter())
                .position(|c| c == name)
                .ok_or_else(|| format!("the run has no output `{name}`"))
        })
        .collect::<Result<Vec<_>, _>>()?;
    let tolerances: Vec<_> = columns.iter().map(|c| case.tolerance_of(c)).collect();
    let mut kept_in_full = false;
    let mut body = String::from("time");
    for name in columns {
        let _ = write!(body, ",{name}");
    }
    for (time, row) in &run.rows {
        let _ = write!(body, "\n{}", rounded(*time, 15));
        for (&i, tolerance) in indices.iter().zip(&tolerances) {
            let x = row[i];
            let short = rounded(x, digits);
            let rounding = (short.parse::<f64>().unwrap_or(x) - x).abs();
            let cell = match rounding > 0.5 * tolerance.allowed(x.abs()) {
                true => {
                    kept_in_full = true;
                    shortest(x)
                }
                false => short,
            };
            let _ = write!(body, ",{cell}");
        }
    }
    let finer = match kept_in_full {
        true => FINER_THAN_PRECISION,
        false => "",
    };
    Ok(format!(
        "{HEADER_START}{digits} significant digits{finer}\n{body}\n"
    ))
}

/// What the first line adds when some values are written in full.
const FINER_THAN_PRECISION: &str = ", in full where a tolerance is finer";

/// `x` rounded to `digits` significant digits, in its shortest form (`diag::number::shortest`);
/// empty for NaN (no value).
pub fn rounded(x: f64, digits: usize) -> String {
    if x.is_nan() {
        return String::new();
    }
    let value: f64 = format!("{:.*e}", digits.saturating_sub(1), x)
        .parse()
        .unwrap_or(x);
    shortest(value)
}

fn summary(
    case: &Case,
    path: &std::path::Path,
    old: Option<&Reference>,
    new: &Reference,
) -> Recorded {
    let mut recorded = Recorded {
        name: case.name.clone(),
        path: path.display().to_string(),
        replaced: old.is_some(),
        added_columns: Vec::new(),
        removed_columns: Vec::new(),
        rows_before: old.map_or(0, |o| o.rows.len()),
        rows_after: new.rows.len(),
        moved: Vec::new(),
        largest: None,
    };
    let Some(old) = old else { return recorded };
    let missing = |from: &Reference, to: &Reference| -> Vec<String> {
        (from.columns.iter())
            .filter(|c| !to.columns.contains(c))
            .cloned()
            .collect()
    };
    recorded.added_columns = missing(new, old);
    recorded.removed_columns = missing(old, new);
    // The new values against the old ones, where both have the variable, at the old times.
    let common: Vec<String> = (old.columns.iter())
        .filter(|c| new.columns.contains(c))
        .cloned()
        .collect();
    let compared = Case {
        outputs: Some(common.clone()),
        variables: (case.variables.clone().into_iter())
            .filter(|(v, _)| common.contains(v))
            .collect(),
        ..case.clone()
    };
    if let Ok(mut errors) = compare(new, old, &compared) {
        errors.sort_by(|a, b| b.closeness(a));
        recorded.largest = errors
            .iter()
            .max_by(|a, b| a.difference.total_cmp(&b.difference))
            .cloned();
        recorded.moved = errors.into_iter().filter(VariableError::fails).collect();
    }
    recorded
}
