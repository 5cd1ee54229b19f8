//! The stops of a mechanism during a run: their event functions (the distance of each stopped
//! coordinate to its bound), and the impact where one is reached, recorded for the report.

use nalgebra::DVector;

use super::{MechanicalSystem, SystemError};
use crate::dynamics::algorithms::forward_kinematics;
use crate::dynamics::energy::kinetic_energy;
use crate::dynamics::mimics;
use crate::dynamics::rows::{impact_velocities, HeldRow, Holder};
use crate::dynamics::stops::{Impact, Side};

/// Below this rate of leaving (coordinate units per second) after an impact, a coordinate
/// pushed against its stop rests on it.
pub const RESTING_RATE: f64 = 1e-8;

/// A coordinate pushed against its stop that would rise less than this above its bound after
/// an impact (relative to max(1, |bound|)) rests on it (`comes_to_rest`).
pub const RESTING_HEIGHT: f64 = 1e-14;

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
        if self.state.resting.contains(&true) {
            let mut dydt = vec![0.0; y.len()];
            self.derivative(t, y, &mut dydt)?;
        }
        for (k, (value, stop)) in values.iter_mut().zip(&self.model.stops).enumerate() {
            *value = match self.state.resting[k] {
                true => self.scratch.contact[k],
                false => stop.distance(y),
            };
        }
        Ok(())
    }

    /// The event of stop `index` at time t: the release of a resting coordinate, or else an
    /// impact.
    pub fn stop_event(&mut self, t: f64, y: &mut [f64], index: usize) -> Result<(), SystemError> {
        match self.state.resting[index] {
            true => {
                self.state.resting[index] = false;
                Ok(())
            }
            false => self.impact(t, y, index),
        }
    }

    /// The impact on stop `index` at time t: the velocities of y jump so that the stopped
    /// coordinate's rate is reversed and scaled by the restitution, the impulse acting through
    /// the mass matrix with the constraint rows kept (`impact_on_stack`). A coordinate that
    /// then leaves too slowly while the motion pushes it into its stop rests on it.
    pub fn impact(&mut self, t: f64, y: &mut [f64], index: usize) -> Result<(), SystemError> {
        let model = self.model;
        let stop = &model.stops[index];
        let positions = model.positions();
        let (q, v) = model.split_state(y);
        let v = v.to_vec();
        let kinetic_before = self.kinetic_energy_at(&q, &v)?;
        // The event was located past the bound by at most the time resolution: the coordinate
        // starts again from the bound itself, so that the next crossing begins at zero. With
        // loops or contacts the positions move onto the stack's rows (the drives' laws among
        // them) and the bounds together.
        let constrained = model.has_loops() || model.has_contacts();
        if constrained {
            self.close_for_impact(t, y, index)?;
        }
        let (q, _) = model.split_state(y);
        let mut after = vec![0.0; v.len()];
        if !self.impact_on_stack(t, &q, &v, index, &mut after)? {
            return Err(SystemError::Impact(format!(
                "the impact on the {} stop of `{}` has no solution (no inertia along it)",
                side_name(stop.side),
                stop.coordinate
            )));
        }
        y[positions..].copy_from_slice(&after);
        if !constrained {
            y[stop.position] = stop.bound;
            mimics::restore(&model.mimics, y, positions, stop.velocity);
        }
        let v_after = y[positions..].to_vec();
        let impact = Impact {
            time: t,
            coordinate: stop.coordinate.clone(),
            side: stop.side,
            bound: stop.bound,
            restitution: stop.restitution,
            rate_before: v[stop.velocity],
            rate_after: after[stop.velocity],
            kinetic_before,
            kinetic_after: self.kinetic_energy_at(&q, &v_after)?,
            rests: false,
        };
        self.state.impacts.push(impact);
        if self.comes_to_rest(t, y, index)? {
            // Too slow to leave: the coordinate rests on the stop from now on.
            self.state.resting[index] = true;
            if constrained {
                self.keep_stacked(t, y)?;
            } else {
                y[positions + stop.velocity] = 0.0;
                mimics::restore(&model.mimics, y, positions, stop.velocity);
            }
            if let Some(last) = self.state.impacts.last_mut() {
                last.rests = true;
            }
        }
        Ok(())
    }

    /// Whether the coordinate of stop `index`, just after an impact at (t, y), rests on the
    /// stop: the motion accelerates it into the stop, and it leaves too slowly to matter,
    /// below `RESTING_RATE` or too slowly to rise `RESTING_HEIGHT` above the bound before the
    /// motion brings it back (its flight's height v² / 2a). Below that height the bounces are
    /// lost in the positions' round-off: the coordinate returns one unit in the last place past
    /// the bound, having gained the rate of that fall, and would bounce on forever.
    fn comes_to_rest(&mut self, t: f64, y: &[f64], index: usize) -> Result<bool, SystemError> {
        let model = self.model;
        let stop = &model.stops[index];
        let leaving = -stop.approach(&y[model.positions()..]);
        let mut dydt = vec![0.0; y.len()];
        self.derivative(t, y, &mut dydt)?;
        let pushed = stop.approach(&dydt[model.positions()..]);
        let height = RESTING_HEIGHT * stop.bound.abs().max(1.0);
        Ok(pushed > 0.0 && (leaving < RESTING_RATE || leaving * leaving < 2.0 * pushed * height))
    }

    /// The velocities just after an impact on stop `index` at (t, q), from `v`, into `after`:
    /// the stop's row joins the constraint stack (`dynamics::rows`) with its rate after,
    /// −e times the one before, the drives' rows to their laws' rates and every other row
    /// brought to rest (the loops' and a tree's couplings by X, the stack's contacts' and
    /// couplings' with loops as rows), solved on the
    /// response X formed at q. The same velocities as the saddle-point system
    /// [M −Gᵀ −eₖ; G 0 0; eₖᵀ 0 0] of every row (`tests/suite/stops.rs` checks the two against
    /// each other). Whether the result is finite.
    fn impact_on_stack(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
        index: usize,
        after: &mut [f64],
    ) -> Result<bool, SystemError> {
        let model = self.model;
        let stop = &model.stops[index];
        self.stacked_geometry(t, q, v)?;
        let row = HeldRow {
            velocity: stop.velocity,
            holder: Holder::Impact {
                index,
                rate_after: -stop.restitution * v[stop.velocity],
            },
        };
        // The rows X keeps (the loops', a tree's couplings) are brought to rest first, by the
        // change of least kinetic metric, v ← X M v: the event is located between steps, where
        // the velocities are off the loops' rows by the integrator's error (4.8e-10 on
        // `limited_four_bar`), and the impulse keeps those rows as they are.
        let mut kept_rows = DVector::from_column_slice(v);
        if model.has_loops() || !model.mimics.is_empty() {
            let tree = DVector::from_column_slice(&v[..model.nv]);
            kept_rows.fill(0.0);
            (kept_rows.rows_mut(0, model.nv)).gemv(1.0, &self.scratch.mass, &tree, 0.0);
            self.scratch.response.apply_vector(&mut kept_rows);
        }
        // The drives keep their laws' rates through the impulse; the stop's row is last.
        self.gather_held(t);
        let mut held = self.drive_rows().to_vec();
        held.push(row);
        let couplings = self.coupling_count();
        let kept = self.state.contact_rows.as_deref().unwrap_or_default();
        let scratch = &mut *self.scratch;
        let stack = &mut scratch.velocity_stack;
        let points = &scratch.point_state;
        stack.arrange(kept, couplings, points, &held);
        stack.gather(&scratch.contact_state, &model.mimics, points);
        let all = &scratch.contact_state;
        let response = &mut scratch.response;
        Ok(impact_velocities(
            stack,
            response,
            all,
            &model.mimics,
            points,
            kept_rows.as_slice(),
            after,
        ))
    }

    fn kinetic_energy_at(&mut self, q: &[f64], v: &[f64]) -> Result<f64, SystemError> {
        forward_kinematics(self.model, &mut self.scratch.data, q, v)?;
        Ok(kinetic_energy(self.model, &self.scratch.data))
    }
}

fn side_name(side: Side) -> &'static str {
    match side {
        Side::Lower => "lower",
        Side::Upper => "upper",
    }
}
