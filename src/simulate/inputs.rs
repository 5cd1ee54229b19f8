//! Efforts that the caller of a run applies from outside the program (`Simulator`): generalised
//! efforts along chosen velocities of the model (a torque along a revolute's angle, a force
//! along a slider), the sum of a value held between steps (a zero-order hold, as a sampled
//! controller applies it) and of a law of the time and the declared coordinates and rates,
//! evaluated with the program's own efforts at every evaluation of the equations of motion (at
//! every stage of a step, so that a law written in Rust gives the motion the same law written
//! in LSD gives).

use std::fmt;
use std::sync::Arc;

use nalgebra::DVector;

/// A law of the inputs: `law(t, coordinates, rates, efforts)` writes the efforts along the
/// inputs (in their order) at time t, from the declared coordinates and rates (in the order of
/// `Simulation::coordinate_names`). A function of the state only: the integrator evaluates it
/// at the stages of its steps, some of which it rejects.
pub type InputLaw = Arc<dyn Fn(f64, &[f64], &[f64], &mut [f64]) + Send + Sync>;

/// The inputs of a run, held in its state (`RunState::inputs`) and added to the efforts of
/// every evaluation.
#[derive(Clone, Default)]
pub struct Inputs {
    /// The velocities of the model the inputs act along, one each.
    pub velocities: Vec<usize>,
    /// The efforts held since they were last set.
    pub held: Vec<f64>,
    pub law: Option<InputLaw>,
    /// The law's efforts at the last evaluation.
    from_law: Vec<f64>,
}

impl fmt::Debug for Inputs {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Inputs")
            .field("velocities", &self.velocities)
            .field("held", &self.held)
            .field("law", &self.law.is_some())
            .finish()
    }
}

impl Inputs {
    /// Inputs along `velocities`, held at zero, without a law.
    pub fn along(velocities: Vec<usize>) -> Inputs {
        Inputs {
            held: vec![0.0; velocities.len()],
            from_law: vec![0.0; velocities.len()],
            velocities,
            law: None,
        }
    }

    /// Whether the run has inputs: its efforts are evaluated even where the program has none.
    pub fn any(&self) -> bool {
        !self.velocities.is_empty()
    }

    /// Adds the inputs at time t to the generalised efforts `tau`, given the declared
    /// coordinates and rates (read by the law) and the model's velocities `v`; returns their
    /// power (they derive from no potential: the energy balance counts their work).
    pub fn add_to(
        &mut self,
        t: f64,
        (coordinates, rates): (&[f64], &[f64]),
        v: &[f64],
        tau: &mut DVector<f64>,
    ) -> f64 {
        if let Some(law) = &self.law {
            self.from_law.fill(0.0);
            law(t, coordinates, rates, &mut self.from_law);
        }
        let mut power = 0.0;
        for (k, &velocity) in self.velocities.iter().enumerate() {
            let from_law = if self.law.is_some() {
                self.from_law[k]
            } else {
                0.0
            };
            let effort = self.held[k] + from_law;
            tau[velocity] += effort;
            power += effort * v[velocity];
        }
        power
    }
}
