//! What a run writes at each output time.

use serde::Serialize;

#[derive(Clone, Debug, Serialize)]
pub struct Sample {
    pub time: f64,
    /// Declared coordinates and their rates, in `Simulation::coordinate_names` order.
    pub coordinates: Vec<f64>,
    pub rates: Vec<f64>,
    pub kinetic_energy: f64,
    /// Potential energy of the conservative efforts (constant forces in the fixed basis such as
    /// gravity, efforts that declare their potential); the others' work is `work`. Always known
    /// from a run; `None` only where a sample is read back without it.
    pub potential_energy: Option<f64>,
    /// The work done since the start by the efforts that derive from no potential (dampers,
    /// motors, …), when there are such efforts.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub work: Option<f64>,
    /// Kinetic energy + potential energy of the conservative efforts − `work`: constant up to
    /// the integration's error.
    #[serde(skip)]
    pub balance: Option<f64>,
    /// Total momentum in the fixed frame: angular (about the origin), then linear.
    pub momentum: [f64; 6],
    /// When asked for: the wrench each join transmits to its second body, at the join, in the
    /// fixed axes (moment, then force; 6 per join, in `Simulation::reaction_names` order).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub reactions: Vec<f64>,
}

#[derive(Clone, Copy, Debug, Serialize)]
pub struct MomentumDrift {
    pub linear: f64,
    pub angular: f64,
}
