//! The outputs of a run, observed on the run's own system (`MechanicalSystem::sampling`):
//! declared coordinates continuous with the previous output, energy, momentum, the drives'
//! efforts, the program's outputs and, when asked for, the reactions.

use super::constraints::ReleasedStretch;
use super::sample::Sample;
use super::system::{MechanicalSystem, SystemError};
use crate::dynamics::algorithms::forward_kinematics;
use crate::dynamics::compiled::{EffortScratch, EffortState};
use crate::dynamics::efforts::{potential_energy, Declared};
use crate::dynamics::energy::{kinetic_energy, momentum, Conservative};
use crate::integrate::HermiteSegment;
use crate::prepare::outputs::Outputs;

/// Samples a state: declared coordinates (continuous with the previous sample), energy, momentum
/// and, when asked for, the reactions. An output between two steps comes from the integrator's
/// interpolant: with loops it is projected onto the constraints like the steps are, except
/// inside a stretch integrated with rows set aside (a singular passage, see
/// `constraints::LoopFindings`), where it is interpolated between the stretch's ends instead, once
/// the stretch has ended.
pub(super) struct Sampler<'m> {
    pub(super) conservative: Conservative,
    pub(super) reactions: bool,
    /// The program's outputs, and where their tape is evaluated.
    pub(super) outputs: &'m Outputs,
    pub(super) output_scratch: EffortScratch,
    /// Outputs inside a stretch with rows set aside whose end is not known yet: their time and
    /// the integrator's state there (for the work of the non-conservative efforts).
    pub(super) pending: Vec<(f64, Vec<f64>)>,
    /// The outputs inside such a stretch that could not be interpolated between its ends (the
    /// run ended inside it): only projected, they may be off the branch.
    pub(super) unsettled: Vec<f64>,
    /// The interpolant over the last stretch whose outputs were sampled, and the stretch's
    /// times.
    pub(super) segment: Option<((f64, f64), HermiteSegment)>,
}

