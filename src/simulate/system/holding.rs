//! The rows an evaluation solves on the response X after the base solve (`rows::RowStack`): the
//! contacts' kept rows, the mimic couplings with closed loops, the driven coordinates (their
//! laws' accelerations at t, the drives' efforts recorded with their power), and the
//! coordinates held at rest,
//! on their stops (resting on a bound) or stuck by their friction, each a unit row eₖᵀ a = 0
//! with a force μₖ along the coordinate. Whatever the mechanism (a tree, closed loops, contacts
//! or both), they are solved together in one saddle-point system; the held forces are recorded
//! for the events (`contact`, `holding`).

use nalgebra::DVector;

use super::{MechanicalSystem, SystemError};
use crate::dynamics::algorithms::forward_kinematics;
use crate::dynamics::contacts;
use crate::dynamics::friction::Phase;
use crate::dynamics::stops::Side;

impl MechanicalSystem<'_> {
    /// Solves the rows at (t, q, v) from the accelerations `a` of the base solve (the loops',
    /// or the tree's), which they replace; records the contacts' forces, the held forces and
    /// the drives' efforts.
    pub(super) fn solve_rows(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
        a: &mut DVector<f64>,
    ) -> Result<(), SystemError> {
        let model = self.model;
        self.gather_held();
        let couplings = self.coupling_count();
        let driven = !model.drives.is_empty();
        if !model.has_contacts() && couplings == 0 && !driven && self.scratch.held.is_empty() {
            return Ok(());
        }
        self.form_response_at(q)?;
        if model.has_contacts() && model.has_loops() {
            // The loops' solve leaves the kinematics for its own rows: the contacts' start anew.
            forward_kinematics(model, &mut self.scratch.data, q, v)?;
            let state = &mut self.scratch.contact_state;
            contacts::contact_rows_into(model, &mut self.scratch.data, v, true, state);
        }
        self.decide_contact_rows();
        let kept = self.state.contact_rows.as_deref().unwrap_or_default();
        let (rows, values) = (&mut self.scratch.rows, &mut self.scratch.law_values);
        rows.arrange(kept, couplings, &self.scratch.driven, &self.scratch.held);
        rows.gather(&self.scratch.contact_state, &model.mimics);
        rows.prescribe(
            model
                .drives
                .iter()
                .map(|d| d.evaluate(t, values).acceleration),
        );
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
        self.record_holding();
        self.record_drives(v);
        Ok(())
    }

    /// The drives' efforts of the last solve, and their power (the work a drive does on the
    /// mechanism counts in its energy balance).
    fn record_drives(&mut self, v: &[f64]) {
        let forces = self.scratch.rows.drive_forces();
        self.scratch.drive_efforts.copy_from_slice(forces);
        let power: f64 = (self.scratch.driven.iter())
            .zip(forces)
            .map(|(&velocity, force)| force * v[velocity])
            .sum();
        self.scratch.drive_power = power;
    }

    /// The mimic couplings solved as rows: with closed loops (a tree's response keeps them).
    pub(super) fn coupling_count(&self) -> usize {
        match self.model.has_loops() {
            true => self.model.mimics.len(),
            false => 0,
        }
    }

    /// The velocities held at rest into `held`: the resting stops', then the sticking joints'.
    pub(super) fn gather_held(&mut self) {
        let model = self.model;
        self.scratch.held.clear();
        let stops = (0..model.stops.len()).filter(|&k| self.state.resting[k]);
        self.scratch
            .held
            .extend(stops.map(|k| model.stops[k].velocity));
        let frictions =
            (0..model.frictions.len()).filter(|&k| self.state.phases[k] == Phase::Sticking);
        self.scratch
            .held
            .extend(frictions.map(|k| model.frictions[k].velocity));
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

    /// The held forces of the last solve, in the order of the held rows (the resting stops,
    /// then the sticking frictions), into each stop's contact force (positive while it pushes)
    /// and each friction's holding force.
    fn record_holding(&mut self) {
        let model = self.model;
        let mut forces = self.scratch.rows.held_forces().iter();
        let stops = (0..model.stops.len()).filter(|&k| self.state.resting[k]);
        for (k, force) in stops.zip(forces.by_ref()) {
            // A lower stop pushes the coordinate up, an upper one down.
            self.scratch.contact[k] = match model.stops[k].side {
                Side::Lower => *force,
                Side::Upper => -*force,
            };
        }
        let frictions =
            (0..model.frictions.len()).filter(|&k| self.state.phases[k] == Phase::Sticking);
        for (k, force) in frictions.zip(forces) {
            self.scratch.holding[k] = *force;
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
