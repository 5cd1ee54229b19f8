//! The workspace of a point (`lsdc workspace`): the actuated coordinates sampled on a grid
//! within their ranges (cell centres), the loops closed at each with the actuated ones held
//! (the forward geometric model, from the neighbouring sample: the grid is walked back and
//! forth so that each sample starts from the one before and stays on its assembly mode), and
//! at each sample the point, the dexterity (condition number of the inverse velocity model) and
//! both singularity measures.
//!
//! The measure of the reachable set (a volume for three actuated coordinates, an area for two,
//! a length for one) is the integral over the reachable actuated box of √det(JᵀJ), J the
//! direct velocity model (|det J| for a square J): the midpoint rule on the cells, exact in
//! the limit where the map is one-to-one (one assembly mode; a fold would count the region it
//! covers twice). The boundary is the samples with an unreachable neighbour or on the box's
//! faces; a singular locus crosses the workspace between two reachable neighbours where det J
//! changes sign, or at a sample found singular.

use serde::Serialize;

use super::configurations::{close_from, point_of, StateRequest};
use super::kinematic_models::{models_at, Actuation, KinematicsError, Output};
use crate::prepare::Prepared;

/// An actuated coordinate's sampled range.
#[derive(Clone, Debug, Serialize)]
pub struct Range {
    pub name: String,
    pub low: f64,
    pub high: f64,
}

/// The ranges of the actuated coordinates: those given (`name`, low, high), else the
/// coordinate's two stops.
pub fn ranges(
    prepared: &Prepared,
    actuation: &Actuation,
    given: &[(String, f64, f64)],
) -> Result<Vec<Range>, String> {
    for (name, _, _) in given {
        if !actuation.names.contains(name) {
            return Err(format!(
                "`--range {name}=…` names no actuated coordinate (actuated: {})",
                actuation.names.join(", ")
            ));
        }
    }
    (actuation.names.iter())
        .map(|name| {
            if let Some((_, low, high)) = given.iter().find(|(n, _, _)| n == name) {
                return Ok(Range {
                    name: name.clone(),
                    low: *low,
                    high: *high,
                });
            }
            let bounds: Vec<f64> = (prepared.model.stops.iter())
                .filter(|s| s.coordinate == *name)
                .map(|s| s.bound)
                .collect();
            match bounds.as_slice() {
                [a, b] => Ok(Range {
                    name: name.clone(),
                    low: a.min(*b),
                    high: a.max(*b),
                }),
                _ => Err(format!(
                    "`{name}` has no stops on both sides: give its range with `--range {name}=LOW:HIGH`"
                )),
            }
        })
        .collect()
}

/// One sample of the grid.
#[derive(Clone, Debug, Serialize)]
pub struct WorkspaceSample {
    pub actuated: Vec<f64>,
    pub reachable: bool,
    /// The point (when reachable).
    pub point: Option<[f64; 3]>,
    /// Condition number of the inverse velocity model (lengths in L); `None` when singular or
    /// unreachable.
    pub dexterity: Option<f64>,
    pub type1_measure: Option<f64>,
    pub type2_measure: Option<f64>,
    /// √det(JᵀJ) of the direct model.
    pub jacobian_measure: Option<f64>,
    pub boundary: bool,
    pub singular: bool,
    #[serde(skip)]
    determinant_sign: f64,
}

/// A singular locus between two neighbouring samples (or at one).
#[derive(Clone, Debug, Serialize)]
pub struct Crossing {
    /// The two samples' indices.
    pub between: [usize; 2],
    /// The point halfway.
    pub point: [f64; 3],
}

#[derive(Clone, Debug, Serialize)]
pub struct Workspace {
    pub point: String,
    pub ranges: Vec<Range>,
    pub samples_per_coordinate: usize,
    /// m³ for three actuated coordinates (m² for two, m for one).
    pub volume: f64,
    pub reachable: usize,
    pub boundary: usize,
    pub crossings: Vec<Crossing>,
    pub samples: Vec<WorkspaceSample>,
}

