//! A motion from a file made the drives of a run (`lsdc inverse --motion`): the coordinates it
//! names, or the actuated coordinates of a parallel robot whose frame it moves.
//!
//! - Coordinates (`A1.q`, …): each column becomes a drive of its coordinate.
//! - A frame's position (`nacelle.x`, `nacelle.y`, `nacelle.z`) with actuated coordinates: at
//!   each time of the file the inverse geometric model (the loops closed with the frame's origin
//!   dragged to the position, from the configuration of the time before: `configurations`),
//!   then the inverse velocity and acceleration models at that configuration
//!   (`kinematic_models`: q̇ₐ = J⁻¹ẋ, q̈ₐ = J⁻¹ẍ + the term of J̇), give the actuated
//!   coordinates' positions, rates and accelerations.
//!
//! - The program's position drive (`drive position(nacelle) = [x, y, z]`): its path sampled
//!   at the run's output times, with the laws' exact rates and accelerations
//!   ([`program_path`]), followed as a file's path is.
//!
//! Either way the drives' laws pass through those values at the file's times (quintic Hermite
//! interpolation, `kinematics::tabulated_law`), the run's outputs are the file's times, and the
//! run starts from the configuration of the first one. With every degree of freedom driven the
//! samples are then the given motion and its efforts, exact at each row.

use std::collections::BTreeMap;

use nalgebra::{DMatrix, DVector};
use serde::Serialize;

use super::configurations::{assemble_holding, close_from, StateRequest};
use super::kinematic_models::{
    actuation, models_at, Actuation, Output, OutputKind, SINGULAR_TOLERANCE,
};
use super::motion_file::{Derivation, MotionFile, Series};
use super::statics::velocity_index;
use crate::dynamics::drives::DrivenCoordinate;
use crate::kinematics::drives::{drive_effort_name, DriveLaw, LawAt};
use crate::kinematics::frames::FramePoint;
use crate::kinematics::tabulated_law::TabulatedLaw;
use crate::prepare::Prepared;

/// What a motion file moves.
pub enum Target<'a> {
    /// The coordinates its columns name.
    Coordinates,
    /// A frame's origin, moved by the actuated coordinates.
    Frame {
        output: &'a Output,
        actuation: &'a Actuation,
    },
}

/// How each column of the file was read.
#[derive(Clone, Debug, Serialize)]
pub struct ColumnSource {
    pub name: String,
    pub rates: Derivation,
    pub accelerations: Derivation,
}

/// The coordinates a motion drives, in the order of their drives.
#[derive(Clone, Debug, Serialize)]
pub struct Imposed {
    pub driven: Vec<String>,
    pub columns: Vec<ColumnSource>,
}

/// The time between rows may differ from the first interval by this much, relative to the
/// last time (the run samples at a fixed interval).
const EVEN_SPACING: f64 = 1e-9;

/// Adds the drives of `motion` to `prepared` (see the module's documentation), and makes its
/// run start at the motion's first row and sample at each of its rows.
pub fn impose(
    prepared: &mut Prepared,
    motion: &MotionFile,
    target: Target<'_>,
) -> Result<Imposed, String> {
    let step = even_step(&motion.times)?;
    let knots = match target {
        Target::Coordinates => coordinate_knots(prepared, motion)?,
        Target::Frame { output, actuation } => frame_knots(prepared, motion, output, actuation)?,
    };
    let mut driven = Vec::new();
    let mut rates = vec![0.0; prepared.coordinates.len()];
    for knot in &knots.series {
        let (position, velocity) = drivable(prepared, &knot.name)?;
        let law = TabulatedLaw::through(
            &motion.times,
            &knot.positions,
            &knot.rates,
            &knot.accelerations,
        )
        .map_err(|e| {
            format!(
                "`{}`: cannot pass a law through its values: {e:?}",
                knot.name
            )
        })?;
        let join = knot.name.rsplit_once('.').map_or("", |(join, _)| join);
        let declared = declared_index(prepared, &knot.name)?;
        rates[declared] = knot.rates[0];
        prepared.model.drives.push(DrivenCoordinate {
            coordinate: knot.name.clone(),
            declared,
            position,
            velocity,
            law: DriveLaw::Tabulated(law),
            effort: drive_effort_name(join),
        });
        driven.push(knot.name.clone());
    }
    prepared.coordinates = knots.start;
    prepared.rates = rates;
    prepared.settings.duration = *motion.times.last().expect("two rows at least");
    prepared.settings.output = step;
    Ok(Imposed {
        driven,
        columns: (motion.series.iter())
            .map(|s| ColumnSource {
                name: s.name.clone(),
                rates: s.rates_from,
                accelerations: s.accelerations_from,
            })
            .collect(),
    })
}

