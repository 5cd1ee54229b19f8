//! A run's sampling instants (`let u = sample(period, x0); update u = f;`): a discrete-time
//! controller evaluated at its period, its states held between instants (a zero-order hold).
//! The run's steps are cut at every instant so that each lands on it exactly (as
//! [`Simulator::advance_to`](super::simulator::Simulator::advance_to) lands on a time), whatever the
//! integrator; there every sampled state due takes its update's value at the state reached,
//! x\[k+1\] = f(x\[k\], measurements at t_k), all of them from the values before the instant, and
//! the integrator starts again from the new state. An output at an instant shows the values
//! held up to it; the report lists every instant with the values it set.

use serde::Serialize;

use super::system::{MechanicalSystem, SystemError};
use crate::dynamics::model::Model;

/// The sampled states of a run and the instants passed.
#[derive(Debug)]
pub(super) struct SamplingClock {
    /// Each sampled state's index among the model's states, its period, and how many of its
    /// instants have passed (its next is at (passed + 1) · period: times by multiplication,
    /// so that rounding does not accumulate over a long run).
    sampled: Vec<(usize, f64, u64)>,
    instants: Vec<SamplingInstant>,
}

/// One sampling instant: its time, and the sampled states' values it set (every sampled
/// state's, in the order of [`SamplingReport::states`]; those not due keep theirs).
#[derive(Clone, Debug, Serialize)]
pub struct SamplingInstant {
    pub time: f64,
    pub values: Vec<f64>,
}

/// The sampling of a run: the sampled states, their periods and every instant the run passed.
#[derive(Clone, Debug, Serialize)]
pub struct SamplingReport {
    pub states: Vec<String>,
    pub periods: Vec<f64>,
    pub instants: Vec<SamplingInstant>,
}

impl SamplingClock {
    /// The clock of `model`'s sampled states, none without them.
    pub(super) fn new(model: &Model) -> Option<SamplingClock> {
        let sampled: Vec<(usize, f64, u64)> = (model.states.iter().enumerate())
            .filter_map(|(k, state)| state.sampling.map(|s| (k, s.period, 0)))
            .collect();
        (!sampled.is_empty()).then_some(SamplingClock {
            sampled,
            instants: Vec::new(),
        })
    }

    /// The next instant of each sampled state.
    fn next_instants(&self) -> impl Iterator<Item = f64> + '_ {
        (self.sampled.iter()).map(|&(_, period, passed)| (passed + 1) as f64 * period)
    }

    /// Where a step towards `t_end` must end: `t_end`, or the next instant before it.
    pub(super) fn landing(&self, t_end: f64) -> f64 {
        self.next_instants().fold(t_end, f64::min)
    }

    /// At time `t`, with the integrator's state `y` (the mechanism's, the states' values after
    /// it, then the work when tracked): when `t` is an instant, the updates of the sampled
    /// states due set in `y`, and true.
    pub(super) fn sample(
        &mut self,
        system: &mut MechanicalSystem<'_>,
        t: f64,
        y: &mut [f64],
    ) -> Result<bool, SystemError> {
        let due: Vec<bool> = self.next_instants().map(|instant| instant == t).collect();
        if !due.contains(&true) {
            return Ok(false);
        }
        let offset = system.dimension();
        let mut updates = vec![0.0; system.state_count()];
        system.sampled_updates(t, y, &mut updates)?;
        for ((k, _, passed), due) in self.sampled.iter_mut().zip(due) {
            if due {
                y[offset + *k] = updates[*k];
                *passed += 1;
            }
        }
        let values = (self.sampled.iter()).map(|&(k, _, _)| y[offset + k]);
        self.instants.push(SamplingInstant {
            time: t,
            values: values.collect(),
        });
        Ok(true)
    }

    /// What the report says of the sampling.
    pub(super) fn report(&mut self, model: &Model) -> SamplingReport {
        SamplingReport {
            states: (self.sampled.iter())
                .map(|&(k, _, _)| model.states[k].name.clone())
                .collect(),
            periods: self.sampled.iter().map(|&(_, period, _)| period).collect(),
            instants: std::mem::take(&mut self.instants),
        }
    }
}
