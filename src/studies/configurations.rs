//! The configurations a kinematic study looks at (`lsdc kinematics --at`, `--along`): given by
//! some of their coordinates (the loops closed by assembly holding them: the direct geometric
//! model), by the position of a frame (the loops closed with the frame's origin dragged there:
//! the inverse geometric model), or read from the samples of a run or a drag (every declared
//! coordinate, and the rates where the file has them).

use std::collections::BTreeMap;

use nalgebra::Vector3;
use serde::Deserialize;

use crate::kinematics::assembly::{assemble, AssemblyError, AssemblyOptions};
use crate::kinematics::drag::{drag, DragOptions};
use crate::kinematics::frames::FramePoint;
use crate::prepare::Prepared;

/// One state of a `--at` file.
#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StateRequest {
    /// Declared coordinates held while the loops are closed (`"A1.q": 0.7`).
    #[serde(default)]
    pub coordinates: BTreeMap<String, f64>,
    /// Where the frame's origin is taken (the inverse geometric model), fixed axes.
    #[serde(default)]
    pub point: Option<[f64; 3]>,
    /// Rates of declared coordinates (`"A1.q": 0.1`); those not given are zero.
    #[serde(default)]
    pub rates: BTreeMap<String, f64>,
}

/// Reads `{"states": [...]}` or the bare list.
pub fn parse_requests(text: &str) -> Result<Vec<StateRequest>, String> {
    #[derive(Deserialize)]
    #[serde(deny_unknown_fields)]
    struct File {
        states: Vec<StateRequest>,
    }
    #[derive(Deserialize)]
    #[serde(untagged)]
    enum Either {
        File(File),
        List(Vec<StateRequest>),
    }
    match serde_json::from_str::<Either>(text) {
        Ok(Either::File(file)) => Ok(file.states),
        Ok(Either::List(list)) => Ok(list),
        Err(_) => {
            // Read again as the documented form, for an error that names what is wrong.
            serde_json::from_str::<File>(text)
                .map(|file| file.states)
                .map_err(|e| e.to_string())
        }
    }
}

/// A configuration closed on the loops: the declared coordinates and their rates.
#[derive(Clone, Debug)]
pub struct Declared {
    pub coordinates: Vec<f64>,
    pub rates: Vec<f64>,
    /// The time of a run's sample (its index for a drag's rows or a `--at` state).
    pub time: f64,
}

/// The configuration `request` asks for, closed from the program's initial one; `frame` is the
/// frame whose origin a `point` places.
pub fn close(
    prepared: &Prepared,
    request: &StateRequest,
    frame: &FramePoint,
) -> Result<Declared, String> {
    close_from(prepared, &prepared.coordinates, request, frame)
}

/// As [`close`], from the declared coordinates `start` (a neighbouring configuration: a
/// sweep stays on its assembly mode).
pub fn close_from(
    prepared: &Prepared,
    start: &[f64],
    request: &StateRequest,
    frame: &FramePoint,
) -> Result<Declared, String> {
    let mut coordinates = assemble_holding(prepared, start, &request.coordinates)?;
    if let Some(point) = request.point {
        if !request.coordinates.is_empty() {
            return Err("give either coordinates or a point, not both".to_string());
        }
        let target = Vector3::from(point);
        let dragged = drag(
            &prepared.kinematics,
            frame,
            &coordinates,
            &target,
            &DragOptions::default(),
        )
        .map_err(|_| "the loops cannot be closed on the way to the point".to_string())?;
        if !dragged.reached(&DragOptions::default()) {
            return Err(format!(
                "the point {point:?} is out of reach: `{}` stops {:.3e} away from it",
                frame.name, dragged.distance
            ));
        }
        coordinates = dragged.q;
    }
    let mut rates = vec![0.0; coordinates.len()];
    for (name, &value) in &request.rates {
        rates[coordinate_index(prepared, name)?] = value;
    }
    Ok(Declared {
        coordinates,
        rates,
        time: 0.0,
    })
}

/// The declared coordinate `name`'s index, or why there is none.
fn coordinate_index(prepared: &Prepared, name: &str) -> Result<usize, String> {
    let names = &prepared.coordinate_names;
    names.iter().position(|n| n == name).ok_or_else(|| {
        let close = crate::diag::suggest::did_you_mean(name, names.iter().map(String::as_str))
            .map_or(String::new(), |c| format!("; did you mean `{c}`?"));
        format!("`{name}` is not a coordinate of the mechanism{close}")
    })
}

