//! The stops of a mechanism during a run: their event functions (the distance of each stopped
//! coordinate to its bound), and the impact where one is reached, recorded for the report.

use nalgebra::DVector;

use super::system::{MechanicalSystem, SystemError};
use crate::dynamics::algorithms::{crba, forward_kinematics};
use crate::dynamics::energy::kinetic_energy;
use crate::dynamics::friction::Phase;
use crate::dynamics::mimics;
use crate::dynamics::stops::{impact_velocities, Impact, Side};

/// Below this approach rate (coordinate units per second) after an impact, a coordinate pushed
/// against its stop rests on it: a contact that lasts, which the run does not model.
pub const RESTING_RATE: f64 = 1e-8;

impl MechanicalSystem<'_> {
    /// The stops' event functions at (t, y): each free coordinate's distance to its bound,
    /// positive inside the range; for a coordinate resting on its stop, the contact force,
    /// positive while the stop pushes.
    pub fn stop_events(
        &mut self,
        t: f64,
        y: &[f64],
        values: &mut [f64],
    ) -> Result<(), SystemError> {
        if self.resting.contains(&true) {
            let mut dydt = vec![0.0; y.len()];
            self.derivative(t, y, &mut dydt)?;
        }
        for (k, (value, stop)) in values.iter_mut().zip(&self.model.stops).enumerate() {
            *value = match self.resting[k] {
                true => self.contact[k],
                false => stop.distance(y),
            };
        }
        Ok(())
    }

    /// The event of stop `index` at time t: the release of a resting coordinate, or else an
    /// impact.
    pub fn stop_event(&mut self, t: f64, y: &mut [f64], index: usize) -> Result<(), SystemError> {
        match self.resting[index] {
            true => {
                self.resting[index] = false;
                Ok(())
            }
            false => self.impact(t, y, index),
        }
    }

    /// Holds the coordinates at rest, on their stops or stuck by their friction, and with loops
    /// the mimic couplings (see `system::couplings`): adds to the accelerations `a` (at q) the
    /// response P Eᵀ λ to the forces λ that keep the held rows E's accelerations zero, and
    /// records λ.
    pub(super) fn hold_resting(
        &mut self,
        q: &[f64],
        a: &mut DVector<f64>,
    ) -> Result<(), SystemError> {
        let model = self.model;
        let (rows, couplings) = self.held_rows();
        if rows.nrows() == 0 {
            return Ok(());
        }
        let (change, forces) = self.held_change(q, &rows, &(&rows * &*a))?;
        *a += change;
        let stops = (0..model.stops.len()).filter(|&k| self.resting[k]);
        let frictions = (0..model.frictions.len()).filter(|&k| self.phases[k] == Phase::Sticking);
        let mut forces = forces.iter().skip(couplings);
        for (k, force) in stops.zip(forces.by_ref()) {
            // A lower stop pushes the coordinate up, an upper one down.
            self.contact[k] = match model.stops[k].side {
                Side::Lower => *force,
                Side::Upper => -*force,
            };
        }
        for (k, force) in frictions.zip(forces) {
            self.holding[k] = *force;
        }
        Ok(())
    }

    /// The impact on stop `index` at time t: the velocities of y jump so that the stopped
    /// coordinate's rate is reversed and scaled by the restitution, the impulse acting through
    /// the mass matrix. A coordinate that then rests against its stop, pushed into it, stops
    /// the run with an error (lasting contact is not modelled).
    pub fn impact(&mut self, t: f64, y: &mut [f64], index: usize) -> Result<(), SystemError> {
        let model = self.model;
        let stop = &model.stops[index];
        let (q, v) = model.split_state(y);
        let v = v.to_vec();
        let mass = crba(model, &mut self.data, &q)?;
        let kinetic_before = self.kinetic_energy_at(&q, &v)?;
        let couplings = (!model.mimics.is_empty()).then(|| mimics::rows(&model.mimics, model.nv));
        let after = impact_velocities(stop, &mass, couplings.as_ref(), &v).ok_or_else(|| {
            SystemError::Impact(format!(
                "the impact on the {} stop of `{}` has no solution (no inertia along it)",
                side_name(stop.side),
                stop.coordinate
            ))
        })?;
        let positions = model.positions();
        y[positions..positions + after.len()].copy_from_slice(after.as_slice());
        // The event was located past the bound by at most the time resolution: the coordinate
        // starts again from the bound itself, so that the next crossing begins at zero.
        y[stop.position] = stop.bound;
        mimics::restore(&model.mimics, y, positions, stop.velocity);
        let v_after = &y[positions..positions + after.len()];
        let impact = Impact {
            time: t,
            coordinate: stop.coordinate.clone(),
            side: stop.side,
            bound: stop.bound,
            restitution: stop.restitution,
            rate_before: v[stop.velocity],
            rate_after: after[stop.velocity],
            kinetic_before,
            kinetic_after: self.kinetic_energy_at(&q, v_after)?,
            rests: false,
        };
        self.impacts.push(impact);
        if stop.approach(v_after) > -RESTING_RATE && self.pushed_into(t, y, index)? {
            // Too slow to leave: the coordinate rests on the stop from now on.
            y[positions + stop.velocity] = 0.0;
            mimics::restore(&model.mimics, y, positions, stop.velocity);
            self.resting[index] = true;
            if let Some(last) = self.impacts.last_mut() {
                last.rests = true;
            }
        }
        Ok(())
    }

    /// Whether the motion at (t, y) accelerates the coordinate of stop `index` into it.
    fn pushed_into(&mut self, t: f64, y: &[f64], index: usize) -> Result<bool, SystemError> {
        let model = self.model;
        let mut dydt = vec![0.0; y.len()];
        self.derivative(t, y, &mut dydt)?;
        Ok(model.stops[index].approach(&dydt[model.positions()..]) > 0.0)
    }

    fn kinetic_energy_at(&mut self, q: &[f64], v: &[f64]) -> Result<f64, SystemError> {
        forward_kinematics(self.model, &mut self.data, q, v)?;
        Ok(kinetic_energy(self.model, &self.data))
    }
}

fn side_name(side: Side) -> &'static str {
    match side {
        Side::Lower => "lower",
        Side::Upper => "upper",
    }
}
