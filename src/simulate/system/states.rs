//! The program's states in a run (`let s = state(x0); rate s = f;`): the integrator carries
//! their values after the mechanism's positions and velocities (`RunOde`), sets them in the run
//! state before each evaluation, and reads their rates from the efforts' tape that evaluation
//! computed: the efforts and the rates at one point cost one evaluation of one tape. The rates
//! that read the model come from the actuators' tape, which the same evaluation computed after
//! the model.

use super::{MechanicalSystem, SystemError};
use crate::dynamics::states::StateModel;

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
    /// (`derivative`), which evaluated the efforts' tape there, into `rates`: zero for a
    /// sampled state, held between its instants.
    pub fn state_rates(&self, rates: &mut [f64]) -> Result<(), SystemError> {
        for (rate, state) in rates.iter_mut().zip(&self.model.states) {
            *rate = match state.continuous() {
                true => self.law_value(state)?,
                false => 0.0,
            };
        }
        match self.first_not_finite(rates) {
            Some(state) => Err(SystemError::StateRateNotFinite { state }),
            None => Ok(()),
        }
    }

    /// The value of `state`'s law (its rate, or a sampled state's update) at the last evaluation
    /// of the equations of motion: a root of the actuators' tape when it reads the model (that
    /// tape is evaluated after the model), of the efforts' tape otherwise.
    fn law_value(&self, state: &StateModel) -> Result<f64, SystemError> {
        let laws = self.model.actuation.as_ref().map(|a| &a.tape);
        Ok(match (state.reads_model, laws) {
            (true, Some(laws)) => laws.root(&self.scratch.actuator_tape, state.rate_root),
            _ => {
                let tape = self.model.effort_tape.as_ref().map_err(Clone::clone)?;
                tape.root(&self.scratch.data.efforts, state.rate_root)
            }
        })
    }

    /// The name of the first state whose computed value (its rate, or a sampled state's
    /// update) is not finite.
    fn first_not_finite(&self, values: &[f64]) -> Option<String> {
        let k = values.iter().position(|v| !v.is_finite())?;
        Some(self.model.states[k].name.clone())
    }
}

impl MechanicalSystem<'_> {
    /// The sampled states' updates at (t, y), the mechanism's state `y` with the states' values
    /// after it, into `updates` (one per state; the continuous ones keep their values): the
    /// efforts' tape evaluated there, as the equations of motion evaluate it.
    pub fn sampled_updates(
        &mut self,
        t: f64,
        y: &[f64],
        updates: &mut [f64],
    ) -> Result<(), SystemError> {
        let n = self.dimension();
        let states = self.state_count();
        self.set_states(&y[n..n + states]);
        let mut rates = vec![0.0; n];
        self.derivative(t, &y[..n], &mut rates)?;
        for ((update, state), value) in updates.iter_mut().zip(&self.model.states).zip(&y[n..]) {
            *update = match state.continuous() {
                true => *value,
                false => self.law_value(state)?,
            };
        }
        match self.first_not_finite(updates) {
            Some(state) => Err(SystemError::UpdateNotFinite { state }),
            None => Ok(()),
        }
    }
}