/// The path of the program's position drive as a motion file: its frame's position, with the
/// laws' exact rates and accelerations, at the times 0, `step`, 2 `step`, … up to `duration`
/// (the last at most half a step from it). `None` when the program has no position drive;
/// refused when it has several (a path moves one frame through its actuated coordinates).
pub fn program_path(
    prepared: &Prepared,
    duration: f64,
    step: f64,
) -> Option<Result<(MotionFile, FramePoint), String>> {
    let drives = &prepared.model.position_drives;
    let drive = drives.first()?;
    if drives.len() > 1 {
        return Some(Err(format!(
            "the program drives the positions of {} frames: `lsdc inverse` follows the path of one through the actuated coordinates",
            drives.len()
        )));
    }
    if !(step > 0.0 && duration >= step) {
        return Some(Err(format!(
            "the path is sampled every {step} s for {duration} s: give a positive interval no longer than the duration (`--every`, `--duration`)"
        )));
    }
    let rows = (duration / step).round() as usize;
    let times: Vec<f64> = (0..=rows).map(|k| k as f64 * step).collect();
    let laws: Vec<[LawAt; 3]> = times.iter().map(|&t| drive.at(t)).collect();
    let series = (drive.component_names().into_iter().enumerate())
        .map(|(axis, name)| Series {
            name,
            positions: laws.iter().map(|at| at[axis].position).collect(),
            rates: laws.iter().map(|at| at[axis].rate).collect(),
            accelerations: laws.iter().map(|at| at[axis].acceleration).collect(),
            rates_from: Derivation::Law,
            accelerations_from: Derivation::Law,
        })
        .collect();
    Some(Ok((MotionFile { times, series }, drive.frame.clone())))
}

/// The program's position drive followed through the actuated coordinates `actuated`
/// (`join.coordinate`, one per degree of freedom): its path sampled at the run's output times
/// ([`program_path`]) imposed as a file's path is, the actuated coordinates' drives added to
/// `prepared` in the place of the position drive. `None` without a position drive.
pub fn follow_program_path(
    prepared: &mut Prepared,
    actuated: &[String],
) -> Option<Result<Imposed, String>> {
    let settings = &prepared.settings;
    let path = program_path(prepared, settings.duration, settings.output)?;
    Some(path.and_then(|(motion, frame)| {
        let actuation = actuation(prepared, actuated).map_err(|e| e.to_string())?;
        let output = Output {
            frame,
            kind: OutputKind::Point,
        };
        let target = Target::Frame {
            output: &output,
            actuation: &actuation,
        };
        let imposed = impose(prepared, &motion, target)
            .map_err(|why| format!("the position drive of `{}`: {why}", output.frame.name))?;
        prepared.model.position_drives.clear();
        Ok(imposed)
    }))
}

/// The positions, rates and accelerations of the driven coordinates at the file's times, and
/// the declared coordinates the run starts from.
struct Knots {
    series: Vec<KnotSeries>,
    start: Vec<f64>,
}

struct KnotSeries {
    name: String,
    positions: Vec<f64>,
    rates: Vec<f64>,
    accelerations: Vec<f64>,
}

/// The interval of the run's outputs: the file's times must start at 0 and be evenly spaced.
fn even_step(times: &[f64]) -> Result<f64, String> {
    if times.len() < 2 {
        return Err("the motion needs two rows at least".to_string());
    }
    if times[0] != 0.0 {
        return Err(format!(
            "the motion starts at t = {}: its times must start at 0 (the run's start)",
            times[0]
        ));
    }
    let step = times[1];
    let last = times[times.len() - 1];
    match (times.iter().enumerate()).find(|(k, &t)| (t - *k as f64 * step).abs() > EVEN_SPACING * last) {
        Some((k, t)) => Err(format!(
            "the motion's times are not evenly spaced: its row {} is at t = {t}, not {} as the first interval, {step}, makes it (the run samples at a fixed interval: resample the file)",
            k + 1,
            (k as f64 * step * 1e9).round() / 1e9
        )),
        None => Ok(step),
    }
}

/// Each column a coordinate: its values as they are; the run starts with the loops assembled
/// holding the first row.
fn coordinate_knots(prepared: &Prepared, motion: &MotionFile) -> Result<Knots, String> {
    let held: BTreeMap<String, f64> = (motion.series.iter())
        .map(|s| (s.name.clone(), s.positions[0]))
        .collect();
    for series in &motion.series {
        drivable(prepared, &series.name)?;
    }
    let start = assemble_holding(prepared, &prepared.coordinates, &held)
        .map_err(|why| format!("the motion's first row: {why}"))?;
    let series = (motion.series.iter())
        .map(|s| KnotSeries {
            name: s.name.clone(),
            positions: s.positions.clone(),
            rates: s.rates.clone(),
            accelerations: s.accelerations.clone(),
        })
        .collect();
    Ok(Knots { series, start })
}

