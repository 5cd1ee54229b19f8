//! Contacts on a mechanism with closed loops: the contacts' rows solved together with the
//! loops'. The loops' solve gives the accelerations without the contacts and the response P of
//! the accelerations to generalised forces (`loops::constrained_response`); the contacts' rows
//! are then solved on P exactly as on M⁻¹ for a tree (`contacts::solve_on_loops`), so their
//! forces keep the loops' rows. After a step the loops are projected first, then the contacts'
//! gaps closed by steps along P Gₙᵀ (along the loops to first order), each followed by the
//! loops' projection, and the velocities projected along P onto every kept contact row (the
//! rolling rows on velocities only): the loops' velocity rows stay kept, G P = 0.

use nalgebra::{DMatrix, DVector};

use super::{MechanicalSystem, SystemError};
use crate::dynamics::algorithms::{crba_after_kinematics, forward_kinematics};
use crate::dynamics::contacts;
use crate::dynamics::loops::{self, Wanted};

/// Newton steps at most that close the contacts' gaps with the loops.
const GAP_STEPS: usize = 4;

impl MechanicalSystem<'_> {
    /// The loops' solve at (t, q, v) without the contacts, then the contacts' rows at (q, v)
    /// (with γ when `with_bias`) and the loops' response P in the contacts' scratch; the contact rows of the run decided if they were not.
    fn contacts_over_loops(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
        with_bias: bool,
    ) -> Result<(), SystemError> {
        let model = self.model;
        self.solve_constrained(t, q, v, Wanted::Accelerations)?;
        forward_kinematics(model, &mut self.data, q, v)?;
        let scratch = &mut self.contacts;
        contacts::contact_rows_into(model, &mut self.data, v, with_bias, &mut scratch.rows);
        // The tree's mass matrix (the complementary coordinates carry no inertia).
        let mut mass = DMatrix::zeros(model.nv, model.nv);
        crba_after_kinematics(model, &mut self.data, &mut mass);
        let identity = DMatrix::identity(model.velocities(), model.velocities());
        let motions = self.loop_scratch.solved_motions();
        let response = loops::constrained_response(&mass, motions, &identity)
            .ok_or(SystemError::SingularMassMatrix)?;
        let kept = (self
            .contact_rows
            .get_or_insert_with(|| contacts::independent_rows_on(model, &response, &scratch.rows)))
        .clone();
        scratch.keep(&kept);
        scratch.response = Some(response);
        Ok(())
    }

    /// The accelerations and contact forces of a mechanism with loops and contacts at
    /// (t, q, v), left in the contacts' scratch.
    pub(super) fn solve_contacts_on_loops(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
    ) -> Result<(), SystemError> {
        self.contacts_over_loops(t, q, v, true)?;
        let free = &self.loop_scratch.accelerations;
        contacts::solve_on_loops(self.model, &mut self.contacts, free)
            .map_err(|e| self.contact_error(&e))
    }

    /// Keeps the contacts of a mechanism with loops in y, after the loops' projection (see the
    /// module's documentation). Its velocities are always projected: true.
    pub(super) fn keep_contacts_on_loops(
        &mut self,
        t: f64,
        y: &mut [f64],
    ) -> Result<bool, SystemError> {
        let model = self.model;
        let positions = model.positions();
        let size = model.contacts.iter().map(|c| c.radius).fold(0.0, f64::max);
        for _ in 0..GAP_STEPS {
            let (mut q, v) = model.split_state(y);
            let mut v = v.to_vec();
            self.contacts_over_loops(t, &q, &v, false)?;
            if contacts::largest_gap(&self.contacts) <= 1e-15 * size
                || !contacts::gap_step(&mut self.contacts)
            {
                break;
            }
            model.retract(&mut q, self.contacts.step.as_slice());
            let choice = &self.loops.structure.choice;
            loops::project(model, &mut self.data, choice, &mut q, &mut v)?;
            y[..positions].copy_from_slice(&q);
            y[positions..].copy_from_slice(&v);
        }
        let (q, v) = model.split_state(y);
        let mut v = v.to_vec();
        self.contacts_over_loops(t, &q, &v, false)?;
        contacts::project_velocities(&mut self.contacts, &mut v);
        y[positions..].copy_from_slice(&v);
        Ok(true)
    }

    /// The solve of [`solve_contacts_on_loops`](Self::solve_contacts_on_loops) for the
    /// reactions: the contacts' forces join the efforts' external forces, the loops' multipliers
    /// are taken at the accelerations with the contacts (in the loops' scratch, for
    /// `reactions`), and the contacts' reactions (`contacts::contact_reactions`) returned.
    pub(super) fn contacts_on_loops_reactions(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
    ) -> Result<DVector<f64>, SystemError> {
        let model = self.model;
        self.solve_contacts_on_loops(t, q, v)?;
        let (rows, solution) = (&self.contacts.rows, &self.contacts.solution);
        let on_bodies = contacts::contact_body_forces(model, &self.data, rows, &solution.forces);
        for (external, force) in self.efforts.external.iter_mut().zip(&on_bodies) {
            *external += force;
        }
        let accelerations = &mut self.loop_scratch.accelerations;
        accelerations.copy_from(&solution.accelerations);
        let forces = contacts::contact_reactions(&solution.forces);
        self.solve_multipliers();
        Ok(forces)
    }
}
