//! Joint friction during a run (see `dynamics::friction`): the slipping joints' efforts, and the
//! events that switch a joint between slipping and sticking. The events of a run are the
//! stops' (see `impacts`), then one per joint with friction.

use nalgebra::DVector;

use super::{MechanicalSystem, SystemError};
use crate::dynamics::friction::{Phase, Switch};

impl MechanicalSystem<'_> {
    /// Adds the slipping and the driven joints' friction efforts at rates `v` to the
    /// generalised forces `free`; their power.
    pub(super) fn add_friction(&self, v: &[f64], free: &mut DVector<f64>) -> f64 {
        let mut power = 0.0;
        for (friction, phase) in self.model.frictions.iter().zip(&self.state.phases) {
            let rate = v[friction.velocity];
            let effort = match *phase {
                _ if friction.driven => friction.driven_effort(rate),
                Phase::Slipping(direction) => friction.slipping_effort(direction, rate),
                Phase::Sticking => continue,
            };
            free[friction.velocity] += effort;
            power += effort * rate;
        }
        power
    }

    /// The number of events of a run: the stops', then the frictions'.
    pub fn event_total(&self) -> usize {
        self.model.stops.len() + self.model.frictions.len()
    }

    /// Every event function at (t, y): the stops' (`stop_events`), then per joint with
    /// friction, s q̇ while it slips in direction s (its rate reaching zero), F_c − |λ| while it
    /// sticks held by λ (the holding force reaching F_c); a driven joint's never changes sign.
    pub fn event_values(
        &mut self,
        t: f64,
        y: &[f64],
        values: &mut [f64],
    ) -> Result<(), SystemError> {
        let (stops, frictions) = values.split_at_mut(self.model.stops.len());
        self.stop_events(t, y, stops)?;
        if self.state.phases.contains(&Phase::Sticking) {
            let mut dydt = vec![0.0; y.len()];
            self.derivative(t, y, &mut dydt)?;
        }
        let v = &y[self.model.positions()..];
        for (k, value) in frictions.iter_mut().enumerate() {
            let friction = &self.model.frictions[k];
            *value = match self.state.phases[k] {
                // Without dry friction, or under a drive, the phase never changes.
                _ if friction.dry == 0.0 || friction.driven => 1.0,
                Phase::Slipping(direction) => direction * v[friction.velocity],
                Phase::Sticking => friction.dry - self.scratch.holding[k].abs(),
            };
        }
        Ok(())
    }

    /// Event `index` at time t (numbered as by `event_values`).
    pub fn act_on_event(&mut self, t: f64, y: &mut [f64], index: usize) -> Result<(), SystemError> {
        let stops = self.model.stops.len();
        match index < stops {
            true => self.stop_event(t, y, index),
            false => self.switch_friction(t, y, index - stops),
        }
    }

    /// The phase of every joint with friction at the start (t, y): slipping with the sign of a
    /// non-zero rate, and from rest sticking or slipping as the holding force says. A driven
    /// joint is never held as sticking (its friction follows its rate, `add_friction`).
    pub fn start_friction(&mut self, t: f64, y: &mut [f64]) -> Result<(), SystemError> {
        let positions = self.model.positions();
        for k in 0..self.model.frictions.len() {
            let friction = &self.model.frictions[k];
            let rate = y[positions + friction.velocity];
            self.state.phases[k] = match rate {
                _ if friction.driven => Phase::Slipping(1.0),
                0.0 => self.phase_from_rest(t, y, k)?,
                rate => Phase::Slipping(rate.signum()),
            };
        }
        Ok(())
    }

    /// A slipping joint whose rate reached zero sticks or slips back; a sticking joint whose
    /// holding force reached F_c slips the way the unbalanced effort drives it.
    fn switch_friction(&mut self, t: f64, y: &mut [f64], k: usize) -> Result<(), SystemError> {
        let model = self.model;
        let positions = model.positions();
        let velocity = model.frictions[k].velocity;
        // The event was located past the rate's zero by at most the time resolution.
        y[positions + velocity] = 0.0;
        crate::dynamics::mimics::restore(&model.mimics, y, positions, velocity);
        self.state.phases[k] = match self.state.phases[k] {
            Phase::Sticking => Phase::Slipping(-self.holding_force(t, y, k)?.signum()),
            Phase::Slipping(_) => self.phase_from_rest(t, y, k)?,
        };
        let friction = &model.frictions[k];
        self.state.switches.push(Switch {
            time: t,
            coordinate: friction.coordinate.clone(),
            position: y[friction.position],
            phase: self.state.phases[k],
        });
        Ok(())
    }

    /// The phase of joint k at rest in state y: sticking while the force that holds it is
    /// within F_c, else slipping as that force's opposite.
    fn phase_from_rest(&mut self, t: f64, y: &[f64], k: usize) -> Result<Phase, SystemError> {
        let hold = self.holding_force(t, y, k)?;
        Ok(self.model.frictions[k].phase_at(0.0, hold))
    }

    /// The force that holds joint k at rest in state y, the other joints in their phases.
    fn holding_force(&mut self, t: f64, y: &[f64], k: usize) -> Result<f64, SystemError> {
        let phase = std::mem::replace(&mut self.state.phases[k], Phase::Sticking);
        let mut dydt = vec![0.0; y.len()];
        let result = self.derivative(t, y, &mut dydt);
        self.state.phases[k] = phase;
        result.map(|()| self.scratch.holding[k])
    }
}
