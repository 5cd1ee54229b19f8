//! A run's samples as columns: a dict of the CSV header's names (`time`, `swing.q`,
//! `swing.q'`, `kinetic_energy`, `potential_energy`, reactions, outputs) to NumPy arrays, the
//! numbers `lsdc simulate` writes in its CSV, bit for bit (a missing potential energy is NaN
//! where the CSV leaves the field empty).

use lsdc::api::{Prepared, Report, Sample};
use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// The names of a run's columns, in the CSV's order (`lsdc::output::csv::header`).
pub fn column_names(prepared: &Prepared) -> Vec<String> {
    let coordinates = &prepared.coordinate_names;
    let mut names = vec!["time".to_string()];
    names.extend(coordinates.iter().cloned());
    names.extend(coordinates.iter().map(|n| format!("{n}'")));
    names.extend(["kinetic_energy", "potential_energy"].map(String::from));
    for name in lsdc::api::reaction_names(prepared) {
        for part in ["mx", "my", "mz", "fx", "fy", "fz"] {
            names.push(format!("{name}.reaction.{part}"));
        }
    }
    names.extend(lsdc::api::output_names(prepared));
    names
}

/// One sample's values in the order of [`column_names`].
fn row(sample: &Sample) -> impl Iterator<Item = f64> + '_ {
    (std::iter::once(sample.time))
        .chain(sample.coordinates.iter().copied())
        .chain(sample.rates.iter().copied())
        .chain([
            sample.kinetic_energy,
            sample.potential_energy.unwrap_or(f64::NAN),
        ])
        .chain(sample.reactions.iter().copied())
        .chain(sample.outputs.iter().copied())
}

/// The samples as a dict of names to NumPy arrays.
pub fn to_dict<'py>(
    py: Python<'py>,
    names: &[String],
    samples: &[Sample],
) -> PyResult<Bound<'py, PyDict>> {
    let mut columns: Vec<Vec<f64>> = vec![Vec::with_capacity(samples.len()); names.len()];
    for sample in samples {
        for (column, value) in columns.iter_mut().zip(row(sample)) {
            // −0 as +0, as the CSV writes it (`0e0`): the arrays hold the CSV's bits.
            column.push(value + 0.0);
        }
    }
    let dict = PyDict::new(py);
    for (name, column) in names.iter().zip(columns) {
        dict.set_item(name, PyArray1::from_vec(py, column))?;
    }
    Ok(dict)
}

/// The run report's main entries as a dict: the integrator, steps, CPU time, energy drift and
/// the failure (`None`, or `(time, message)`).
pub fn report_dict<'py>(py: Python<'py>, report: &Report) -> PyResult<Bound<'py, PyDict>> {
    let dict = PyDict::new(py);
    dict.set_item("integrator", &report.integrator)?;
    dict.set_item("duration", report.duration)?;
    dict.set_item("steps", report.steps)?;
    dict.set_item("rejected_steps", report.rejected_steps)?;
    dict.set_item("function_evaluations", report.function_evaluations)?;
    dict.set_item("cpu_seconds", report.cpu_seconds)?;
    dict.set_item("wall_seconds", report.wall_seconds)?;
    dict.set_item("energy_drift", report.energy_drift)?;
    let failure = (report.failure.as_ref()).map(|f| (f.time, f.message.clone()));
    dict.set_item("failure", failure)?;
    Ok(dict)
}

/// `columns` and `report` as an `lsdc.Columns` (a dict with `to_pandas()` and `report`,
/// defined in Python: `lsdc/_columns.py`).
pub fn as_columns<'py>(
    py: Python<'py>,
    columns: Bound<'py, PyDict>,
    report: Bound<'py, PyDict>,
) -> PyResult<Bound<'py, PyAny>> {
    let class = py.import("lsdc._columns")?.getattr("Columns")?;
    class.call1((columns, report))
}