/// The actuated coordinates' knots from the path of `output`'s frame (see the module's
/// documentation).
fn frame_knots(
    prepared: &Prepared,
    motion: &MotionFile,
    output: &Output,
    actuation: &Actuation,
) -> Result<Knots, String> {
    if output.kind != OutputKind::Point {
        return Err("a motion moves a frame's origin (its orientation follows)".to_string());
    }
    let frame = &output.frame.name;
    let axes = ["x", "y", "z"].map(|axis| format!("{frame}.{axis}"));
    let columns: Vec<&str> = motion.series.iter().map(|s| s.name.as_str()).collect();
    if columns != axes.iter().map(String::as_str).collect::<Vec<_>>() {
        return Err(format!(
            "a path of `{frame}` has the columns time, {}, optionally their rates (') and accelerations (''); this file has {}",
            axes.join(", "),
            columns.join(", ")
        ));
    }
    for name in &actuation.names {
        drivable(prepared, name)?;
    }
    let model = &prepared.model;
    let declared: Vec<usize> = (actuation.names.iter())
        .map(|name| declared_index(prepared, name))
        .collect::<Result<_, _>>()?;
    let count = actuation.names.len();
    let mut series: Vec<KnotSeries> = (actuation.names.iter())
        .map(|name| KnotSeries {
            name: name.clone(),
            positions: Vec::new(),
            rates: Vec::new(),
            accelerations: Vec::new(),
        })
        .collect();
    let mut start = None;
    let mut previous = prepared.coordinates.clone();
    let axis = |k: usize, f: fn(&super::motion_file::Series) -> &Vec<f64>| {
        DVector::from_fn(3, |r, _| f(&motion.series[r])[k])
    };
    for (k, &time) in motion.times.iter().enumerate() {
        let at_time = |why: String| format!("the path at t = {time}: {why}");
        let position = axis(k, |s| &s.positions);
        let request = StateRequest {
            point: Some([position[0], position[1], position[2]]),
            ..Default::default()
        };
        let closed = close_from(prepared, &previous, &request, &output.frame).map_err(at_time)?;
        let zero = vec![0.0; closed.coordinates.len()];
        let (q, _) = (model.state_from_declared(&closed.coordinates, &zero))
            .map_err(|e| at_time(format!("{e:?}")))?;
        let models = |rates: &[f64]| {
            models_at(model, actuation, output, &q, rates, SINGULAR_TOLERANCE)
                .map_err(|e| at_time(e.to_string()))
        };
        let still = models(&vec![0.0; count])?;
        if let Some(kind) = still.singularity.kind {
            return Err(at_time(format!(
                "the mechanism is at a singular configuration there, {}",
                kind.describe()
            )));
        }
        let inverse = DMatrix::from_fn(count, 3, |r, c| still.inverse[r][c]);
        let rates = &inverse * axis(k, |s| &s.rates);
        let moving = models(rates.as_slice())?;
        let term = DVector::from_column_slice(&moving.inverse_acceleration_term);
        let accelerations = &inverse * axis(k, |s| &s.accelerations) + term;
        for (j, knot) in series.iter_mut().enumerate() {
            knot.positions.push(closed.coordinates[declared[j]]);
            knot.rates.push(rates[j]);
            knot.accelerations.push(accelerations[j]);
        }
        start.get_or_insert_with(|| closed.coordinates.clone());
        previous = closed.coordinates;
    }
    Ok(Knots {
        series,
        start: start.expect("two rows at least"),
    })
}

/// The state position and velocity of the coordinate `name` if a drive may impose it: the one
/// coordinate of a joint of the tree, which no `mimic` couples to a leader and no drive of the
/// program imposes (the rules of `drive`, `kinematics::drives`).
fn drivable(prepared: &Prepared, name: &str) -> Result<(usize, usize), String> {
    let model = &prepared.model;
    let velocity = velocity_index(prepared, name).map_err(|e| e.to_string())?;
    let refuse = |why: &str| Err(format!("`{name}` cannot be driven: {why}"));
    let Some(joint) = model.joint_of_velocity(velocity) else {
        return refuse("its join closes a loop, and the loop's closure decides it");
    };
    if !joint.is_single_coordinate() {
        return refuse(
            "a drive imposes the coordinate of a join with one (a revolute or prismatic joint)",
        );
    }
    if model.mimics.iter().any(|m| m.velocity == velocity) {
        return refuse("it follows its `mimic` leader");
    }
    if model.drives.iter().any(|d| d.velocity == velocity) {
        return refuse("the program drives it already (`drive`)");
    }
    Ok((joint.q_offset, velocity))
}

fn declared_index(prepared: &Prepared, name: &str) -> Result<usize, String> {
    (prepared.coordinate_names.iter())
        .position(|n| n == name)
        .ok_or_else(|| format!("`{name}` is not a coordinate of the mechanism"))
}
