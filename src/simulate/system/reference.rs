//! The run's reference angles follow its steps: at the end of each accepted step, the angles
//! recovered from quaternions (spherical and free joints) are taken on the branch and turn that
//! the reference's rates predict (`dynamics::angles::AngleReference`), and become the
//! reference. Kept from one output to the next instead, an angle that advanced more than π
//! between two outputs lost a turn (a top at 60 rad/s sampled every 0.05 s), and the angles
//! depended on `--every`; chosen by nearness alone at each step, the middle angle took its
//! mirror branch at a gimbal passage (its outer angles, fast there, jumped by π).
//!
//! The prediction is the trapezoid from the rates at both ends, exact for an angle whose rate
//! is steady. Where an angle's rate changes within the step by so much that its prediction may
//! be off by a quarter turn, the step is followed in shorter intervals on the cubic Hermite
//! interpolant of its ends (Hairer, Nørsett and Wanner, Solving ODEs I, II.6).

use super::{MechanicalSystem, SystemError};
use crate::dynamics::model::{DeclaredState, Recovered};
use crate::integrate::HermiteSegment;
use std::f64::consts::FRAC_PI_2;

/// Most intervals a step is followed in.
const MOST_INTERVALS: usize = 64;

impl MechanicalSystem<'_> {
    /// Sets the reference at the state y at time t, the start of the run (nearest the
    /// declared starting values, which keep their turns).
    pub fn start_reference(&mut self, t: f64, y: &[f64]) -> Result<(), SystemError> {
        self.state.reference.time = t;
        self.state.reference.rates.fill(0.0);
        self.state.reference_state.clear();
        self.follow_reference(t, y)
    }

    /// Moves the reference to the end (t, y) of an accepted step (see the module); nothing for
    /// a mechanism without recovered angles.
    pub fn follow_reference(&mut self, t: f64, y: &[f64]) -> Result<(), SystemError> {
        let model = self.model;
        if model.recovered_angles().next().is_none() {
            return Ok(());
        }
        // The spare storage of the reference (nothing is allocated once it held one).
        let spare = std::mem::take(&mut self.scratch.next_reference);
        let mut next = self.declared_at(t, y, spare)?;
        let intervals = self.intervals(&next, t);
        if intervals > 1 {
            let segment = self.segment_to(t, y)?;
            let start = self.state.reference.time;
            let mut inner = vec![0.0; y.len()];
            for k in 1..intervals {
                let time = start + (t - start) * k as f64 / intervals as f64;
                segment.evaluate(time, &mut inner);
                next = self.declared_at(time, &inner, next)?;
                self.adopt(time, &inner, &mut next);
            }
            next = self.declared_at(t, y, next)?;
        }
        self.adopt(t, y, &mut next);
        self.scratch.next_reference = next;
        Ok(())
    }

    /// The declared coordinates and rates at (t, y) against the reference, in `into`'s storage.
    fn declared_at(
        &mut self,
        t: f64,
        y: &[f64],
        mut into: DeclaredState,
    ) -> Result<DeclaredState, SystemError> {
        let model = self.model;
        let mut q = std::mem::take(&mut self.scratch.positions);
        let v = model.split_state_into(y, &mut q);
        let reference = &self.state.reference;
        let found = model.declared_into((t, &q, v), reference, &mut into, Recovered::Every);
        self.scratch.positions = q;
        found?;
        Ok(into)
    }

    /// Makes `next` at (t, y) the reference, giving back the old one's storage in `next`.
    fn adopt(&mut self, t: f64, y: &[f64], next: &mut DeclaredState) {
        let reference = &mut self.state.reference;
        reference.time = t;
        std::mem::swap(&mut reference.coordinates, &mut next.coordinates);
        std::mem::swap(&mut reference.rates, &mut next.rates);
        self.state.reference_state.clear();
        self.state.reference_state.extend_from_slice(y);
    }

    /// In how many intervals the step from the reference to `next` at t is to be followed: one
    /// unless a recovered angle's rate changed by more than a quarter turn per interval.
    fn intervals(&self, next: &DeclaredState, t: f64) -> usize {
        let reference = &self.state.reference;
        let elapsed = (t - reference.time).abs();
        let change = (self.model.recovered_angles())
            .map(|i| (next.rates[i] - reference.rates[i]).abs() * elapsed)
            .fold(0.0, f64::max);
        let known = self.state.reference_state.len() == self.dimension();
        match change > FRAC_PI_2 && known {
            true => ((change / FRAC_PI_2).ceil() as usize).min(MOST_INTERVALS),
            false => 1,
        }
    }

    /// The cubic Hermite interpolant from the reference's state to (t, y), their derivatives
    /// evaluated with the outputs' scratch (the integrator's caches stay as its steps left
    /// them).
    fn segment_to(&mut self, t: f64, y: &[f64]) -> Result<HermiteSegment, SystemError> {
        let start = self.state.reference.time;
        let from = self.state.reference_state.clone();
        let (mut slope_from, mut slope_to) = (vec![0.0; y.len()], vec![0.0; y.len()]);
        self.sampling(|system| {
            system.derivative(start, &from, &mut slope_from)?;
            system.derivative(t, y, &mut slope_to)
        })?;
        let mut segment = HermiteSegment::new(y.len());
        segment.set(start, t - start, [&from, &slope_from, y, &slope_to]);
        Ok(segment)
    }
}
