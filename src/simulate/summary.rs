//! What a run's report says of its outputs as a whole (energy drift and balance, momentum drift,
//! the energies at the end), gathered output by output as the samples are produced, so that a
//! long run need not keep them.

use super::branch;
use super::sample::{MomentumDrift, Sample};
use crate::dynamics::joint::JointType;
use crate::dynamics::model::Model;

/// The largest change of a quantity since the first output, and the scale it is measured
/// against.
#[derive(Default)]
struct Drift {
    first: Option<f64>,
    /// Whether every output so far had the quantity.
    complete: bool,
    largest_change: f64,
    scale: f64,
}

impl Drift {
    /// Takes the quantity at one more output, and the size of the energies there.
    fn add(&mut self, outputs_before: usize, value: Option<f64>, size: f64) {
        if outputs_before == 0 {
            self.first = value;
            self.complete = true;
            self.scale = value.map_or(0.0, f64::abs);
        }
        self.scale = self.scale.max(size);
        match (value, self.first) {
            (Some(value), Some(first)) => {
                self.largest_change = self.largest_change.max((value - first).abs());
            }
            _ => self.complete = false,
        }
    }

    /// The largest change relative to the scale; `None` unless every output had the quantity.
    fn relative(&self) -> Option<f64> {
        self.first?;
        if self.scale == 0.0 {
            return Some(0.0);
        }
        self.complete.then(|| self.largest_change / self.scale)
    }
}

/// The report's figures over the outputs so far.
pub(super) struct Summary {
    outputs: usize,
    energy: Drift,
    balance: Drift,
    /// The total momentum at the first output and its largest changes, when nothing outside
    /// acts on the mechanism.
    momentum: Option<([f64; 6], MomentumDrift)>,
    tracks_momentum: bool,
    last: Option<Sample>,
    /// Whether every effort derives from a potential (else the energy is not conserved).
    conservative: bool,
    /// What the check of singular passages needs of every output (three numbers each), for a
    /// mechanism with loops.
    branch: Option<Vec<branch::Output>>,
}

impl Summary {
    /// `conservative`: whether every effort derives from a potential, so that the energy is
    /// conserved and its drift is reported.
    pub(super) fn new(model: &Model, conservative: bool) -> Self {
        Summary {
            outputs: 0,
            energy: Drift::default(),
            balance: Drift::default(),
            momentum: None,
            tracks_momentum: isolated(model),
            last: None,
            conservative,
            branch: model.has_loops().then(Vec::new),
        }
    }

    pub(super) fn add(&mut self, sample: &Sample) {
        let kinetic = sample.kinetic_energy;
        let energy = (sample.potential_energy)
            .filter(|_| self.conservative)
            .map(|p| p + kinetic);
        self.energy.add(self.outputs, energy, kinetic.abs());
        let work = sample.work.unwrap_or(0.0);
        let potential = sample.balance.unwrap_or(0.0) - kinetic + work;
        let size = kinetic.abs().max(work.abs()).max(potential.abs());
        self.balance.add(self.outputs, sample.balance, size);
        if self.tracks_momentum {
            self.add_momentum(&sample.momentum);
        }
        if let Some(outputs) = &mut self.branch {
            outputs.push(branch::Output {
                time: sample.time,
                conserved: sample.balance.or(energy),
                kinetic,
            });
        }
        self.outputs += 1;
        self.last = Some(sample.clone());
    }

    fn add_momentum(&mut self, momentum: &[f64; 6]) {
        let (first, drift) = self.momentum.get_or_insert((
            *momentum,
            MomentumDrift {
                linear: 0.0,
                angular: 0.0,
            },
        ));
        let change = |range: std::ops::Range<usize>| {
            range
                .map(|i| (momentum[i] - first[i]).abs())
                .fold(0.0, f64::max)
        };
        drift.angular = drift.angular.max(change(0..3));
        drift.linear = drift.linear.max(change(3..6));
    }

    /// Largest |E(t) − E(0)| over the outputs relative to the larger of |E(0)| and the largest
    /// kinetic energy, when the efforts are conservative (at least two outputs).
    pub(super) fn energy_drift(&self) -> Option<f64> {
        (self.outputs >= 2)
            .then(|| self.energy.relative())
            .flatten()
    }

    /// The largest change of kinetic + potential − work, over the largest of those energies.
    pub(super) fn energy_balance(&self) -> Option<f64> {
        self.balance.relative()
    }

    pub(super) fn momentum_drift(&self) -> Option<MomentumDrift> {
        (self.outputs >= 2).then_some(self.momentum?.1)
    }

    /// The last output.
    pub(super) fn last(&self) -> Option<&Sample> {
        self.last.as_ref()
    }

    /// Kinetic, potential and work at the last output, when the work is integrated.
    pub(super) fn final_energies(&self) -> Option<[f64; 3]> {
        let s = self.last.as_ref()?;
        Some([
            s.kinetic_energy,
            s.balance? - s.kinetic_energy + s.work?,
            s.work?,
        ])
    }

    /// The outputs as the check of singular passages reads them (mechanisms with loops).
    pub(super) fn branch_outputs(&self) -> &[branch::Output] {
        self.branch.as_deref().unwrap_or(&[])
    }
}

/// Whether nothing outside acts on the mechanism: its root joints are free and no effort is
/// applied, so its total momentum is conserved.
fn isolated(model: &Model) -> bool {
    let free = model
        .joints
        .iter()
        .filter(|j| j.parent == 0)
        .all(|j| matches!(j.kind, JointType::Free { .. }));
    free && model.applied.is_empty() && model.gravity == nalgebra::Vector3::zeros()
}
