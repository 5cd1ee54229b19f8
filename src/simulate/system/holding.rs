//! Coordinates held at rest during a run, on their stops (resting on a bound) or stuck by their
//! friction: each adds the row eₖᵀ a = 0 to the equations of motion, with a force μₖ along the
//! coordinate found with the accelerations. On a tree, the forces solve
//! (E P Eᵀ) μ = −E a with P the response to generalised forces (M⁻¹, or with the mimic
//! couplings kept), and so they do with closed loops, P being the response along the loops'
//! allowed motions; with contacts, the held rows join the contacts' rows in their saddle-point
//! system (`stops::held_accelerations`).

use nalgebra::DVector;

use super::{MechanicalSystem, SystemError};
use crate::dynamics::algorithms::crba_into;
use crate::dynamics::dense::solve_in_place;
use crate::dynamics::friction::Phase;
use crate::dynamics::stops::Side;

impl MechanicalSystem<'_> {
    /// Holds the coordinates at rest, on their stops or stuck by their friction: adds to the
    /// accelerations `a` (at q) the response to the forces that keep those coordinates'
    /// accelerations zero, and records the forces (`contact`, `holding`).
    pub(super) fn hold_resting(
        &mut self,
        q: &[f64],
        a: &mut DVector<f64>,
    ) -> Result<(), SystemError> {
        let model = self.model;
        if model.has_loops() {
            // The mimic couplings are held rows there too, held even when nothing rests.
            self.hold_on_response(q, a)?;
            self.record_holding();
            return Ok(());
        }
        let mut rows = std::mem::take(&mut self.hold.rows);
        rows.clear();
        let stops = (0..model.stops.len()).filter(|&k| self.resting[k]);
        let frictions = (0..model.frictions.len()).filter(|&k| self.phases[k] == Phase::Sticking);
        rows.extend(stops.map(|k| model.stops[k].velocity));
        rows.extend(frictions.map(|k| model.frictions[k].velocity));
        let held = match rows.is_empty() {
            true => Ok(()),
            false if model.has_contacts() => self.hold_with_constraints(&rows, a),
            false if !model.mimics.is_empty() || has_repeats(&rows) => self.hold_on_response(q, a),
            false => self.hold_on_tree(q, &rows, a),
        };
        let count = rows.len();
        self.hold.rows = rows;
        held?;
        if count > 0 {
            self.record_holding();
        }
        Ok(())
    }

    /// `hold_resting` on a tree without couplings, each velocity held once: P = M⁻¹, from the
    /// factor the accelerations took when they came from the mass matrix, else from CRBA here.
    fn hold_on_tree(
        &mut self,
        q: &[f64],
        rows: &[usize],
        a: &mut DVector<f64>,
    ) -> Result<(), SystemError> {
        let model = self.model;
        self.hold.size_for(model.nv, rows.len());
        // `mass_accelerations` factored M at this state unless native code gave them.
        let factored = self.needs_mass_matrix() && self.native.is_none();
        if !factored {
            crba_into(model, &mut self.data, q, &mut self.hold.mass)?;
            if !self.hold.factor.factor(&self.hold.mass) {
                return Err(SystemError::SingularMassMatrix);
            }
        }
        let hold = &mut self.hold;
        let factor = if factored {
            &self.mass_factor
        } else {
            &hold.factor
        };
        hold.responses.fill(0.0);
        for (column, &row) in rows.iter().enumerate() {
            hold.responses[(row, column)] = 1.0;
        }
        factor.solve_mut(&mut hold.responses);
        for (i, &row) in rows.iter().enumerate() {
            for j in 0..rows.len() {
                hold.coupling[(i, j)] = hold.responses[(row, j)];
            }
            hold.forces[i] = -a[row];
        }
        // E M⁻¹ Eᵀ is positive definite: distinct coordinates of a positive definite M.
        solve_in_place(&mut hold.coupling, &mut hold.forces)
            .map_err(|_| SystemError::SingularMassMatrix)?;
        a.gemv(1.0, &hold.responses, &hold.forces, 1.0);
        Ok(())
    }

    /// `hold_resting` through the response P of the accelerations (`held_change`): in a
    /// mechanism with loops (the loops' allowed motions, with the mimic couplings as rows), or on
    /// a tree with mimic couplings (P = S (Sᵀ M S)⁻¹ Sᵀ) or a velocity held twice (a stop and a
    /// friction on one coordinate). The forces come from a rank-revealing solve, since a
    /// follower held with its leader gives two rows for one coupled motion; the couplings'
    /// forces are not recorded. This path allocates.
    fn hold_on_response(&mut self, q: &[f64], a: &mut DVector<f64>) -> Result<(), SystemError> {
        let (rows, couplings) = self.held_rows();
        if rows.nrows() == 0 {
            self.hold.forces = DVector::zeros(0);
            return Ok(());
        }
        let (change, forces) = self.held_change(q, &rows, &(&rows * &*a))?;
        *a += change;
        self.hold.forces = forces
            .rows(couplings, forces.len() - couplings)
            .clone_owned();
        Ok(())
    }

    /// The held forces of the last `hold_resting`, in the order of its rows (the resting stops,
    /// then the sticking frictions), into each stop's contact force (positive while it pushes)
    /// and each friction's holding force.
    fn record_holding(&mut self) {
        let model = self.model;
        let mut forces = self.hold.forces.iter();
        let stops = (0..model.stops.len()).filter(|&k| self.resting[k]);
        for (k, force) in stops.zip(forces.by_ref()) {
            // A lower stop pushes the coordinate up, an upper one down.
            self.contact[k] = match model.stops[k].side {
                Side::Lower => *force,
                Side::Upper => -*force,
            };
        }
        let frictions = (0..model.frictions.len()).filter(|&k| self.phases[k] == Phase::Sticking);
        for (k, force) in frictions.zip(forces) {
            self.holding[k] = *force;
        }
    }

    /// The held forces found by the constrained path (`stop_rows`), for `record_holding`.
    pub(super) fn set_held_forces(&mut self, forces: DVector<f64>) {
        self.hold.forces = forces;
    }
}

/// Whether a velocity appears twice among `rows` (few rows: a quadratic scan).
fn has_repeats(rows: &[usize]) -> bool {
    (0..rows.len()).any(|i| rows[i + 1..].contains(&rows[i]))
}
