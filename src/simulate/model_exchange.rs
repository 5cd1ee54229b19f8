//! The equations of motion of a tree as an outside integrator uses them (FMI model exchange,
//! the units of `lsdc export-fmu`, docs/fmi.md): the integrator chooses the time and the state,
//! the equations give the state's derivatives there (positions' rates, and the accelerations of
//! the forward dynamics under the program's efforts and the inputs), and the outputs of a run's
//! sample. The state is the declared coordinates then their rates, in the order of
//! `Prepared::coordinate_names`.
//!
//! Only a tree whose state is its declared coordinates and whose equations have no events
//! qualifies (`refusal`): closed loops and couplings need lsdc's projection onto their
//! constraints, stops and friction's phases are events, sampled states are updated at
//! instants, and a spherical or free joint's quaternion leaves the unit sphere under steps
//! that do not know it (lsdc integrates it on SO(3)).

use super::inputs::Inputs;
use super::sample::Sample;
use super::sampler::Sampler;
use super::simulator::{features, input_velocities, start_system, Start};
use super::system::MechanicalSystem;
use crate::dynamics::compiled::EffortScratch;
use crate::dynamics::energy::conservative_forces;
use crate::dynamics::joint::JointType;
use crate::integrators::Feature;
use crate::prepare::Prepared;

/// Why the equations of `prepared` cannot be handed to an outside integrator, or `None` when
/// they can.
pub fn refusal(prepared: &Prepared) -> Option<String> {
    let model = &prepared.model;
    if let Some(join) = model.loops.first() {
        return Some(format!(
            "its closed loops (`{}`) need lsdc's projection onto their constraints",
            join.name
        ));
    }
    let found: Vec<&str> = (features(model).into_iter())
        .filter(|f| *f != Feature::GearedRotors)
        .map(Feature::description)
        .collect();
    if !found.is_empty() {
        return Some(format!(
            "its {} are events, constraints or states lsdc's own run handles",
            found.join(", ")
        ));
    }
    let turning = model.joints.iter().find(|j| j.kind != JointType::Chain);
    if let Some(joint) = turning {
        return Some(format!(
            "the orientation of `{}` is a quaternion, which lsdc integrates on SO(3): an outside integrator's steps would leave the unit sphere",
            joint.chain.name
        ));
    }
    None
}

/// The equations of a prepared tree with inputs, evaluated at the states an outside
/// integrator chooses.
pub struct Equations<'p> {
    system: MechanicalSystem<'p>,
    sampler: Sampler<'p>,
    /// For each declared coordinate, its place among the model's positions (and its rate's
    /// among the velocities).
    places: Vec<usize>,
    /// The start: declared coordinates then rates.
    start: Vec<f64>,
    /// The model's state (positions then velocities) and its derivative, reused.
    y: Vec<f64>,
    dydt: Vec<f64>,
}

impl<'p> Equations<'p> {
    /// The equations of `prepared` with efforts along the velocities named in `inputs` (held
    /// at zero until set), or why an outside integrator cannot integrate them.
    pub fn new(prepared: &'p Prepared, inputs: &[&str]) -> Result<Equations<'p>, String> {
        if let Some(reason) = refusal(prepared) {
            return Err(reason);
        }
        let model = &prepared.model;
        let inputs = Inputs::along(input_velocities(model, inputs)?);
        let start = Start {
            coordinates: &prepared.coordinates,
            rates: &prepared.rates,
        };
        let (system, y0) = start_system(prepared, &start, inputs)?;
        // A tree of chains: one position per velocity, each a declared coordinate.
        let names: Vec<String> = (0..model.nv).map(|i| model.velocity_name(i)).collect();
        let places: Option<Vec<usize>> = (prepared.coordinate_names.iter())
            .map(|name| names.iter().position(|n| n == name))
            .collect();
        let places = match places {
            Some(places) if places.len() == model.nq && model.nq == model.nv => places,
            _ => {
                return Err(
                    "its declared coordinates are not the positions of its equations".to_string(),
                )
            }
        };
        let n = places.len();
        let mut declared = vec![0.0; 2 * n];
        for (k, &place) in places.iter().enumerate() {
            declared[k] = y0[place];
            declared[n + k] = y0[n + place];
        }
        let sampler = Sampler {
            conservative: conservative_forces(model),
            reactions: false,
            outputs: &prepared.outputs,
            output_scratch: EffortScratch::default(),
            pending: Vec::new(),
            unsettled: Vec::new(),
            segment: None,
        };
        Ok(Equations {
            system,
            sampler,
            places,
            start: declared,
            y: y0,
            dydt: vec![0.0; 2 * n],
        })
    }

    /// The number of continuous states: twice the number of declared coordinates.
    pub fn state_count(&self) -> usize {
        2 * self.places.len()
    }

    /// The state the program starts from: its declared coordinates, then their rates.
    pub fn start(&self) -> &[f64] {
        &self.start
    }

    /// Sets the efforts along the inputs (in their order), used until set again.
    pub fn set_inputs(&mut self, efforts: &[f64]) -> Result<(), String> {
        let held = &mut self.system.state.inputs.held;
        if efforts.len() != held.len() {
            return Err(format!(
                "{} input efforts given for {} inputs",
                efforts.len(),
                held.len()
            ));
        }
        held.copy_from_slice(efforts);
        Ok(())
    }

    /// The model's state of the declared state `x`.
    fn load(&mut self, x: &[f64]) -> Result<(), String> {
        let n = self.places.len();
        if x.len() != 2 * n {
            return Err(format!("{} states given for {}", x.len(), 2 * n));
        }
        for (k, &place) in self.places.iter().enumerate() {
            self.y[place] = x[k];
            self.y[n + place] = x[n + k];
        }
        Ok(())
    }

    /// The derivatives of the state `x` at time `t` into `dxdt`: the rates, then the
    /// accelerations (the forward dynamics under the program's efforts and the inputs).
    pub fn derivatives(&mut self, t: f64, x: &[f64], dxdt: &mut [f64]) -> Result<(), String> {
        self.load(x)?;
        let n = self.places.len();
        if dxdt.len() != 2 * n {
            return Err(format!(
                "{} derivatives asked for {} states",
                dxdt.len(),
                2 * n
            ));
        }
        (self.system)
            .derivative(t, &self.y, &mut self.dydt)
            .map_err(|e| format!("the equations cannot be evaluated at t = {t}: {e}"))?;
        for (k, &place) in self.places.iter().enumerate() {
            dxdt[k] = self.dydt[place];
            dxdt[n + k] = self.dydt[n + place];
        }
        Ok(())
    }

    /// The run's sample at the state `x` at time `t`: coordinates, rates, energies and the
    /// program's outputs.
    pub fn sample(&mut self, t: f64, x: &[f64]) -> Result<Sample, String> {
        self.load(x)?;
        let (sampler, y) = (&mut self.sampler, &self.y);
        let sampled = (self.system).sampling(|system| sampler.sample(system, t, y));
        sampled.map_err(|e| format!("the outputs cannot be evaluated at t = {t}: {e}"))
    }
}
