//! Singular configurations along a run or a drag (`lsdc kinematics --along`): both measures of
//! `kinematic_models` at every sample, and the singular passages located in time as events.
//!
//! Near a configuration where a measure vanishes transversally it is |f(t)| for a smooth f (a
//! singular value through zero), so a passage shows in the samples as a local minimum. With
//! the samples' signs flipped past it, the cubic through the two samples on each side has its
//! root t₀ between them; the minimum is a passage when that cubic also gives the sample at the
//! minimum (to a tenth of its neighbours' measures), which a smooth minimum away from zero does
//! not. A sample below the tolerance is an event too. The samples need not fall on t₀.

use serde::Serialize;

use super::configurations::Declared;
use super::kinematic_models::{
    models_at, Actuation, KinematicsError, Output, SingularKind, SingularMotion,
};
use crate::dynamics::model::Model;

/// Both measures at one sample.
#[derive(Clone, Debug, Serialize)]
pub struct SampleMeasures {
    pub time: f64,
    pub type1_measure: f64,
    pub type2_measure: f64,
    pub kind: Option<SingularKind>,
}

/// A singular passage.
#[derive(Clone, Debug, Serialize)]
pub struct SingularEvent {
    /// Where the measure passes through zero (or the sample below the tolerance).
    pub time: f64,
    pub kind: SingularKind,
    /// The measure there (0 at a passage between samples) and at the nearest sample.
    pub measure: f64,
    pub sampled_measure: f64,
    /// The motion the singularity lets through, at the nearest sample.
    pub motion: Option<SingularMotion>,
}

#[derive(Clone, Debug, Serialize)]
pub struct Scan {
    pub tolerance: f64,
    pub samples: Vec<SampleMeasures>,
    pub events: Vec<SingularEvent>,
}

/// The measures at every sample and the singular passages between them.
pub fn scan(
    model: &Model,
    actuation: &Actuation,
    output: &Output,
    samples: &[Declared],
    tolerance: f64,
) -> Result<Scan, KinematicsError> {
    let mut measured = Vec::with_capacity(samples.len());
    let mut motions = Vec::with_capacity(samples.len());
    for (index, sample) in samples.iter().enumerate() {
        let (q, _) = model
            .state_from_declared(&sample.coordinates, &sample.rates)
            .map_err(|e| KinematicsError::State {
                index,
                message: format!("cannot read the coordinates: {e:?}"),
            })?;
        let rates = vec![0.0; actuation.velocities.len()];
        let models = models_at(model, actuation, output, &q, &rates, tolerance)?;
        let s = models.singularity;
        measured.push(SampleMeasures {
            time: sample.time,
            type1_measure: s.type1_measure,
            type2_measure: s.type2_measure,
            kind: s.kind,
        });
        motions.push(s.weakest_motions);
    }
    let mut events = Vec::new();
    let kinds = [SingularKind::Type1, SingularKind::Type2];
    for (which, kind) in kinds.into_iter().enumerate() {
        let series: Vec<(f64, f64)> = (measured.iter())
            .map(|m| (m.time, [m.type1_measure, m.type2_measure][which]))
            .collect();
        for (index, time, measure) in passages(&series, tolerance) {
            let motion = motions[index][which].clone();
            events.push(SingularEvent {
                time,
                kind,
                measure,
                sampled_measure: series[index].1,
                motion,
            });
        }
    }
    events.sort_by(|a, b| a.time.total_cmp(&b.time));
    Ok(Scan {
        tolerance,
        samples: measured,
        events,
    })
}

/// The local minima of a series (time, measure) that are passages through zero, or below
/// `tolerance`: (nearest sample, time, measure there).
fn passages(series: &[(f64, f64)], tolerance: f64) -> Vec<(usize, f64, f64)> {
    let mut found = Vec::new();
    for i in 0..series.len() {
        let here = series[i].1;
        let before = i.checked_sub(1).map(|j| series[j].1);
        let after = series.get(i + 1).map(|s| s.1);
        let lowest = before.is_none_or(|b| here < b) && after.is_none_or(|a| here <= a);
        if !lowest {
            continue;
        }
        if here < tolerance {
            found.push((i, series[i].0, here));
        } else if let Some(time) = passage(series, i) {
            found.push((i, time, 0.0));
        }
    }
    found
}

/// The time of the passage through zero at the local minimum i, if it is one (see the
/// module's comment).
fn passage(series: &[(f64, f64)], i: usize) -> Option<f64> {
    if i < 2 || i + 2 >= series.len() {
        return None;
    }
    let points: Vec<(f64, f64)> = [i - 2, i - 1, i + 1, i + 2]
        .iter()
        .enumerate()
        .map(|(k, &j)| (series[j].0, if k < 2 { series[j].1 } else { -series[j].1 }))
        .collect();
    // The cubic through the four signed samples (Lagrange).
    let cubic = |t: f64| {
        (0..4)
            .map(|a| {
                let weight: f64 = (0..4)
                    .filter(|&b| b != a)
                    .map(|b| (t - points[b].0) / (points[a].0 - points[b].0))
                    .product();
                weight * points[a].1
            })
            .sum::<f64>()
    };
    let scale = series[i - 1].1.min(series[i + 1].1);
    if (cubic(series[i].0).abs() - series[i].1).abs() > 0.1 * scale {
        return None;
    }
    // Its root between the neighbours (positive before, negative after), by bisection.
    let (mut low, mut high) = (series[i - 1].0, series[i + 1].0);
    for _ in 0..60 {
        let middle = 0.5 * (low + high);
        if cubic(middle) > 0.0 {
            low = middle;
        } else {
            high = middle;
        }
    }
    Some(0.5 * (low + high))
}
