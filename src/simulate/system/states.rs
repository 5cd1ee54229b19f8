//! The program's states in a run (`let s = state(x0); rate s = f;`): the integrator carries
//! their values after the mechanism's positions and velocities (`RunOde`), sets them in the run
//! state before each evaluation, and reads their rates from the efforts' tape that evaluation
//! computed: the efforts and the rates at one point cost one evaluation of one tape. The rates
//! that read the model come from the actuators' tape, which the same evaluation computed after
//! the model.

use super::{MechanicalSystem, SystemError};

impl MechanicalSystem<'_> {
    /// How many states the program has.
    pub fn state_count(&self) -> usize {
        self.model.states.len()
    }

    /// Sets the states' values at the point about to be evaluated.
    pub fn set_states(&mut self, values: &[f64]) {
        self.state.states.copy_from_slice(values);
    }

    /// The states' rates at the point of the last evaluation of the equations of motion
    /// (`derivative`), which evaluated the efforts' tape there, into `rates`.
    pub fn state_rates(&self, rates: &mut [f64]) -> Result<(), SystemError> {
        let tape = self.model.effort_tape.as_ref().map_err(Clone::clone)?;
        let values = &self.scratch.data.efforts;
        let laws = self.model.actuation.as_ref().map(|a| &a.tape);
        for (rate, state) in rates.iter_mut().zip(&self.model.states) {
            *rate = match (state.reads_model, laws) {
                (true, Some(laws)) => laws.root(&self.scratch.actuator_tape, state.rate_root),
                _ => tape.root(values, state.rate_root),
            };
        }
        if let Some(k) = rates.iter().position(|r| !r.is_finite()) {
            return Err(SystemError::StateRateNotFinite {
                state: self.model.states[k].name.clone(),
            });
        }
        Ok(())
    }
}
