//! The reactions of a mechanism with loops or contacts whose coordinates are held (`holding`):
//! the forces that hold them (a resting stop's contact force, a sticking joint's friction, with
//! loops the mimic couplings' forces) act on their coordinates as the link efforts do, so the
//! reactions' solve counts them among the efforts' generalised forces, with the accelerations
//! the run's held equations give.

use super::{MechanicalSystem, SystemError};
use crate::dynamics::algorithms::forward_kinematics;
use crate::dynamics::contacts;
use crate::dynamics::loops::Wanted;

impl MechanicalSystem<'_> {
    /// The loops' solve at (t, q, v) for the reactions: the accelerations held on every held
    /// row (`held_rows`), their forces Eᵀλ added to the efforts' generalised forces, and the
    /// loops' multipliers taken there; all left in the loops' scratch and `efforts`, the
    /// forward kinematics of (q, v) in `data`.
    pub(super) fn solve_held_on_loops(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
    ) -> Result<(), SystemError> {
        self.solve_constrained(t, q, v, Wanted::Accelerations)?;
        let (rows, _) = self.held_rows();
        if rows.nrows() > 0 {
            let held = &rows * &self.loop_scratch.accelerations;
            let (change, forces) = self.held_change(q, &rows, &held)?;
            self.loop_scratch.accelerations += change;
            self.efforts.tau.gemv_tr(1.0, &rows, &forces, 1.0);
            // The response's mass matrix left the kinematics of q alone in `data`.
            forward_kinematics(self.model, &mut self.data, q, v)?;
        }
        self.solve_multipliers();
        Ok(())
    }

    /// The contacts' solve at (t, q, v) for the reactions of a tree with contacts: solved again
    /// with the held coordinates' forces (`hold_with_constraints`) among the generalised forces,
    /// so that the contacts' forces and the accelerations are the held ones; left in the
    /// contacts' scratch.
    pub(super) fn solve_held_contacts(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
    ) -> Result<(), SystemError> {
        self.solve_contacts(t, q, v)?;
        let held = self.held_velocities();
        if held.is_empty() {
            return Ok(());
        }
        let mut a = self.contacts.solution.accelerations.clone();
        self.hold_with_constraints(&held, &mut a)?;
        for (&k, force) in held.iter().zip(self.hold.forces.iter()) {
            self.force[k] += force;
        }
        contacts::solve(self.model, &mut self.contacts, &self.force)
            .map_err(|e| self.contact_error(&e))
    }
}
