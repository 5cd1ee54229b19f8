//! The inputs of a linearisation, named with `--input`: a generalised force along a coordinate
//! (`crank.q`: N·m for an angle, N for a length), or a constant state of the program
//! (`let voltage = state(0); rate voltage = 0;`, a motor's voltage), whose value becomes an
//! input instead of a state. Every other state of the program is a state of the linear model.

use super::error::LinearizeError;
use crate::prepare::Prepared;
use crate::studies::statics::velocity_index;

/// One input, in the order named.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Input {
    /// A generalised force along the model's velocity.
    Effort(usize),
    /// The value of the program's state with this index (`Model::states`).
    State(usize),
}

/// The inputs named, and the program's states split between the linear model's states and
/// its inputs.
#[derive(Clone, Debug, Default)]
pub struct Inputs {
    pub inputs: Vec<Input>,
    /// The efforts' velocities, in the order named (the run's `Inputs::along`).
    pub efforts: Vec<usize>,
    /// The names of the efforts' coordinates, in the order named (for `statics`).
    pub effort_names: Vec<String>,
    /// The program's states that are inputs, in the order named.
    pub held_states: Vec<usize>,
    /// The program's states that are states of the linear model, in the program's order.
    pub kept_states: Vec<usize>,
}

impl Inputs {
    /// The inputs `names`: each a program state's name or a coordinate `join.coordinate`, named
    /// once; a state must be constant (`rate s = 0;`), since the linear model holds it at
    /// whatever value the input gives it.
    pub fn named(prepared: &Prepared, names: &[String]) -> Result<Inputs, LinearizeError> {
        refuse_repeated(names)?;
        let model = &prepared.model;
        let mut split = Inputs::default();
        for name in names {
            if let Some(k) = model.states.iter().position(|s| s.name == *name) {
                if crate::elab::value::constant(&model.states[k].rate) != Some(0.0) {
                    return Err(LinearizeError::VaryingStateInput { name: name.clone() });
                }
                split.inputs.push(Input::State(k));
                split.held_states.push(k);
                continue;
            }
            let index = coordinate_index(prepared, name)?;
            split.inputs.push(Input::Effort(index));
            split.efforts.push(index);
            split.effort_names.push(name.clone());
        }
        split.kept_states = (0..model.states.len())
            .filter(|k| !split.held_states.contains(k))
            .collect();
        Ok(split)
    }

    /// The program's states' values: the kept ones from `kept`, the held ones from `held` (in
    /// their orders), into `states`.
    pub fn fill_states(&self, kept: &[f64], held: &[f64], states: &mut [f64]) {
        for (&k, &value) in self.kept_states.iter().zip(kept) {
            states[k] = value;
        }
        for (&k, &value) in self.held_states.iter().zip(held) {
            states[k] = value;
        }
    }
}

/// Refuses a name given twice (as an input or a coordinate).
pub(super) fn refuse_repeated(names: &[String]) -> Result<(), LinearizeError> {
    match (1..names.len()).find(|&k| names[..k].contains(&names[k])) {
        Some(k) => Err(LinearizeError::Repeated {
            name: names[k].clone(),
        }),
        None => Ok(()),
    }
}

/// The state velocity of the coordinate `join.coordinate`, which no drive imposes.
pub(super) fn coordinate_index(prepared: &Prepared, name: &str) -> Result<usize, LinearizeError> {
    let index = velocity_index(prepared, name).map_err(LinearizeError::Name)?;
    match prepared.model.drives.iter().any(|d| d.velocity == index) {
        true => Err(LinearizeError::DrivenInput {
            name: name.to_string(),
        }),
        false => Ok(index),
    }
}
