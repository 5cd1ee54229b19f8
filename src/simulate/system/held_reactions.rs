//! The reactions: the wrench each join transmits (`reactions`), from the forces of every block
//! of the constraint stack at the accelerations of the run's own equations, every row solved
//! (`stack_reactions`, the one reactions path): the contacts' and the position drives' forces
//! act on the bodies, so they join the efforts' external forces; the other rows' forces (a mimic coupling's, a
//! resting stop's, a sticking joint's, a drive's) act along coordinates, as link efforts do, so
//! they join the efforts' generalised forces; the loops' block's multipliers then come from
//! M a − f, and act on the bodies their loops close.

use nalgebra::DVector;

use super::{MechanicalSystem, SystemError};
use crate::dynamics::algorithms::{rnea, transmitted_wrenches};
use crate::dynamics::contacts;
use crate::dynamics::driven_points;
use crate::dynamics::loops;
use crate::spatial;

/// The forces of every block of the stack at one state (`stack_reactions`).
struct StackForces {
    /// The accelerations, every row solved.
    accelerations: DVector<f64>,
    /// The forces on the bodies: the efforts', the contacts' and the loops' closing forces.
    external: Vec<spatial::Force>,
    /// What the reactions list after the tree's joins: the loops' multipliers (6 per loop),
    /// then the contacts' reactions.
    listed: Option<DVector<f64>>,
}

impl MechanicalSystem<'_> {
    /// The wrench each join transmits to its second body, at the join, in the fixed axes
    /// (moment, then force): the tree's joins from inverse dynamics with the accelerations of the
    /// motion and the stack's forces, then the loops' from their multipliers and the contacts'.
    /// The coordinates held (resting stops, sticking joints, drives) are held as the run holds
    /// them, their forces in their joins' reactions as a link effort is.
    pub fn reactions(&mut self, t: f64, q: &[f64], v: &[f64]) -> Result<Vec<f64>, SystemError> {
        let model = self.model;
        // The reactions read the spatial kinematics and inverse dynamics of the stack's solve.
        // The drives' rows give their forces to the reactions: no hybrid dynamics here.
        let planar = self.scratch.planar.take();
        let driven = self.driven.take();
        let forces = self.stack_reactions(t, q, v);
        (self.scratch.planar, self.driven) = (planar, driven);
        let StackForces {
            accelerations,
            mut external,
            listed,
        } = forces?;
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
        if let Some(listed) = listed {
            reactions.extend_from_slice(listed.as_slice());
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

    /// The position drives' forces of the last solve added to the forces on the bodies
    /// `external`; `data` holds the forward kinematics of the state.
    fn add_point_forces(&self, external: &mut [spatial::Force]) {
        let forces = &self.scratch.point_forces;
        driven_points::add_body_forces(self.model, &self.scratch.data, forces, external);
    }

    /// The forces of every block of the stack at (t, q, v), the whole stack solved as the run's
    /// equations solve it (`solve_every_row`), the forward kinematics of (q, v) left in `data`:
    /// see the module's documentation.
    fn stack_reactions(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
    ) -> Result<StackForces, SystemError> {
        let model = self.model;
        let accelerations = self.solve_every_row(t, q, v)?;
        // The forces added to the efforts' external forces below are not zero.
        self.scratch.external_is_zero = false;
        if !model.has_loops() && !model.has_contacts() {
            // A tree's evaluation may skip the efforts (none applied): they are taken here.
            let mut external = self.efforts(t, q, v)?.external;
            self.add_point_forces(&mut external);
            let listed = None;
            return Ok(StackForces {
                accelerations,
                external,
                listed,
            });
        }
        let mut external = std::mem::take(&mut self.scratch.efforts.external);
        self.add_point_forces(&mut external);
        self.scratch.efforts.external = external;
        let touching = (model.has_contacts()).then(|| self.contact_forces_among_efforts());
        if !model.has_loops() {
            let external = self.scratch.efforts.external.clone();
            return Ok(StackForces {
                accelerations,
                external,
                listed: touching,
            });
        }
        // `solve_rows` left the stack as it was when no row applied at this state.
        if self.coupling_count() > 0 || !self.scratch.held.is_empty() {
            self.scratch
                .rows
                .add_coordinate_forces(&model.mimics, &mut self.scratch.efforts.tau);
        }
        self.loop_block_multipliers(&accelerations);
        let solution = &self.scratch.loop_scratch;
        let (c, multipliers) = (&solution.constraints, &solution.multipliers);
        let on_bodies = loops::constraint_forces(model, &self.scratch.data, c, multipliers);
        let external = (self.scratch.efforts.external.iter())
            .zip(&on_bodies)
            .map(|(a, b)| a + b)
            .collect();
        let listed = match touching {
            Some(forces) => DVector::from_iterator(
                multipliers.len() + forces.len(),
                multipliers.iter().chain(forces.iter()).copied(),
            ),
            None => multipliers.clone(),
        };
        Ok(StackForces {
            accelerations,
            external,
            listed: Some(listed),
        })
    }
}
