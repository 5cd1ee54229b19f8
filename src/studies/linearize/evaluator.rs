//! The first-order system a linearisation differentiates, in the chart's coordinates: the
//! state x = (independent coordinates z, their rates ż, the program's kept states s) and the
//! values of the states held as inputs give (z̈, ṡ), and the program's outputs.

use super::chart::Chart;
use super::error::LinearizeError;
use super::inputs::Inputs;
use crate::dynamics::algorithms::forward_kinematics;
use crate::dynamics::angles::AngleReference;
use crate::dynamics::compiled::{EffortScratch, EffortState};
use crate::prepare::Prepared;
use crate::simulate::system::{MechanicalSystem, SystemError};

/// The equations of motion in the chart's coordinates, and the outputs.
pub(super) struct Evaluator<'p> {
    pub prepared: &'p Prepared,
    pub system: MechanicalSystem<'p>,
    pub chart: Chart,
    pub time: f64,
    pub inputs: Inputs,
    pub scratch: EffortScratch,
}

impl Evaluator<'_> {
    /// How many coordinates are independent (n: x has 2n + the kept states).
    pub fn independent(&self) -> usize {
        self.chart.independent.len()
    }

    /// The mechanism's state at x, the program's states set from x and `held`.
    pub fn state(
        &mut self,
        x: &[f64],
        held: &[f64],
    ) -> Result<(Vec<f64>, Vec<f64>), LinearizeError> {
        let n = self.independent();
        let mut states = std::mem::take(&mut self.system.state.states);
        self.inputs.fill_states(&x[2 * n..], held, &mut states);
        self.system.state.states = states;
        let model = self.system.model;
        let data = &mut self.system.scratch.data;
        Ok(self.chart.state(model, data, &x[..n], &x[n..2 * n])?)
    }

    /// The independent coordinates' accelerations, then the kept states' rates, at state x
    /// under the generalised forces `efforts` and the held states' values `held`.
    pub fn rates(
        &mut self,
        x: &[f64],
        efforts: &[f64],
        held: &[f64],
    ) -> Result<Vec<f64>, LinearizeError> {
        let model = self.system.model;
        let (q, v) = self.state(x, held)?;
        self.system.state.inputs.held.copy_from_slice(efforts);
        let y: Vec<f64> = q.iter().chain(&v).copied().collect();
        let mut dydt = vec![0.0; y.len()];
        self.system.derivative(self.time, &y, &mut dydt)?;
        let positions = model.positions();
        let mut rates: Vec<f64> = (self.chart.independent.iter())
            .map(|&i| dydt[positions + i])
            .collect();
        if !model.states.is_empty() {
            // The derivative evaluated the efforts' tape, which holds the states' rates.
            let mut all = vec![0.0; model.states.len()];
            self.system.state_rates(&mut all)?;
            rates.extend(self.inputs.kept_states.iter().map(|&k| all[k]));
        }
        Ok(rates)
    }

    /// The program's outputs at state x with the held states at `held`, the efforts at
    /// `efforts` (the model an output reads is that of an evaluation of the equations of
    /// motion there, as a run's samples have it).
    pub fn outputs(
        &mut self,
        x: &[f64],
        efforts: &[f64],
        held: &[f64],
    ) -> Result<Vec<f64>, LinearizeError> {
        let model = self.system.model;
        let (q, v) = self.state(x, held)?;
        if self.prepared.outputs.reads_model {
            // The model in the actuated coordinates is computed by the actuators' evaluation.
            self.rates(x, efforts, held)?;
        }
        // Angles against the program's initial values, as every output of the study.
        let reference = AngleReference::at_rest(self.prepared.coordinates.clone());
        let (coordinates, rates) = model
            .declared((self.time, &q, &v), &reference)
            .map_err(|e| LinearizeError::System(SystemError::from(e)))?;
        let scratch = &mut *self.system.scratch;
        let model_values = (scratch.model_laws.as_ref()).map_or(&[][..], |r| &r.values[..]);
        let data = &mut scratch.data;
        forward_kinematics(model, data, &q, &v)
            .map_err(|e| LinearizeError::System(SystemError::from(e)))?;
        let state = EffortState {
            world: &data.world,
            velocity: &data.velocity,
            coordinates: &coordinates,
            rates: &rates,
            states: &self.system.state.states,
            time: self.time,
            model: model_values,
        };
        Ok(self.prepared.outputs.values(&state, &mut self.scratch))
    }
}
