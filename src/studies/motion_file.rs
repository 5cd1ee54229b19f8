//! A motion read from a CSV file (`lsdc inverse --motion FILE`): a `time` column and, per
//! imposed quantity (a coordinate `A1.q`, a frame's position `nacelle.x`), its positions,
//! optionally its rates (`A1.q'`) and accelerations (`A1.q''`). What the file does not give is
//! taken from a quintic smoothing spline of the positions: Woltring's GCVSPL (H. J. Woltring,
//! "A Fortran package for generalized, cross-validatory spline smoothing and differentiation",
//! Advances in Engineering Software 8(2), 1986), through the `gcv_spline` crate, with half
//! order 3 (degree 5, so that the acceleration is itself twice differentiable). With the
//! default error variance 0 the spline interpolates the positions; a variance σ² > 0 (the
//! positions' noise, in their units squared) smooths them by the predicted mean-squared-error
//! criterion of the package.

use serde::Serialize;

use super::configurations::row_fields;

/// Where a rate or an acceleration comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Derivation {
    /// Its own column of the file.
    File,
    /// The quintic spline of the positions.
    Spline,
    /// The program's law, differentiated on its expression (a position drive's path).
    Law,
    /// The loops' closure at the measured independent coordinates (`lsdc identify` on a
    /// mechanism with closed loops: the coordinates not measured).
    Loops,
}

/// One imposed quantity along the file's times.
#[derive(Clone, Debug)]
pub struct Series {
    /// The column's name: `A1.q`, `nacelle.x`.
    pub name: String,
    pub positions: Vec<f64>,
    pub rates: Vec<f64>,
    pub accelerations: Vec<f64>,
    pub rates_from: Derivation,
    pub accelerations_from: Derivation,
}

/// The motion of a file: its times and the series, in the order of their columns.
#[derive(Clone, Debug)]
pub struct MotionFile {
    pub times: Vec<f64>,
    pub series: Vec<Series>,
}

/// Reads `text` (named `file` in the errors, which give its line): `#` lines and blank lines
/// are skipped, the first other line names the columns. `variance` is the spline's error
/// variance (0: it interpolates).
pub fn read_motion(text: &str, file: &str, variance: f64) -> Result<MotionFile, String> {
    let mut lines = (text.lines().enumerate())
        .filter(|(_, l)| !l.trim().is_empty() && !l.trim_start().starts_with('#'));
    let Some((header_index, header)) = lines.next() else {
        return Err(format!("{file}: no header line"));
    };
    let columns: Vec<&str> = header.split(',').map(str::trim).collect();
    let at_header = |message: String| format!("{file}:{}: {message}", header_index + 1);
    let Some(time_column) = columns.iter().position(|c| *c == "time") else {
        return Err(at_header("no `time` column".to_string()));
    };
    for (k, name) in columns.iter().enumerate() {
        if columns[..k].contains(name) {
            return Err(at_header(format!("`{name}` is a column twice")));
        }
        let base = name.trim_end_matches('\'');
        if base != *name && !columns.contains(&base) {
            return Err(at_header(format!(
                "`{name}` is a derivative of `{base}`, which is no column: give the positions"
            )));
        }
        if name.ends_with("'''") {
            return Err(at_header(format!(
                "`{name}`: a motion gives positions, rates (') and accelerations ('') only"
            )));
        }
    }
    let mut rows: Vec<Vec<f64>> = Vec::new();
    for (index, line) in lines {
        let fields = row_fields(line, columns.len(), file, index)?;
        let row = (fields.iter())
            .map(|f| match f.parse::<f64>() {
                Ok(x) if x.is_finite() => Ok(x),
                _ => Err(format!(
                    "{file}:{}: `{f}` is not a finite number",
                    index + 1
                )),
            })
            .collect::<Result<Vec<f64>, String>>()?;
        if let Some(previous) = rows.last() {
            if row[time_column] <= previous[time_column] {
                return Err(format!(
                    "{file}:{}: the time {} does not follow {}: times must increase",
                    index + 1,
                    row[time_column],
                    previous[time_column]
                ));
            }
        }
        rows.push(row);
    }
    let column = |k: usize| rows.iter().map(|r| r[k]).collect::<Vec<f64>>();
    let times = column(time_column);
    let bases = (0..columns.len()).filter(|&k| k != time_column && !columns[k].ends_with('\''));
    let mut series = Vec::new();
    for k in bases {
        let name = columns[k];
        let positions = column(k);
        let given = |suffix: &str| {
            (columns.iter())
                .position(|c| *c == format!("{name}{suffix}"))
                .map(column)
        };
        let (rates, accelerations) = (given("'"), given("''"));
        let spline = match (&rates, &accelerations) {
            (Some(_), Some(_)) => None,
            _ => Some(
                spline_derivatives(&times, &positions, variance).map_err(|why| {
                    at_header(format!("cannot fit the spline of `{name}`: {why}"))
                })?,
            ),
        };
        let from = |given: &Option<Vec<f64>>| match given {
            Some(_) => Derivation::File,
            None => Derivation::Spline,
        };
        let (rates_from, accelerations_from) = (from(&rates), from(&accelerations));
        let (spline_rates, spline_accelerations) = spline.unwrap_or_default();
        series.push(Series {
            name: name.to_string(),
            positions,
            rates: rates.unwrap_or(spline_rates),
            accelerations: accelerations.unwrap_or(spline_accelerations),
            rates_from,
            accelerations_from,
        });
    }
    Ok(MotionFile { times, series })
}

/// The rates and accelerations at `times` of the quintic spline of `positions` (see the
/// module's documentation).
pub(crate) fn spline_derivatives(
    times: &[f64],
    positions: &[f64],
    variance: f64,
) -> Result<(Vec<f64>, Vec<f64>), String> {
    const HALF_ORDER: usize = 3;
    if times.len() < 2 * HALF_ORDER {
        return Err(format!(
            "{} rows, and a quintic spline needs {} at least",
            times.len(),
            2 * HALF_ORDER
        ));
    }
    let spline = gcv_spline::GcvSpline::from_data_half_order_and_smoothing(
        &times.to_vec(),
        &positions.to_vec(),
        HALF_ORDER,
        variance,
    )
    .map_err(|e| format!("{e:?}"))?;
    let at = |order: usize| {
        times
            .iter()
            .map(|&t| spline.point_derivative(t, order))
            .collect()
    };
    Ok((at(1), at(2)))
}
