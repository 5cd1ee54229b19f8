//! The solve behind the reactions of a mechanism with closed loops. The loops' multipliers come
//! from M a − f at the accelerations of the run's own equations, every row solved (`holding`):
//! the contacts' forces act on the bodies, so they join the efforts' external forces; the other
//! rows' forces (a mimic coupling's, a resting stop's, a sticking joint's) act along
//! coordinates, as link efforts do, so they join the efforts' generalised forces.

use nalgebra::DVector;

use super::{MechanicalSystem, SystemError};
use crate::dynamics::contacts;

impl MechanicalSystem<'_> {
    /// Solves a mechanism with loops at (t, q, v) for its reactions: the accelerations and the
    /// loops' multipliers left in the loops' scratch, the rows' forces among the efforts, the
    /// forward kinematics of (q, v) in `data`; with contacts, their reactions
    /// (`contacts::contact_reactions`) returned.
    pub(super) fn loops_reactions_solve(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
    ) -> Result<Option<DVector<f64>>, SystemError> {
        let model = self.model;
        let accelerations = self.solve_every_row(t, q, v)?;
        let touching = match model.has_contacts() {
            true => {
                let forces = &self.scratch.rows.contact_forces;
                let on_bodies = contacts::contact_body_forces(
                    model,
                    &self.scratch.data,
                    &self.scratch.contact_state,
                    forces,
                );
                for (external, force) in self.scratch.efforts.external.iter_mut().zip(&on_bodies) {
                    *external += force;
                }
                Some(contacts::contact_reactions(forces))
            }
            false => None,
        };
        // `solve_rows` left the stack as it was when no row applied at this state.
        if self.coupling_count() > 0 || !self.scratch.held.is_empty() {
            self.scratch
                .rows
                .add_coordinate_forces(&model.mimics, &mut self.scratch.efforts.tau);
        }
        self.scratch
            .loop_scratch
            .accelerations
            .copy_from(&accelerations);
        self.solve_multipliers();
        Ok(touching)
    }
}
