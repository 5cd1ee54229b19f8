//! `lsdc drag`: a point of a body follows a path of targets, quasi-statically, by either method
//! (`kinematics::drag`, exact loops and the point as a soft goal, the default; or
//! `kinematics::penalty`, the planar penalty joints). One row per target: where the point
//! ended, its distance to the target, the loops' residual or the joints' gap, the energy and
//! the configuration.

use nalgebra::{Vector2, Vector3};
use serde::Serialize;

use crate::kinematics::drag::{drag, DragError, DragOptions};
use crate::kinematics::eval::EvalError;
use crate::kinematics::frames::FramePoint;
use crate::kinematics::model::KinematicModel;
use crate::kinematics::penalty::{self, PlanarModel, Stiffness};

/// A target read from the path file, with its line for messages.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Target {
    pub line: usize,
    pub position: [f64; 3],
}

/// Reads targets: one per line, `x,y` or `x,y,z` (z defaults to `default_z`); blank lines,
/// `#` comments and a first line that is not numbers (a header) are skipped.
pub fn parse_targets(text: &str, name: &str, default_z: f64) -> Result<Vec<Target>, String> {
    let mut targets = Vec::new();
    for (index, line) in text.lines().enumerate() {
        let line_number = index + 1;
        let trimmed = line.trim();
        if trimmed.is_empty() || trimmed.starts_with('#') {
            continue;
        }
        let fields: Result<Vec<f64>, _> = trimmed.split(',').map(|f| f.trim().parse()).collect();
        let position = match fields.as_deref() {
            Ok([x, y]) => [*x, *y, default_z],
            Ok([x, y, z]) => [*x, *y, *z],
            Err(_) if targets.is_empty() && index == 0 => continue,
            _ => {
                return Err(format!(
                    "{name}:{line_number}: expected a target `x,y` or `x,y,z` (numbers), found `{trimmed}`"
                ))
            }
        };
        if position.iter().any(|v| !v.is_finite()) {
            return Err(format!(
                "{name}:{line_number}: a target must be finite numbers"
            ));
        }
        targets.push(Target {
            line: line_number,
            position,
        });
    }
    if targets.is_empty() {
        return Err(format!(
            "{name}: no targets (one `x,y` or `x,y,z` per line)"
        ));
    }
    Ok(targets)
}

/// The result at one target.
#[derive(Clone, Debug, Serialize)]
pub struct DragRow {
    pub target: [f64; 3],
    pub point: [f64; 3],
    pub distance: f64,
    pub reached: bool,
    /// Exact method: the loops' largest residual. Penalty: the largest gap of a pivot.
    pub gap: f64,
    /// ½ K_M distance² (exact), or the springs' energy (penalty).
    pub energy: f64,
    pub iterations: usize,
    /// The joint coordinates (exact) or X, Y, Θ of each body (penalty), in
    /// `DragRun::configuration_names` order.
    pub configuration: Vec<f64>,
}

#[derive(Clone, Debug, Serialize)]
pub struct DragRun {
    pub method: &'static str,
    pub point: String,
    pub configuration_names: Vec<String>,
    pub rows: Vec<DragRow>,
}

impl DragRun {
    /// The targets out of reach: their rows.
    pub fn unreached(&self) -> impl Iterator<Item = (usize, &DragRow)> {
        self.rows.iter().enumerate().filter(|(_, r)| !r.reached)
    }
}

fn array(v: &Vector3<f64>) -> [f64; 3] {
    [v.x, v.y, v.z]
}

/// Follows the targets with the exact method from the closed configuration `q`.
pub fn follow_exact(
    model: &KinematicModel,
    frame: &FramePoint,
    q: &[f64],
    targets: &[Target],
    mouse_stiffness: f64,
    options: &DragOptions,
) -> Result<DragRun, DragError> {
    let mut q = q.to_vec();
    let mut rows = Vec::new();
    for target in targets {
        let goal = Vector3::from(target.position);
        let dragged = drag(model, frame, &q, &goal, options)?;
        rows.push(DragRow {
            target: target.position,
            point: array(&dragged.point),
            distance: dragged.distance,
            reached: dragged.reached(options),
            gap: dragged.loop_residual,
            energy: 0.5 * mouse_stiffness * dragged.distance.powi(2),
            iterations: dragged.iterations,
            configuration: dragged.q.clone(),
        });
        q = dragged.q;
    }
    Ok(DragRun {
        method: "exact",
        point: frame.name.clone(),
        configuration_names: model.coordinate_names(),
        rows,
    })
}

