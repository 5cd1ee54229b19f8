//! The blocks 2 to 4 of the constraint stack (`stack`), which an evaluation solves on the
//! response X of the first (`rows::RowStack`): the
//! contacts' kept rows, the mimic couplings with closed loops, and the coordinates held: driven
//! by their laws (eₖᵀ a = d̈ₖ(t)), on their stops (resting on a bound) or stuck by their
//! friction (eₖᵀ a = 0), each with a force μₖ along the coordinate. Whatever the mechanism (a
//! tree, closed loops, contacts or both), they are solved together in one saddle-point system;
//! the held forces are handed back to what holds them: the events' (`contact`, `holding`) and
//! the drives' efforts, with their power (the work a drive does counts in the energy balance).

use nalgebra::DVector;

use super::{MechanicalSystem, SystemError};
use crate::dynamics::algorithms::forward_kinematics;
use crate::dynamics::contacts;
use crate::dynamics::friction::Phase;
use crate::dynamics::rows::{HeldRow, Holder};
use crate::dynamics::stops::Side;

impl MechanicalSystem<'_> {
    /// Solves the rows at (t, q, v) from the accelerations `a` of the base solve (the loops'
    /// block, or the tree's), which they replace; records the contacts' forces, the held forces
    /// and the drives' efforts. Called by `solve_stack` only.
    pub(super) fn solve_rows(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
        a: &mut DVector<f64>,
    ) -> Result<(), SystemError> {
        let model = self.model;
        if self.drives_by_subtrees() {
            // The drives are the only rows there (`DrivenSubtrees::find`), and the hybrid
            // dynamics solved them.
            return Ok(());
        }
        self.gather_held(t);
        let couplings = self.coupling_count();
        let points = !model.position_drives.is_empty();
        if !model.has_contacts() && couplings == 0 && self.scratch.held.is_empty() && !points {
            return Ok(());
        }
        self.form_response_at(q)?;
        if model.has_contacts() && model.has_loops() {
            // The loops' solve leaves the kinematics for its own rows: the contacts' start anew.
            forward_kinematics(model, &mut self.scratch.data, q, v)?;
            self.contact_rows_here(v, true)?;
        }
        if points {
            // The response's mass matrix leaves the kinematics of q only.
            forward_kinematics(model, &mut self.scratch.data, q, v)?;
            self.point_rows_here(t, v, true);
        }
        self.decide_contact_rows();
        let kept = self.state.contact_rows.as_deref().unwrap_or_default();
        let rows = &mut self.scratch.rows;
        let point_state = &self.scratch.point_state;
        rows.arrange(kept, couplings, point_state, &self.scratch.held);
        rows.gather(&self.scratch.contact_state, &model.mimics, point_state);
        let solved = (self.scratch.rows).solve(
            model,
            &self.scratch.contact_state,
            &mut self.scratch.response,
            a,
        );
        solved.map_err(|unsettled| SystemError::SingularContact {
            contact: model.contacts[unsettled.contact].name.clone(),
            row: contacts::CONTACT_ROW_NAMES[2],
        })?;
        a.copy_from(&self.scratch.rows.accelerations);
        let forces = &self.scratch.rows.contact_forces;
        self.scratch.efforts.power +=
            contacts::friction_power(model, &self.scratch.contact_state, forces);
        self.record_holding(v);
        Ok(())
    }

    /// The mimic couplings solved as rows: with closed loops (a tree's response keeps them).
    pub(super) fn coupling_count(&self) -> usize {
        match self.model.has_loops() {
            true => self.model.mimics.len(),
            false => 0,
        }
    }

    /// The coordinates held at time `t` into `held`: the driven ones' (their laws evaluated at
    /// t), then those the state holds (`rows_the_state_holds`).
    pub(super) fn gather_held(&mut self, t: f64) {
        let model = self.model;
        let mut held = std::mem::take(&mut self.scratch.held);
        held.clear();
        let values = &mut self.scratch.law_values;
        held.extend(
            (model.drives.iter().enumerate())
                .map(|(index, drive)| HeldRow::driven(index, drive, drive.evaluate(t, values))),
        );
        held.extend(self.rows_the_state_holds());
        self.scratch.held = held;
    }

    /// Whether no coordinate is held at this state: no drive, and none the state holds
    /// (`gather_held` would gather no row).
    pub(super) fn holds_nothing(&self) -> bool {
        self.model.drives.is_empty() && self.rows_the_state_holds().next().is_none()
    }

    /// The rows held by the run's state rather than by a law of time: the stops the
    /// coordinates rest on, then the joints whose friction sticks.
    fn rows_the_state_holds(&self) -> impl Iterator<Item = HeldRow> + '_ {
        let model = self.model;
        let frictions =
            (0..model.frictions.len()).filter(|&k| self.state.phases[k] == Phase::Sticking);
        let sticking = frictions.map(|index| HeldRow {
            velocity: model.frictions[index].velocity,
            holder: Holder::Friction { index },
        });
        self.resting_stop_rows().chain(sticking)
    }

    /// The held rows of the stops the run's coordinates rest on.
    fn resting_stop_rows(&self) -> impl Iterator<Item = HeldRow> + '_ {
        let model = self.model;
        let resting = (0..model.stops.len()).filter(|&k| self.state.resting[k]);
        resting.map(|index| HeldRow::on_stop(index, &model.stops[index]))
    }

    /// The contact rows of the run, decided at the first state evaluated (from the contacts'
    /// rows and the response formed there), then kept.
    pub(super) fn decide_contact_rows(&mut self) {
        let model = self.model;
        if model.has_contacts() && self.state.contact_rows.is_none() {
            let kept = contacts::independent_rows(
                model,
                &mut self.scratch.response,
                &self.scratch.contact_state,
            );
            self.state.contact_rows = Some(kept);
        }
        let kept = self.state.contact_rows.as_deref().unwrap_or_default();
        self.scratch.normal_rows.clear();
        self.scratch
            .normal_rows
            .extend(kept.iter().copied().filter(|r| r % 3 == 2));
    }

    /// The driven coordinates' rows among the held ones (`gather_held` puts them first).
    pub(super) fn drive_rows(&self) -> &[HeldRow] {
        &self.scratch.held[..self.model.drives.len()]
    }

    /// The held forces of the last solve, in the order of the held rows, into each drive's
    /// effort (with their power at the velocities `v`), each stop's contact force (positive
    /// while it pushes) and each friction's holding force.
    fn record_holding(&mut self, v: &[f64]) {
        let model = self.model;
        self.scratch.drive_power = 0.0;
        // A position drive's force at its frame's origin, times the origin's velocity J v.
        let points = &self.scratch.point_state;
        let forces = self.scratch.rows.point_forces();
        for (i, &force) in forces.iter().enumerate() {
            let rate = points.velocity[i] + points.laws[i / 3][i % 3].rate;
            self.scratch.drive_power += force * rate;
        }
        self.scratch.point_forces.copy_from_slice(forces);
        for (row, force) in self.scratch.rows.held_forces() {
            match row.holder {
                Holder::Drive { index, .. } => {
                    self.scratch.drive_efforts[index] = force;
                    self.scratch.drive_power += force * v[row.velocity];
                }
                // A lower stop pushes the coordinate up, an upper one down.
                Holder::Stop { index, .. } => {
                    self.scratch.contact[index] = match model.stops[index].side {
                        Side::Lower => force,
                        Side::Upper => -force,
                    }
                }
                Holder::Friction { index } => self.scratch.holding[index] = force,
                // An impact's row is solved at its event, never among an evaluation's rows.
                Holder::Impact { .. } => {}
            }
        }
    }

    /// The accelerations of the run's equations at (t, q, v), every row solved, leaving the
    /// contacts' rows and forces and the forward kinematics of (q, v) in place: for the
    /// reactions.
    pub(super) fn solve_every_row(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
    ) -> Result<DVector<f64>, SystemError> {
        let mut rates = vec![0.0; self.dimension()];
        self.derivative_at(t, q, v, &mut rates)?;
        forward_kinematics(self.model, &mut self.scratch.data, q, v)?;
        Ok(DVector::from_column_slice(&rates[self.model.positions()..]))
    }
}
