//! What a run has decided and seen so far, held once and read by every evaluation of its
//! equations, the integrator's and the sampler's alike (MuJoCo's one `mjData`): the declared
//! coordinates and rates at the last step, the friction's phases and the resting stops, the contact
//! rows kept, what the loops' monitors found, the events so far, and the efforts applied from
//! outside the program.

use crate::dynamics::angles::AngleReference;
use crate::dynamics::friction::{Phase, Switch};
use crate::dynamics::model::Model;
use crate::dynamics::stops::Impact;
use crate::simulate::constraints::LoopFindings;
use crate::simulate::inputs::Inputs;

#[derive(Clone, Debug)]
pub struct RunState {
    /// Declared coordinates and rates at the end of the last step (`follow_reference`):
    /// recovered angles stay continuous and keep their turns (a spring on an angle sees 3π/2,
    /// not −π/2, after one and a half turns), and the state there.
    pub reference: AngleReference,
    pub reference_state: Vec<f64>,
    /// Per joint with friction, its phase (set at the start and at its events).
    pub phases: Vec<Phase>,
    /// Per stop, whether its coordinate rests on it.
    pub resting: Vec<bool>,
    /// The contact rows kept for the run (decided at the first evaluation, see
    /// `contacts::independent_rows`).
    pub contact_rows: Option<Vec<usize>>,
    /// What the loops' monitors found: the stretches integrated with rows set aside, and the
    /// residuals, rank changes and singular passages of the steps and of the outputs.
    pub loops: LoopFindings,
    /// The impacts on the stops and the friction's changes of phase so far, in time order.
    pub impacts: Vec<Impact>,
    pub switches: Vec<Switch>,
    /// The efforts applied from outside the program (`Simulator`), read by every evaluation.
    pub inputs: Inputs,
    /// The values of the program's states (`state(x0)`) at the point being evaluated: the
    /// integrator's state past the mechanism's, set before each evaluation (`RunOde`).
    pub states: Vec<f64>,
}

impl RunState {
    /// The state of a run about to start from declared coordinates `reference` (taken at rest
    /// at t = 0 until the run's start sets it): every joint with friction slipping, no stop
    /// resting, nothing seen.
    pub fn new(model: &Model, reference: Vec<f64>) -> RunState {
        RunState {
            reference: AngleReference::at_rest(reference),
            reference_state: Vec::new(),
            phases: vec![Phase::Slipping(1.0); model.frictions.len()],
            resting: vec![false; model.stops.len()],
            contact_rows: None,
            loops: LoopFindings::default(),
            impacts: Vec::new(),
            switches: Vec::new(),
            inputs: Inputs::default(),
            states: model.states.iter().map(|s| s.initial).collect(),
        }
    }
}
