//! Joint friction during a run (see `dynamics::friction`): the slipping joints' efforts, and the
//! events that switch a joint between slipping and sticking. The events of a run are the
//! stops' (see `impacts`), then one per joint with friction.

use std::cell::RefCell;
use std::rc::Rc;

use nalgebra::DVector;

use super::system::{MechanicalSystem, SharedPhases, SystemError};
use crate::dynamics::friction::{Phase, Switch};

impl MechanicalSystem<'_> {
    /// Adds the slipping joints' friction efforts at rates `v` to the generalised forces
    /// `free`; their power.
    pub(super) fn add_friction(&self, v: &[f64], free: &mut DVector<f64>) -> f64 {
        let mut power = 0.0;
        for (friction, phase) in self.model.frictions.iter().zip(&self.phases) {
            if let Phase::Slipping(direction) = *phase {
                let rate = v[friction.velocity];
                let effort = friction.slipping_effort(direction, rate);
                free[friction.velocity] += effort;
                power += effort * rate;
            }
        }
        power
    }

    /// The number of events of a run: the stops', then the frictions'.
    pub fn event_total(&self) -> usize {
        self.model.stops.len() + self.model.frictions.len()
    }

    /// Every event function at (t, y): the stops' (`stop_events`), then per joint with
    /// friction, s q̇ while it slips in direction s (its rate reaching zero), F_c − |λ| while it
    /// sticks held by λ (the holding force reaching F_c).
    pub fn event_values(
        &mut self,
        t: f64,
        y: &[f64],
        values: &mut [f64],
    ) -> Result<(), SystemError> {
        let (stops, frictions) = values.split_at_mut(self.model.stops.len());
        self.stop_events(t, y, stops)?;
        if self.phases.contains(&Phase::Sticking) {
            let mut dydt = vec![0.0; y.len()];
            self.derivative(t, y, &mut dydt)?;
        }
        let v = &y[self.model.positions()..];
        for (k, value) in frictions.iter_mut().enumerate() {
            let friction = &self.model.frictions[k];
            *value = match self.phases[k] {
                // Without dry friction the phase never changes.
                _ if friction.dry == 0.0 => 1.0,
                Phase::Slipping(direction) => direction * v[friction.velocity],
                Phase::Sticking => friction.dry - self.holding[k].abs(),
            };
        }
        Ok(())
    }

    /// Event `index` at time t (numbered as by `event_values`).
    pub fn act_on_event(&mut self, t: f64, y: &mut [f64], index: usize) -> Result<(), SystemError> {
        let stops = self.model.stops.len();
        let acted = match index < stops {
            true => self.stop_event(t, y, index),
            false => self.switch_friction(t, y, index - stops),
        };
        self.publish_phases();
        acted
    }

    /// The phases and resting stops of this system, shared from now on with the systems that
    /// mirror them (`mirror_phases`): the sampler's, whose outputs that depend on the
    /// accelerations (the reactions) must see a sticking joint held as the run does.
    pub fn share_phases(&mut self) -> Rc<RefCell<SharedPhases>> {
        let shared = self.shared_phases.get_or_insert_with(Rc::default).clone();
        self.publish_phases();
        shared
    }

    /// Mirrors from now on the phases another system shares (`share_phases`).
    pub fn mirror_phases(&mut self, shared: Rc<RefCell<SharedPhases>>) {
        self.shared_phases = Some(shared);
    }

    /// Writes this system's phases to the shared ones.
    fn publish_phases(&self) {
        if let Some(shared) = &self.shared_phases {
            let mut shared = shared.borrow_mut();
            shared.phases.clone_from(&self.phases);
            shared.resting.clone_from(&self.resting);
        }
    }

    /// Takes the shared phases (those of the integrated system at the last event).
    pub fn adopt_phases(&mut self) {
        if let Some(shared) = &self.shared_phases {
            let shared = shared.borrow();
            self.phases.clone_from(&shared.phases);
            self.resting.clone_from(&shared.resting);
        }
    }

    /// The phase of every joint with friction at the start (t, y): slipping with the sign of a
    /// non-zero rate, and from rest sticking or slipping as the holding force says.
    pub fn start_friction(&mut self, t: f64, y: &mut [f64]) -> Result<(), SystemError> {
        let positions = self.model.positions();
        for k in 0..self.model.frictions.len() {
            let rate = y[positions + self.model.frictions[k].velocity];
            self.phases[k] = match rate {
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
        self.phases[k] = match self.phases[k] {
            Phase::Sticking => Phase::Slipping(-self.holding_force(t, y, k)?.signum()),
            Phase::Slipping(_) => self.phase_from_rest(t, y, k)?,
        };
        let friction = &model.frictions[k];
        self.switches.push(Switch {
            time: t,
            coordinate: friction.coordinate.clone(),
            position: y[friction.position],
            phase: self.phases[k],
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
        let phase = std::mem::replace(&mut self.phases[k], Phase::Sticking);
        let mut dydt = vec![0.0; y.len()];
        let result = self.derivative(t, y, &mut dydt);
        self.phases[k] = phase;
        result.map(|()| self.holding[k])
    }
}
