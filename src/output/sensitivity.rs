//! A sensitivity study's results (`lsdc sensitivity`): CSV with a column per quantity and
//! parameter (`d(swing.q)/d(L)`), JSON with the values, the derivatives and those at the end
//! of the run by name, the report as text, and a plot of the derivatives over time.

use std::fmt::Write as _;
use std::path::Path;

use super::plot::{plot_series, PlotError, Series};
use crate::studies::sensitivity::Sensitivities;

/// The CSV text: `time`, then every derivative column; a failed run ends with a comment line
/// saying when and why, after the rows computed before it.
pub fn csv(sensitivities: &Sensitivities) -> String {
    let mut out = String::from("time");
    for column in &sensitivities.columns {
        let _ = write!(out, ",{column}");
    }
    out.push('\n');
    for sample in &sensitivities.samples {
        let _ = write!(out, "{:e}", sample.time + 0.0);
        for value in &sample.derivatives {
            let _ = write!(out, ",{:e}", value + 0.0);
        }
        out.push('\n');
    }
    if let Some(failure) = &sensitivities.report.failure {
        let _ = writeln!(
            out,
            "# the run failed at t = {}: {}",
            failure.time, failure.message
        );
    }
    out
}

/// The JSON value: the study's fields, and `final`, the derivatives at the last sample by
/// column name.
pub fn json(sensitivities: &Sensitivities) -> serde_json::Value {
    let mut value = serde_json::to_value(sensitivities).unwrap_or_default();
    let finals: serde_json::Map<String, serde_json::Value> = (sensitivities.final_values())
        .into_iter()
        .map(|(name, x)| (name.to_string(), serde_json::json!(x)))
        .collect();
    if let Some(object) = value.as_object_mut() {
        object.insert("final".to_string(), serde_json::Value::Object(finals));
    }
    value
}

/// The report for standard error: the parameters, the cost, how it ended.
pub fn report(sensitivities: &Sensitivities) -> String {
    let report = &sensitivities.report;
    let mut out = String::new();
    for parameter in &sensitivities.parameters {
        let _ = writeln!(
            out,
            "parameter {} = {} ({})",
            parameter.name, parameter.value, parameter.kind
        );
    }
    let _ = writeln!(
        out,
        "integrator {}: {} steps ({} rejected), {} evaluations of the augmented system (dimension {} = {} × {}; ∂f/∂x S {}){}",
        report.integrator,
        report.steps,
        report.rejected_steps,
        report.function_evaluations,
        report.augmented_dimension,
        report.state_dimension,
        1 + sensitivities.parameters.len(),
        report.state_derivatives,
        report
            .cpu_seconds
            .map_or(String::new(), |s| format!(", {s:.3} s of CPU")),
    );
    if let Some(failure) = &report.failure {
        let _ = writeln!(
            out,
            "the run failed at t = {}: {}",
            failure.time, failure.message
        );
    }
    out
}

/// Draws the derivatives over time to `path` (.svg or .png): a panel per parameter, a line per
/// coordinate and output (the rates left out, as `lsdc simulate`'s plot leaves them).
pub fn plot(sensitivities: &Sensitivities, path: &Path) -> Result<(), PlotError> {
    let times: Vec<f64> = sensitivities.samples.iter().map(|s| s.time).collect();
    let count = sensitivities.parameters.len();
    let panels: Vec<Series> = (sensitivities.parameters.iter().enumerate())
        .map(|(j, parameter)| Series {
            caption: format!("Sensitivities to {}", parameter.name),
            lines: (sensitivities.quantities.iter().enumerate())
                .filter(|(_, quantity)| !quantity.ends_with('\''))
                .map(|(k, quantity)| {
                    let label = crate::studies::sensitivity::column_name(quantity, &parameter.name);
                    let values = (sensitivities.samples.iter())
                        .map(|s| s.derivatives[k * count + j])
                        .collect();
                    (label, values)
                })
                .collect(),
        })
        .collect();
    plot_series(path, &times, &panels)
}
