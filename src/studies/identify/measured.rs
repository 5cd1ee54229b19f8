//! The measurements `lsdc identify --data` reads: a CSV file with the columns `lsdc simulate`
//! and `lsdc inverse` write. `time`; per coordinate its positions (`elbow.q`) and, when
//! measured, its rates (`elbow.q'`) and accelerations (`elbow.q''`); per joint of one coordinate
//! whose effort is measured, the effort an actuator applies along it (`elbow.drive_effort`).
//! Other columns are ignored. Rates missing are those of a quintic smoothing spline of the
//! positions, and accelerations missing those of the spline of the rates (of the positions
//! when the rates are missing too): `motion_file`'s spline (Woltring's GCVSPL), of error
//! variance `--smoothing`. Errors give the file, line and column.

use crate::diag::suggest::did_you_mean;
use crate::dynamics::model::Model;
use crate::kinematics::drives::drive_effort_name;
use crate::studies::motion_file::{spline_derivatives, Derivation};

/// A coordinate's positions, rates and accelerations along the samples.
type Series = (Vec<f64>, Vec<f64>, Vec<f64>);

/// The measurements along the file's times, per velocity of the model.
#[derive(Clone, Debug)]
pub struct Measured {
    pub times: Vec<f64>,
    /// Per sample, the positions, rates and accelerations (nv each: the model's coordinates).
    pub positions: Vec<Vec<f64>>,
    pub rates: Vec<Vec<f64>>,
    pub accelerations: Vec<Vec<f64>>,
    /// The velocities whose efforts are measured, and per sample those efforts.
    pub measured_efforts: Vec<usize>,
    pub efforts: Vec<Vec<f64>>,
    /// Where the rates and accelerations come from, per coordinate.
    pub rates_from: Vec<Derivation>,
    pub accelerations_from: Vec<Derivation>,
}

