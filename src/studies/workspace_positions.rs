//! The workspace of a point sampled over a box of positions (`lsdc workspace --positions`): at
//! each cell's centre the inverse geometric model, the loops closed with the point dragged
//! there (`configurations::close_from`, the drag of `kinematics::drag`), and the position is
//! reachable when the point gets there with every actuated coordinate within its range (its
//! stops, or `--range`). The volume is the number of reachable cells times a cell's volume.
//!
//! Each sample starts from a reachable neighbour's configuration when one was sampled (the box
//! is walked back and forth, so the previous sample is a neighbour), else from the last
//! reachable one: the drag then moves a short way and stays on the assembly mode it started on
//! (an arm elbow out stays out), so the positions counted are those of that mode, as the
//! sampling over the actuated coordinates counts them.

use serde::Serialize;

use super::configurations::{close_from, StateRequest};
use super::kinematic_models::{models_at, Actuation, KinematicsError, Output};
use super::workspace::{back_and_forth, flat, unflat, Range};
use crate::prepare::Prepared;

/// A box of positions: lower and upper corners (fixed axes).
#[derive(Clone, Copy, Debug, Serialize)]
pub struct PositionBox {
    pub lower: [f64; 3],
    pub upper: [f64; 3],
}

/// One cell of the box.
#[derive(Clone, Debug, Serialize)]
pub struct PositionSample {
    pub point: [f64; 3],
    pub reachable: bool,
    /// The actuated coordinates the point is reached with (when the drag reached it), within
    /// their ranges or not.
    pub actuated: Option<Vec<f64>>,
    /// Condition number of the inverse velocity model (lengths in L), when reachable and not
    /// singular.
    pub dexterity: Option<f64>,
    pub boundary: bool,
}

#[derive(Clone, Debug, Serialize)]
pub struct PositionWorkspace {
    pub point: String,
    pub positions: PositionBox,
    pub ranges: Vec<Range>,
    pub samples_per_axis: usize,
    /// m³: the reachable cells' volume.
    pub volume: f64,
    pub reachable: usize,
    pub boundary: usize,
    pub samples: Vec<PositionSample>,
}

/// Samples the box on `count` cells per axis.
pub fn sample_positions(
    prepared: &Prepared,
    actuation: &Actuation,
    output: &Output,
    ranges: &[Range],
    positions: &PositionBox,
    count: usize,
    tolerance: f64,
) -> Result<PositionWorkspace, KinematicsError> {
    let widths: [f64; 3] =
        std::array::from_fn(|d| (positions.upper[d] - positions.lower[d]) / count as f64);
    let total = count.pow(3);
    let actuated_indices: Vec<usize> = (ranges.iter())
        .map(|r| {
            (prepared.coordinate_names.iter())
                .position(|n| *n == r.name)
                .expect("a range names a declared coordinate")
        })
        .collect();
    let mut samples: Vec<Option<PositionSample>> = vec![None; total];
    // The configuration of each reachable sample, to start its neighbours from.
    let mut configurations: Vec<Option<Vec<f64>>> = vec![None; total];
    let mut last = prepared.coordinates.clone();
    for step in 0..total {
        let digits = back_and_forth(step, count, 3);
        let index = flat(&digits, count);
        let point: [f64; 3] =
            std::array::from_fn(|d| positions.lower[d] + (digits[d] as f64 + 0.5) * widths[d]);
        let start = neighbours(&digits, count)
            .find_map(|n| configurations[n].as_ref())
            .unwrap_or(&last)
            .clone();
        let request = StateRequest {
            point: Some(point),
            ..Default::default()
        };
        let sample = match close_from(prepared, &start, &request, &output.frame) {
            Err(_) => PositionSample {
                point,
                reachable: false,
                actuated: None,
                dexterity: None,
                boundary: false,
            },
            Ok(declared) => {
                let actuated: Vec<f64> = (actuated_indices.iter())
                    .map(|&i| declared.coordinates[i])
                    .collect();
                let within = (actuated.iter().zip(ranges))
                    .all(|(value, range)| (range.low..=range.high).contains(value));
                let mut dexterity = None;
                if within {
                    let model = &prepared.model;
                    let (q, _) =
                        model.state_from_declared(&declared.coordinates, &declared.rates)?;
                    let rates = vec![0.0; actuation.velocities.len()];
                    dexterity = models_at(model, actuation, output, &q, &rates, tolerance)?
                        .inverse_condition;
                    last.clone_from(&declared.coordinates);
                    configurations[index] = Some(declared.coordinates);
                }
                PositionSample {
                    point,
                    reachable: within,
                    actuated: Some(actuated),
                    dexterity,
                    boundary: false,
                }
            }
        };
        samples[index] = Some(sample);
    }
    let mut samples: Vec<PositionSample> = samples
        .into_iter()
        .map(|s| s.expect("every cell visited"))
        .collect();
    for index in 0..total {
        let digits = unflat(index, count, 3);
        let on_face = digits.iter().any(|&d| d == 0 || d + 1 == count);
        let open = neighbours(&digits, count).any(|n| !samples[n].reachable);
        samples[index].boundary = samples[index].reachable && (on_face || open);
    }
    let reachable = samples.iter().filter(|s| s.reachable).count();
    Ok(PositionWorkspace {
        point: output.frame.name.clone(),
        positions: *positions,
        ranges: ranges.to_vec(),
        samples_per_axis: count,
        volume: reachable as f64 * widths.iter().product::<f64>().abs(),
        reachable,
        boundary: samples.iter().filter(|s| s.boundary).count(),
        samples,
    })
}

/// The flat indices of a cell's neighbours (one index ±1) inside the grid.
fn neighbours(digits: &[usize], count: usize) -> impl Iterator<Item = usize> + '_ {
    (0..digits.len()).flat_map(move |d| {
        [digits[d].checked_sub(1), Some(digits[d] + 1)]
            .into_iter()
            .flatten()
            .filter(move |&moved| moved < count)
            .map(move |moved| {
                let mut other = digits.to_vec();
                other[d] = moved;
                flat(&other, count)
            })
    })
}

/// The samples as CSV: the point, `reachable`, the actuated coordinates, the dexterity,
/// `boundary`.
pub fn positions_to_csv(workspace: &PositionWorkspace) -> String {
    let mut text = "x,y,z,reachable,".to_string();
    for range in &workspace.ranges {
        text += &format!("{},", range.name);
    }
    text += "dexterity,boundary\n";
    let number = |x: Option<f64>| x.map_or(String::new(), |x| format!("{x:e}"));
    for s in &workspace.samples {
        text += &format!(
            "{:e},{:e},{:e},{},",
            s.point[0], s.point[1], s.point[2], s.reachable
        );
        for k in 0..workspace.ranges.len() {
            text += &format!("{},", number(s.actuated.as_ref().map(|a| a[k])));
        }
        text += &format!("{},{}\n", number(s.dexterity), s.boundary);
    }
    text
}
