//! The program's states in a run (`let s = state(x0); rate s = f;`): the integrator carries
//! their values after the mechanism's positions and velocities (`RunOde`), sets them in the run
//! state before each evaluation, and reads their rates from the efforts' tape that evaluation
//! computed: the efforts and the rates at one point cost one evaluation of one tape.

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
    /// (`derivative`), which evaluated the efforts' tape there, into `rates`: zero for a
    /// sampled state, held between its instants.
    pub fn state_rates(&self, rates: &mut [f64]) -> Result<(), SystemError> {
        let tape = self.model.effort_tape.as_ref().map_err(Clone::clone)?;
        let values = &self.scratch.data.efforts;
        for (rate, state) in rates.iter_mut().zip(&self.model.states) {
            *rate = match state.continuous() {
                true => tape.root(values, state.rate_root),
                false => 0.0,
            };
        }
        match self.first_not_finite(rates) {
            Some(state) => Err(SystemError::StateRateNotFinite { state }),
            None => Ok(()),
        }
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
        let tape = self.model.effort_tape.as_ref().map_err(Clone::clone)?;
        let values = &self.scratch.data.efforts;
        for ((update, state), value) in updates.iter_mut().zip(&self.model.states).zip(&y[n..]) {
            *update = match state.continuous() {
                true => *value,
                false => tape.root(values, state.rate_root),
            };
        }
        match self.first_not_finite(updates) {
            Some(state) => Err(SystemError::UpdateNotFinite { state }),
            None => Ok(()),
        }
    }
}
