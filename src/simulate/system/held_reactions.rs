//! The reactions: the wrench each join transmits (`reactions`), and the solve behind those of
//! a mechanism with closed loops. The loops' multipliers come
//! from M a − f at the accelerations of the run's own equations, every row solved (`holding`):
//! the contacts' forces act on the bodies, so they join the efforts' external forces; the other
//! rows' forces (a mimic coupling's, a resting stop's, a sticking joint's) act along
//! coordinates, as link efforts do, so they join the efforts' generalised forces.

use nalgebra::DVector;

use super::{MechanicalSystem, SystemError};
use crate::dynamics::algorithms::{rnea, transmitted_wrenches};
use crate::dynamics::contacts;
use crate::dynamics::loops;
use crate::spatial;

impl MechanicalSystem<'_> {
    /// The wrench each join transmits to its second body, at the join, in the fixed axes
    /// (moment, then force): the tree's joins from inverse dynamics with the accelerations of the
    /// motion and the loops' forces, then the loops' from their multipliers. The coordinates
    /// held at rest (resting stops, sticking joints) are held as the run holds them, their
    /// forces in their joins' reactions as a link effort is.
    pub fn reactions(&mut self, t: f64, q: &[f64], v: &[f64]) -> Result<Vec<f64>, SystemError> {
        let model = self.model;
        let (accelerations, mut external, multipliers) = if model.has_loops() {
            let touching = self.loops_reactions_solve(t, q, v)?;
            let solution = &self.scratch.loop_scratch;
            let (c, multipliers) = (&solution.constraints, &solution.multipliers);
            let on_bodies = loops::constraint_forces(model, &self.scratch.data, c, multipliers);
            let external: Vec<_> = self
                .scratch
                .efforts
                .external
                .iter()
                .zip(&on_bodies)
                .map(|(a, b)| a + b)
                .collect();
            let accelerations = solution.accelerations.clone();
            let mut multipliers = multipliers.clone();
            if let Some(forces) = touching {
                multipliers = DVector::from_iterator(
                    multipliers.len() + forces.len(),
                    multipliers.iter().chain(forces.iter()).copied(),
                );
            }
            (accelerations, external, Some(multipliers))
        } else if model.has_contacts() {
            let accelerations = self.solve_every_row(t, q, v)?;
            let forces = self.contact_forces_among_efforts();
            let external = self.scratch.efforts.external.clone();
            (accelerations, external, Some(forces))
        } else {
            // The accelerations of the run's own equations: with the geared rotors, the mimic
            // couplings, the friction's phases and the coordinates held at rest.
            let mut rates = vec![0.0; self.dimension()];
            self.derivative_at(t, q, v, &mut rates)?;
            let a = DVector::from_column_slice(&rates[model.positions()..]);
            let efforts = self.efforts(t, q, v)?;
            (a, efforts.external, None)
        };
        // The link efforts act across their joints: they are not part of the reaction.
        external.truncate(model.body_count() + 1);
        rnea(
            model,
            &mut self.scratch.data,
            q,
            v,
            &accelerations.as_slice()[..model.nv],
            &external,
        )?;
        let transmitted = transmitted_wrenches(model, &self.scratch.data, &external);
        let mut reactions = Vec::with_capacity(6 * (model.joints.len() + model.loops.len()));
        for joint in &model.joints {
            let frame = self.scratch.data.world[joint.child] * joint.on_child;
            let about_origin = spatial::force_to_parent(
                &self.scratch.data.world[joint.child],
                &transmitted[joint.child],
            );
            let at_join = spatial::force_to_child(
                &spatial::Pose::translation(
                    frame.translation.x,
                    frame.translation.y,
                    frame.translation.z,
                ),
                &about_origin,
            );
            // The tree carries the child; a join written from the child's side has it first.
            let on_second = if joint.first_on_parent {
                at_join
            } else {
                -at_join
            };
            reactions.extend_from_slice(on_second.as_slice());
        }
        if let Some(multipliers) = multipliers {
            reactions.extend_from_slice(multipliers.as_slice());
        }
        Ok(reactions)
    }

    /// The contacts' forces of the last solve (`holding`) added to the efforts' external forces
    /// (they act on the bodies); their reactions (`contacts::contact_reactions`).
    fn contact_forces_among_efforts(&mut self) -> DVector<f64> {
        let forces = &self.scratch.rows.contact_forces;
        let on_bodies = contacts::contact_body_forces(
            self.model,
            &self.scratch.data,
            &self.scratch.contact_state,
            forces,
        );
        for (external, force) in self.scratch.efforts.external.iter_mut().zip(&on_bodies) {
            *external += force;
        }
        contacts::contact_reactions(forces)
    }

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
        let touching = model
            .has_contacts()
            .then(|| self.contact_forces_among_efforts());
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
