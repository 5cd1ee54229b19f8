//! The stops of a mechanism during a run: their event functions (the distance of each stopped
//! coordinate to its bound), and the impact where one is reached, recorded for the report.

use serde::Serialize;

use super::system::{MechanicalSystem, SystemError};
use crate::dynamics::algorithms::{crba, forward_kinematics};
use crate::dynamics::energy::kinetic_energy;
use crate::dynamics::stops::{impact_velocities, Side};

/// Below this approach rate (coordinate units per second) after an impact, a coordinate pushed
/// against its stop rests on it: a contact that lasts, which the run does not model.
pub const RESTING_RATE: f64 = 1e-8;

/// One impact on a stop, as the run report gives it.
#[derive(Clone, Debug, Serialize)]
pub struct Impact {
    pub time: f64,
    /// `swing.q`, and which of its bounds (at `bound`) was hit.
    pub coordinate: String,
    pub side: Side,
    pub bound: f64,
    pub restitution: f64,
    /// The coordinate's rate just before and just after the impact.
    pub rate_before: f64,
    pub rate_after: f64,
    /// The mechanism's kinetic energy just before and just after.
    pub kinetic_before: f64,
    pub kinetic_after: f64,
}

impl MechanicalSystem<'_> {
    /// The stops' event functions at the state y: each stopped coordinate's distance to its
    /// bound, positive inside the range.
    pub fn stop_distances(&self, y: &[f64], values: &mut [f64]) {
        for (value, stop) in values.iter_mut().zip(&self.model.stops) {
            *value = stop.distance(y);
        }
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
        let after = impact_velocities(stop, &mass, None, &v).ok_or_else(|| {
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
        };
        self.impacts.push(impact);
        if stop.approach(v_after) > -RESTING_RATE {
            self.refuse_resting(t, y, index)?;
        }
        Ok(())
    }

    /// Stops the run when the coordinate of stop `index`, at rest on it after an impact, is
    /// pushed into it; lets the run go on when the motion leaves the stop.
    fn refuse_resting(&mut self, t: f64, y: &[f64], index: usize) -> Result<(), SystemError> {
        let model = self.model;
        let stop = &model.stops[index];
        let mut dydt = vec![0.0; y.len()];
        self.derivative(t, y, &mut dydt)?;
        let acceleration = &dydt[model.positions()..];
        if stop.approach(acceleration) > 0.0 {
            return Err(SystemError::Impact(format!(
                "`{}` comes to rest on its {} stop ({}) at t = {t}: a lasting contact, which the \
                 simulation does not model; give the stop a restitution above 0, or end the run before",
                stop.coordinate,
                side_name(stop.side),
                stop.bound
            )));
        }
        Ok(())
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