impl Sampler<'_> {
    /// The samples of the outputs up to `time`, given the integrator's state there: none while
    /// `time` lies inside a stretch integrated with rows set aside, all those of the stretch
    /// once it has ended.
    pub(super) fn offer(
        &mut self,
        system: &mut MechanicalSystem<'_>,
        time: f64,
        y: &[f64],
    ) -> Result<Vec<Sample>, SystemError> {
        system.sampling(|system| self.offer_with(system, time, y))
    }

    /// `offer`, with the outputs' scratch in place.
    fn offer_with(
        &mut self,
        system: &mut MechanicalSystem<'_>,
        time: f64,
        y: &[f64],
    ) -> Result<Vec<Sample>, SystemError> {
        let mut samples = self.settle(system, false)?;
        if self.released_at(system, time) {
            self.pending.push((time, y.to_vec()));
            samples.extend(self.settle(system, false)?);
        } else {
            samples.push(self.sample(system, time, y)?);
        }
        Ok(samples)
    }

    /// The samples still pending at the end of the run: those of a stretch that ended, or,
    /// when the run ended inside one, the projected outputs (`unsettled`).
    pub(super) fn finish(
        &mut self,
        system: &mut MechanicalSystem<'_>,
    ) -> Result<Vec<Sample>, SystemError> {
        system.sampling(|system| {
            let mut samples = self.settle(system, true)?;
            for (time, y) in std::mem::take(&mut self.pending) {
                self.unsettled.push(time);
                samples.push(self.sample(system, time, &y)?);
            }
            Ok(samples)
        })
    }

    /// Whether an output at `time` lies strictly inside a stretch integrated with rows set
    /// aside (so far: one not ended yet holds every later time).
    fn released_at(&self, system: &MechanicalSystem<'_>, time: f64) -> bool {
        let released = &system.state.loops.released;
        let stretch = released.iter().rev().find(|s| s.entry.0 < time);
        stretch.is_some_and(|s| !s.settled || s.exit.as_ref().is_none_or(|exit| time < exit.0))
    }

    /// The samples of the pending outputs, if their stretch has ended (or the run, `ended`):
    /// the cubic Hermite interpolant between the stretch's ends (`interpolant`). It is not
    /// projected: deep in the passage a projection cannot find the branch, which the ends and
    /// the interpolant follow to their accuracy.
    fn settle(
        &mut self,
        system: &mut MechanicalSystem<'_>,
        ended: bool,
    ) -> Result<Vec<Sample>, SystemError> {
        let Some(&(first, _)) = self.pending.first() else {
            return Ok(Vec::new());
        };
        let stretch = {
            let released = &system.state.loops.released;
            let stretch = released.iter().rev().find(|s| s.entry.0 < first);
            match stretch {
                Some(s) if s.exit.is_some() && (s.settled || ended) => s.clone(),
                _ => return Ok(Vec::new()),
            }
        };
        let exit = stretch.exit.as_ref().map_or(f64::INFINITY, |exit| exit.0);
        let n = system.dimension();
        let mut samples = Vec::new();
        for (time, y) in std::mem::take(&mut self.pending) {
            if time >= exit {
                // After the last state kept, at the end of a run that ended inside the stretch.
                self.unsettled.push(time);
                samples.push(self.sample(system, time, &y)?);
                continue;
            }
            let mut state = vec![0.0; n];
            self.interpolant(system, &stretch)?
                .evaluate(time, &mut state);
            system.measure_loops(time, &state)?;
            samples.push(self.describe(system, time, state, &y[n..])?);
        }
        Ok(samples)
    }

    /// The cubic Hermite interpolant over a stretch with rows set aside, between its ends, each
    /// closed onto every row (its velocities by the constraints' impulse) and given the
    /// derivative of the equations with every row: kept for the stretch's later outputs.
    fn interpolant(
        &mut self,
        system: &mut MechanicalSystem<'_>,
        stretch: &ReleasedStretch,
    ) -> Result<&HermiteSegment, SystemError> {
        let (entry, exit) = (&stretch.entry, stretch.exit.as_ref().expect("an end"));
        let span = (entry.0, exit.0);
        if self
            .segment
            .as_ref()
            .is_none_or(|(cached, _)| *cached != span)
        {
            let n = system.dimension();
            let mut ends = [entry.1.clone(), exit.1.clone()];
            let mut slopes = [vec![0.0; n], vec![0.0; n]];
            for ((time, end), slope) in [entry.0, exit.0]
                .into_iter()
                .zip(&mut ends)
                .zip(&mut slopes)
            {
                system.keep_closed(time, end)?;
                system.derivative(time, end, slope)?;
            }
            let mut segment = HermiteSegment::new(n);
            let [start, end] = &ends;
            let [start_slope, end_slope] = &slopes;
            segment.set(
                entry.0,
                exit.0 - entry.0,
                [start, start_slope, end, end_slope],
            );
            self.segment = Some((span, segment));
        }
        Ok(&self.segment.as_ref().expect("just set").1)
    }

    /// The sample of the integrator's state `y` at `time`, projected onto the loops.
    pub(super) fn sample(
        &mut self,
        system: &mut MechanicalSystem<'_>,
        time: f64,
        y: &[f64],
    ) -> Result<Sample, SystemError> {
        // After the motion, the program's states, then the work of the non-conservative
        // efforts when it is integrated.
        let n = system.dimension();
        let mut state = y[..n].to_vec();
        system.set_states(&y[n..n + system.state_count()]);
        system.keep_closed(time, &mut state)?;
        self.describe(system, time, state, &y[n..])
    }

    /// The sample of a state (positions, velocities) on the loops, with `after` the
    /// integrator's state past the motion: the program's states, then the work when it is
    /// integrated.
    fn describe(
        &mut self,
        system: &mut MechanicalSystem<'_>,
        time: f64,
        mut y: Vec<f64>,
        after: &[f64],
    ) -> Result<Sample, SystemError> {
        let model = system.model;
        let (states, work) = after.split_at(system.state_count());
        let work = work.first().copied();
        system.set_states(states);
        system.ball_rates(&mut y)?;
        let (q, v) = model.split_state(&y);
        let (coordinates, rates) = model.declared((time, &q, v), &system.state.reference)?;
        let reactions = if self.reactions {
            system.reactions(time, &q, v)?
        } else {
            Vec::new()
        };
        // The drives' efforts (the coordinates', then the position drives' forces): the
        // multipliers of their rows in the equations at the sample; then the states' values.
        // The drives' efforts, and the model that outputs may read, are those of an evaluation.
        let points = 3 * model.position_drives.len();
        let columns = model.drives.len() + points + states.len() + self.outputs.names.len();
        let mut outputs = Vec::with_capacity(columns);
        if !model.drives.is_empty() || points > 0 || self.outputs.reads_model {
            let mut rates = vec![0.0; y.len()];
            system.derivative(time, &y, &mut rates)?;
            outputs.extend_from_slice(&system.scratch.drive_efforts);
            outputs.extend_from_slice(&system.scratch.point_forces);
        }
        outputs.extend_from_slice(states);
        let scratch = &mut *system.scratch;
        let model_values = scratch
            .model_laws
            .as_ref()
            .map_or(&[][..], |r| &r.values[..]);
        let data = &mut scratch.data;
        forward_kinematics(model, data, &q, v)?;
        let h = momentum(model, data);
        let declared = Declared {
            model,
            coordinates: &coordinates,
            rates: &rates,
            states,
        };
        // `+ 0.0` turns a −0 into 0 for the outputs.
        let potential = potential_energy(model, data, &self.conservative, &declared, time)? + 0.0;
        let kinetic = kinetic_energy(model, data);
        let state = EffortState {
            world: &data.world,
            velocity: &data.velocity,
            coordinates: &coordinates,
            rates: &rates,
            states,
            time,
            model: model_values,
        };
        outputs.extend(self.outputs.values(&state, &mut self.output_scratch));
        Ok(Sample {
            time,
            coordinates,
            rates,
            kinetic_energy: kinetic,
            potential_energy: Some(potential),
            work: work.map(|w| w + 0.0),
            balance: work.map(|w| kinetic + potential - w),
            momentum: [h[0], h[1], h[2], h[3], h[4], h[5]],
            reactions,
            outputs,
        })
    }
}