/// The most linearised solves per target of the penalty method when it runs to convergence.
pub const PENALTY_SOLVES: usize = 100;

/// A configuration change (in metres and radians) below which the penalty method's solves have
/// converged: round-off for coordinates of order one.
const PENALTY_STILL: f64 = 1e-13;

/// The largest change of a body's coordinates (X, Y, Θ) between two planar configurations.
fn largest_change(before: &[[f64; 3]], after: &[[f64; 3]]) -> f64 {
    before
        .iter()
        .flatten()
        .zip(after.iter().flatten())
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max)
}

#[derive(Clone, Copy, Debug)]
pub struct PenaltyOptions {
    pub stiffness: Stiffness,
    /// Linearised solves per target (1: the seed's one solve per move), or `None`: as many as
    /// move the configuration, up to `PENALTY_SOLVES`.
    pub iterations: Option<usize>,
    pub reach_tolerance: f64,
}

/// Follows the targets with the seed's penalty method from the configuration `q`.
pub fn follow_penalty(
    model: &KinematicModel,
    planar: &PlanarModel,
    frame: &FramePoint,
    q: &[f64],
    targets: &[Target],
    options: &PenaltyOptions,
) -> Result<DragRun, EvalError> {
    let PenaltyOptions {
        stiffness,
        iterations,
        reach_tolerance,
    } = *options;
    let point = penalty::planar_point(frame);
    let mut state = penalty::planar_state(model, q)?;
    let mut rows = Vec::new();
    for target in targets {
        let goal = Vector2::new(target.position[0], target.position[1]);
        let mut solves = 0;
        while solves < iterations.unwrap_or(PENALTY_SOLVES) {
            let next = planar.step(&state, &point, &goal, stiffness);
            solves += 1;
            let moved = largest_change(&state, &next);
            state = next;
            // A NaN configuration moves no further either.
            if iterations.is_none() && (moved <= PENALTY_STILL || moved.is_nan()) {
                break;
            }
        }
        let position = penalty::point_position(planar, &state, &point);
        let distance = (position.xy() - goal).norm();
        rows.push(DragRow {
            target: target.position,
            point: array(&position),
            distance,
            reached: distance <= reach_tolerance,
            gap: planar.largest_gap(&state),
            energy: planar.energy(&state, &point, &goal, stiffness),
            iterations: solves,
            configuration: state.iter().flatten().copied().collect(),
        });
    }
    let configuration_names = planar
        .body_names
        .iter()
        .flat_map(|b| ["X", "Y", "theta"].map(|c| format!("{b}.{c}")))
        .collect();
    Ok(DragRun {
        method: "penalty",
        point: frame.name.clone(),
        configuration_names,
        rows,
    })
}

/// The run as CSV: a header, then one line per target.
pub fn to_csv(run: &DragRun) -> String {
    let mut out = String::from(
        "target.x,target.y,target.z,point.x,point.y,point.z,distance,reached,gap,energy,iterations",
    );
    for name in &run.configuration_names {
        out.push(',');
        out.push_str(name);
    }
    out.push('\n');
    for row in &run.rows {
        let numbers = row.target.iter().chain(&row.point).chain([&row.distance]);
        let mut fields: Vec<String> = numbers.map(|v| format!("{v:e}")).collect();
        fields.push(row.reached.to_string());
        fields.push(format!("{:e}", row.gap));
        fields.push(format!("{:e}", row.energy));
        fields.push(row.iterations.to_string());
        fields.extend(row.configuration.iter().map(|v| format!("{v:e}")));
        out.push_str(&fields.join(","));
        out.push('\n');
    }
    out
}