/// The configuration assembled from the declared coordinates `start` with the coordinates
/// `held` at their values (the direct geometric model).
pub fn assemble_holding(
    prepared: &Prepared,
    start: &[f64],
    held: &BTreeMap<String, f64>,
) -> Result<Vec<f64>, String> {
    let mut start = start.to_vec();
    let mut fixed = vec![false; start.len()];
    for (name, &value) in held {
        let index = coordinate_index(prepared, name)?;
        start[index] = value;
        fixed[index] = true;
    }
    let options = AssemblyOptions::default();
    let assembled = assemble(&prepared.kinematics, &start, &fixed, &options).map_err(|error| {
        match error {
            AssemblyError::NoAssembly { loop_errors, .. } => {
                let (position, rotation) = (loop_errors.iter())
                    .fold((0.0f64, 0.0f64), |(p, r), (lp, lr)| (p.max(*lp), r.max(*lr)));
                format!(
                    "the loops do not close with these coordinates held (closest: {position:.3e} m and {rotation:.3e} rad apart)"
                )
            }
            AssemblyError::Evaluation(_) => {
                "the geometry cannot be evaluated at these coordinates".to_string()
            }
        }
    })?;
    Ok(assembled.q)
}

/// The fields of the CSV line `line` (line `index` + 1 of `file`), as many as the header's
/// `columns`.
pub(crate) fn row_fields<'a>(
    line: &'a str,
    columns: usize,
    file: &str,
    index: usize,
) -> Result<Vec<&'a str>, String> {
    let fields: Vec<&str> = line.split(',').map(str::trim).collect();
    match fields.len() == columns {
        true => Ok(fields),
        false => Err(format!(
            "{file}:{}: {} fields for {columns} columns",
            index + 1,
            fields.len(),
        )),
    }
}

/// Where `frame`'s origin is (fixed axes) at the declared coordinates.
pub fn point_of(
    prepared: &Prepared,
    frame: &FramePoint,
    coordinates: &[f64],
) -> Result<[f64; 3], crate::kinematics::eval::EvalError> {
    let configuration = crate::kinematics::forward::forward(&prepared.kinematics, coordinates)?;
    let p = frame.pose(&configuration).translation.vector;
    Ok([p.x, p.y, p.z])
}

/// Reads the samples of a run (`lsdc simulate`'s CSV: `time`, the coordinates, their rates
/// `name'`) or of a drag (`lsdc drag`'s CSV, the coordinates among its columns): every declared
/// coordinate must be a column; rates are read where present, zero otherwise; without a `time`
/// column a sample's time is its row number.
pub fn read_samples(prepared: &Prepared, text: &str, file: &str) -> Result<Vec<Declared>, String> {
    let mut lines = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty() && !l.starts_with('#'));
    let Some((_, header)) = lines.next() else {
        return Err(format!("{file}: no header line"));
    };
    let columns: Vec<&str> = header.split(',').map(str::trim).collect();
    let column = |name: &str| columns.iter().position(|c| *c == name);
    let names = &prepared.coordinate_names;
    let positions = names
        .iter()
        .map(|n| {
            column(n).ok_or_else(|| {
                format!("{file}: no column `{n}` (every coordinate of the mechanism is needed)")
            })
        })
        .collect::<Result<Vec<usize>, String>>()?;
    let rates: Vec<Option<usize>> = names.iter().map(|n| column(&format!("{n}'"))).collect();
    let time = column("time");
    let mut samples = Vec::new();
    for (row, (index, line)) in lines.enumerate() {
        let fields = row_fields(line, columns.len(), file, index)?;
        // Only the columns read need be numbers (a drag's `reached` is not).
        let number = |c: usize| {
            fields[c]
                .parse::<f64>()
                .map_err(|_| format!("{file}:{}: `{}` is not a number", index + 1, fields[c]))
        };
        let coordinates = positions
            .iter()
            .map(|&c| number(c))
            .collect::<Result<_, _>>()?;
        let rates = (rates.iter())
            .map(|c| c.map_or(Ok(0.0), number))
            .collect::<Result<_, _>>()?;
        let time = time.map_or(Ok(row as f64), number)?;
        samples.push(Declared {
            coordinates,
            rates,
            time,
        });
    }
    Ok(samples)
}
