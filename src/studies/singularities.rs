//! Singular configurations along a run or a drag (`lsdc kinematics --along`): both measures of
//! `kinematic_models` at every sample, and the singular passages located in time as events.
//!
//! Near a configuration where a measure vanishes transversally it behaves as |t − t₀| (a
//! singular value through zero), so a passage shows in the samples as a local minimum: the two
//! lines through the two samples on each side of it meet at (t₀, m₀). A passage is an event
//! when m₀ is below the tolerance, and the samples need not fall on it.

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
    /// Where the lines through the samples on either side meet.
    pub time: f64,
    pub kind: SingularKind,
    /// The measure there (extrapolated) and at the nearest sample.
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
        motions.push((s.type1_motion, s.type2_motion));
    }
    let mut events = Vec::new();
    let kinds = [SingularKind::Type1, SingularKind::Type2];
    for (which, kind) in kinds.into_iter().enumerate() {
        let series: Vec<(f64, f64)> = (measured.iter())
            .map(|m| (m.time, [m.type1_measure, m.type2_measure][which]))
            .collect();
        for (index, time, measure) in passages(&series, tolerance) {
            let motion = match kind {
                SingularKind::Type1 => motions[index].0.clone(),
                _ => motions[index].1.clone(),
            };
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

/// The local minima of a series (time, measure) whose passage, extrapolated from the two
/// samples on each side, reaches below `tolerance`: (nearest sample, time, measure there).
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
            continue;
        }
        // The minimum lies between samples i − 1 and i + 1: meet the line through samples
        // i − 2, i − 1 (or i − 1, i) with the line through i + 1, i + 2 (or i, i + 1).
        let Some((t, m)) = meeting(series, i) else {
            continue;
        };
        if m < tolerance {
            found.push((i, t, m.max(0.0)));
        }
    }
    found
}

/// Where the falling line before sample i meets the rising line after it.
fn meeting(series: &[(f64, f64)], i: usize) -> Option<(f64, f64)> {
    let line = |a: usize, b: usize| {
        let ((ta, ma), (tb, mb)) = (series[a], series[b]);
        let slope = (mb - ma) / (tb - ta);
        (slope, ma - slope * ta)
    };
    let left = if i >= 2 {
        line(i - 2, i - 1)
    } else {
        line(i.checked_sub(1)?, i)
    };
    let right = if i + 2 < series.len() {
        line(i + 1, i + 2)
    } else {
        line(i, (i + 1 < series.len()).then_some(i + 1)?)
    };
    let ((s1, c1), (s2, c2)) = (left, right);
    if !(s1 < 0.0 && s2 > 0.0) {
        return None;
    }
    let t = (c2 - c1) / (s1 - s2);
    // Only a meeting between the neighbouring samples locates this minimum.
    let lower = series[i.saturating_sub(1)].0;
    let upper = series[(i + 1).min(series.len() - 1)].0;
    (lower..=upper).contains(&t).then_some((t, s1 * t + c1))
}