/// Reads `text` (named `file` in the errors) for `model`'s coordinates (which must all be
/// joints' own coordinates: `identify` refuses spherical and free joints before). With closed
/// loops, only the coordinates whose efforts are measured need their positions: the others
/// follow from the loops' closure (`loops`), and are left NaN here, from `Derivation::Loops`.
pub fn read_measured(
    text: &str,
    file: &str,
    model: &Model,
    smoothing: f64,
) -> Result<Measured, String> {
    let mut lines = (text.lines().enumerate())
        .filter(|(_, l)| !l.trim().is_empty() && !l.trim_start().starts_with('#'));
    let Some((header_index, header)) = lines.next() else {
        return Err(format!("{file}: no header line"));
    };
    let columns: Vec<&str> = header.split(',').map(str::trim).collect();
    // The column (1-based, in characters) where each field of the header starts.
    let starts: Vec<usize> = std::iter::once(1)
        .chain(
            header
                .match_indices(',')
                .map(|(i, _)| header[..i].chars().count() + 2),
        )
        .collect();
    let at_header =
        |column: usize, message: String| format!("{file}:{}:{column}: {message}", header_index + 1);
    let end_of_header = header.chars().count() + 1;
    let find = |name: &str| columns.iter().position(|c| *c == name);
    // A missing column is shown where the closest one is, or at the end of the header.
    let missing = |name: &str| {
        let closest = did_you_mean(name, columns.iter().copied());
        let column = closest.and_then(find).map_or(end_of_header, |k| starts[k]);
        let suggestion = closest
            .map(|s| format!("; did you mean `{s}`?"))
            .unwrap_or_default();
        at_header(
            column,
            format!("no column `{name}`: the positions of every coordinate are needed{suggestion}"),
        )
    };
    let time = find("time").ok_or_else(|| at_header(1, "no `time` column".to_string()))?;
    let names: Vec<String> = (0..model.nv).map(|i| model.velocity_name(i)).collect();
    let measured_efforts: Vec<usize> = (model.joints.iter())
        .filter(|j| j.is_single_coordinate())
        .filter(|j| find(&drive_effort_name(&j.chain.name)).is_some())
        .map(|j| j.v_offset)
        .collect();
    // Per coordinate, its positions' column; `None` for one the loops' closure gives.
    let mut position_columns = Vec::new();
    for (velocity, name) in names.iter().enumerate() {
        let closed = model.has_loops() && !measured_efforts.contains(&velocity);
        match (find(name), closed) {
            (_, true) => position_columns.push(None),
            (Some(k), false) => position_columns.push(Some(k)),
            (None, false) => return Err(missing(name)),
        }
    }
    if measured_efforts.is_empty() {
        let expected: Vec<String> = (model.joints.iter())
            .filter(|j| j.is_single_coordinate())
            .map(|j| format!("`{}`", drive_effort_name(&j.chain.name)))
            .collect();
        return Err(at_header(
            end_of_header,
            format!(
                "no measured effort: give one column at least of {}",
                expected.join(", ")
            ),
        ));
    }
    let effort_name = |velocity: usize| {
        let joint = model.joint_of_velocity(velocity);
        drive_effort_name(joint.map_or("", |j| j.chain.name.as_str()))
    };
    // The columns read: a field elsewhere may hold anything (an empty potential energy).
    let read: Vec<usize> = std::iter::once(time)
        .chain(position_columns.iter().flatten().copied())
        .chain(
            (names.iter().zip(&position_columns))
                .filter(|(_, k)| k.is_some())
                .flat_map(|(n, _)| {
                    [find(&format!("{n}'")), find(&format!("{n}''"))]
                        .into_iter()
                        .flatten()
                }),
        )
        .chain(
            measured_efforts
                .iter()
                .filter_map(|&v| find(&effort_name(v))),
        )
        .collect();
    let mut rows: Vec<Vec<f64>> = Vec::new();
    for (index, line) in lines {
        let fields: Vec<&str> = line.split(',').map(str::trim).collect();
        if fields.len() != columns.len() {
            return Err(format!(
                "{file}:{}:1: {} fields for {} columns",
                index + 1,
                fields.len(),
                columns.len()
            ));
        }
        let row: Vec<f64> = (fields.iter())
            .map(|f| f.parse::<f64>().unwrap_or(f64::NAN))
            .collect();
        if let Some(&bad) = read.iter().find(|&&k| !row[k].is_finite()) {
            // The field's first character: after the comma that ends the field before it.
            let column_start = match bad {
                0 => 1,
                _ => line
                    .match_indices(',')
                    .nth(bad - 1)
                    .map_or(1, |(i, _)| line[..i].chars().count() + 2),
            };
            return Err(format!(
                "{file}:{}:{column_start}: `{}` is not a finite number (column `{}`)",
                index + 1,
                fields[bad],
                columns[bad]
            ));
        }
        rows.push(row);
        let row = &rows[rows.len() - 1];
        if rows.len() > 1 && row[time] <= rows[rows.len() - 2][time] {
            return Err(format!(
                "{file}:{}:{}: the time {} does not follow {}: times must increase",
                index + 1,
                starts[time],
                row[time],
                rows[rows.len() - 2][time]
            ));
        }
    }
    let column = |k: usize| rows.iter().map(|r| r[k]).collect::<Vec<f64>>();
    let times = column(time);
    let mut by_coordinate = Vec::new();
    let (mut rates_from, mut accelerations_from) = (Vec::new(), Vec::new());
    for (name, &k) in names.iter().zip(&position_columns) {
        let Some(k) = k else {
            let unknown = vec![f64::NAN; times.len()];
            rates_from.push(Derivation::Loops);
            accelerations_from.push(Derivation::Loops);
            by_coordinate.push((unknown.clone(), unknown.clone(), unknown));
            continue;
        };
        let positions = column(k);
        let spline = |values: &[f64], of: &str| {
            spline_derivatives(&times, values, smoothing).map_err(|why| {
                at_header(starts[k], format!("cannot fit the spline of `{of}`: {why}"))
            })
        };
        let (rates, from_rates) = match find(&format!("{name}'")) {
            Some(r) => (column(r), Derivation::File),
            None => (spline(&positions, name)?.0, Derivation::Spline),
        };
        let (accelerations, from_accelerations) = match find(&format!("{name}''")) {
            Some(a) => (column(a), Derivation::File),
            None => (spline(&rates, &format!("{name}'"))?.0, Derivation::Spline),
        };
        rates_from.push(from_rates);
        accelerations_from.push(from_accelerations);
        by_coordinate.push((positions, rates, accelerations));
    }
    let per_sample = |pick: fn(&Series) -> &Vec<f64>| {
        (0..times.len())
            .map(|s| by_coordinate.iter().map(|c| pick(c)[s]).collect())
            .collect()
    };
    let efforts = (0..times.len())
        .map(|s| {
            (measured_efforts.iter())
                .filter_map(|&v| find(&effort_name(v)).map(|k| rows[s][k]))
                .collect()
        })
        .collect();
    Ok(Measured {
        positions: per_sample(|c| &c.0),
        rates: per_sample(|c| &c.1),
        accelerations: per_sample(|c| &c.2),
        times,
        measured_efforts,
        efforts,
        rates_from,
        accelerations_from,
    })
}