/// Samples the workspace of `output`'s point on a grid of `count` cells per actuated coordinate.
pub fn sample(
    prepared: &Prepared,
    actuation: &Actuation,
    output: &Output,
    ranges: &[Range],
    count: usize,
    tolerance: f64,
) -> Result<Workspace, KinematicsError> {
    let dimension = ranges.len();
    let total = count.pow(dimension as u32);
    let widths: Vec<f64> = ranges
        .iter()
        .map(|r| (r.high - r.low) / count as f64)
        .collect();
    let mut samples: Vec<Option<WorkspaceSample>> = vec![None; total];
    let mut start = prepared.coordinates.clone();
    for step in 0..total {
        let digits = back_and_forth(step, count, dimension);
        let actuated: Vec<f64> = (0..dimension)
            .map(|d| ranges[d].low + (digits[d] as f64 + 0.5) * widths[d])
            .collect();
        let request = StateRequest {
            coordinates: (ranges.iter().map(|r| r.name.clone()))
                .zip(actuated.iter().copied())
                .collect(),
            ..Default::default()
        };
        let index = flat(&digits, count);
        let closed = close_from(prepared, &start, &request, &output.frame);
        let sample = match closed {
            Err(_) => unreachable_sample(actuated),
            Ok(declared) => {
                start.clone_from(&declared.coordinates);
                let model = &prepared.model;
                let (q, _) = model.state_from_declared(&declared.coordinates, &declared.rates)?;
                let rates = vec![0.0; actuation.velocities.len()];
                let models = models_at(model, actuation, output, &q, &rates, tolerance)?;
                let point = point_of(prepared, &output.frame, &declared.coordinates)?;
                let j = nalgebra::DMatrix::from_fn(models.direct.len(), dimension, |r, c| {
                    models.direct[r][c]
                });
                let gram = (j.transpose() * &j).determinant();
                let sign = if j.is_square() {
                    j.determinant().signum()
                } else {
                    1.0
                };
                WorkspaceSample {
                    actuated,
                    reachable: true,
                    point: Some(point),
                    dexterity: models.inverse_condition,
                    type1_measure: Some(models.singularity.type1_measure),
                    type2_measure: Some(models.singularity.type2_measure),
                    jacobian_measure: Some(gram.max(0.0).sqrt()),
                    boundary: false,
                    singular: models.singularity.kind.is_some(),
                    determinant_sign: sign,
                }
            }
        };
        samples[index] = Some(sample);
    }
    let mut samples: Vec<WorkspaceSample> = samples
        .into_iter()
        .map(|s| s.expect("every cell visited"))
        .collect();
    let cell: f64 = widths.iter().product();
    let volume = samples
        .iter()
        .filter_map(|s| s.jacobian_measure)
        .sum::<f64>()
        * cell.abs();
    let mut crossings = Vec::new();
    for index in 0..total {
        let digits = unflat(index, count, dimension);
        let mut boundary = false;
        for d in 0..dimension {
            if digits[d] == 0 || digits[d] + 1 == count {
                boundary = true;
            }
            for delta in [-1i64, 1] {
                let moved = digits[d] as i64 + delta;
                if moved < 0 || moved >= count as i64 {
                    continue;
                }
                let mut other = digits.clone();
                other[d] = moved as usize;
                let neighbour = &samples[flat(&other, count)];
                if !neighbour.reachable {
                    boundary = true;
                } else if delta == 1 && samples[index].reachable {
                    let here = &samples[index];
                    if here.determinant_sign != neighbour.determinant_sign || here.singular {
                        let (a, b) = (
                            here.point.unwrap_or_default(),
                            neighbour.point.unwrap_or_default(),
                        );
                        crossings.push(Crossing {
                            between: [index, flat(&other, count)],
                            point: std::array::from_fn(|k| 0.5 * (a[k] + b[k])),
                        });
                    }
                }
            }
        }
        samples[index].boundary = boundary && samples[index].reachable;
    }
    Ok(Workspace {
        point: output.frame.name.clone(),
        ranges: ranges.to_vec(),
        samples_per_coordinate: count,
        volume,
        reachable: samples.iter().filter(|s| s.reachable).count(),
        boundary: samples.iter().filter(|s| s.boundary).count(),
        crossings,
        samples,
    })
}

fn unreachable_sample(actuated: Vec<f64>) -> WorkspaceSample {
    WorkspaceSample {
        actuated,
        reachable: false,
        point: None,
        dexterity: None,
        type1_measure: None,
        type2_measure: None,
        jacobian_measure: None,
        boundary: false,
        singular: false,
        determinant_sign: 0.0,
    }
}

/// The grid indices of step `step` of a walk that goes back and forth (boustrophedon): each
/// step changes one index by one, so each sample starts from its neighbour's configuration.
pub(crate) fn back_and_forth(step: usize, count: usize, dimension: usize) -> Vec<usize> {
    let mut digits = unflat(step, count, dimension);
    // The last index runs fastest; it runs backwards when the indices before it sum to odd.
    for d in (0..dimension).rev() {
        let before: usize = digits[..d].iter().sum();
        if before % 2 == 1 {
            digits[d] = count - 1 - digits[d];
        }
    }
    digits
}

/// The indices (first slowest) of a flat index.
pub(crate) fn unflat(mut index: usize, count: usize, dimension: usize) -> Vec<usize> {
    let mut digits = vec![0; dimension];
    for d in (0..dimension).rev() {
        digits[d] = index % count;
        index /= count;
    }
    digits
}

pub(crate) fn flat(digits: &[usize], count: usize) -> usize {
    digits.iter().fold(0, |flat, &d| flat * count + d)
}

/// The samples as CSV: the actuated coordinates, `reachable`, the point, the dexterity, both
/// measures, `boundary`, `singular`.
pub fn to_csv(workspace: &Workspace) -> String {
    let mut text: String = workspace
        .ranges
        .iter()
        .map(|r| format!("{},", r.name))
        .collect();
    text += "reachable,x,y,z,dexterity,type1_measure,type2_measure,boundary,singular\n";
    let number = |x: Option<f64>| x.map_or(String::new(), |x| format!("{x:e}"));
    for s in &workspace.samples {
        for a in &s.actuated {
            text += &format!("{a:e},");
        }
        let [x, y, z] = s.point.map_or([None; 3], |p| p.map(Some));
        text += &format!(
            "{},{},{},{},{},{},{},{},{}\n",
            s.reachable,
            number(x),
            number(y),
            number(z),
            number(s.dexterity),
            number(s.type1_measure),
            number(s.type2_measure),
            s.boundary,
            s.singular
        );
    }
    text
}
