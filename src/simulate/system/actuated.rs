//! The actuators' efforts in an evaluation: the model in the actuated coordinates computed once
//! from the program's other efforts (`dynamics::reduced_model`), then the laws' tape, each law
//! added to the generalised forces along its coordinate and its power to the work of the
//! efforts that derive from no potential.

use super::{MechanicalSystem, SystemError};
use crate::dynamics::compiled::EffortState;
use crate::dynamics::reduced_model::{
    reduced_model, LoopSolution, ReducedError, ReducedScratch, ReducedState,
};

impl MechanicalSystem<'_> {
    /// Adds the actuators' efforts at (t, q, v) to `scratch.efforts`, which holds the other
    /// efforts there; `data` holds the forward kinematics of (q, v), and `loop_scratch` the
    /// loops' allowed motions there when `loops_solved`.
    pub(super) fn actuate(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
        loops_solved: bool,
    ) -> Result<(), SystemError> {
        let model = self.model;
        let Some(actuation) = &model.actuation else {
            return Ok(());
        };
        let scratch = &mut *self.scratch;
        let m = actuation.coordinates.len();
        let reduced = scratch
            .model_laws
            .get_or_insert_with(|| ReducedScratch::new(model, m));
        if actuation.reads.any() {
            let velocities: Vec<usize> = actuation.coordinates.iter().map(|c| c.velocity).collect();
            let state = ReducedState {
                q,
                v,
                coordinates: &scratch.declared.coordinates,
                states: &self.state.states,
                time: t,
                efforts: &scratch.efforts,
            };
            let loops = loops_solved.then(|| LoopSolution {
                motions: scratch.loop_scratch.found_motions(),
                particular: scratch.loop_scratch.particular(),
            });
            reduced_model(
                model,
                &mut scratch.data,
                &state,
                &velocities,
                actuation.reads,
                (reduced, loops),
            )
            .map_err(|error| match error {
                ReducedError::Evaluation(e) => SystemError::Evaluation(e),
                ReducedError::Undetermined => SystemError::ActuatedUndetermined,
            })?;
        }
        let state = EffortState {
            world: &scratch.data.world,
            velocity: &scratch.data.velocity,
            coordinates: &scratch.declared.coordinates,
            rates: &scratch.declared.rates,
            states: &self.state.states,
            time: t,
            model: &reduced.values,
        };
        let tape = &actuation.tape;
        tape.eval(
            &model.effort_frames,
            &state,
            false,
            &mut scratch.actuator_tape,
        );
        for (coordinate, &root) in actuation.coordinates.iter().zip(&actuation.roots) {
            let effort = tape.root(&scratch.actuator_tape, root);
            scratch.efforts.tau[coordinate.velocity] += effort;
            scratch.efforts.power += effort * v[coordinate.velocity];
        }
        Ok(())
    }
}
