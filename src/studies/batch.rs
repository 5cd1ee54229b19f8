//! Batch evaluation (`lsdc eval`): the recursive algorithms at a list of states, for
//! cross-checking with other multibody libraries. For each state (q, v and a or τ) it computes
//! the inverse dynamics (RNEA), the mass matrix (CRBA), the forward dynamics (ABA) and the pose
//! of every body in the fixed frame.
//!
//! The efforts are the program's own (`apply` and link efforts, evaluated at time 0): a URDF
//! imported with gravity applies each link's weight. A mechanism with loops is evaluated on its
//! spanning tree, without the complementary links; the output names them.
//!
//! Errors are per quantity: when one cannot be computed at a state (ABA where the mass matrix
//! is singular, as with massless links on moving joints; RNEA and ABA when an effort cannot be
//! evaluated), it is `null` and the state's `errors` gives the reason under its name, while the
//! other quantities of the state are kept. A state fails as a whole, stopping the batch with its
//! index, only for its input (a list of the wrong length, a number that is not finite, a
//! quaternion that is not unit) or when the mechanism's geometry cannot be evaluated at it.
//!
//! The JSON output:
//!
//! ```text
//! {"positions": [names of q], "velocities": [names of v],
//!  "complementary_links_ignored": [...],            (only for a mechanism with loops)
//!  "states": [{"rnea": [τ] | null,                  (only when `a` is given)
//!              "crba": [[M by rows]],
//!              "aba": [a] | null,                   (only when `tau` is given)
//!              "frames": [{"body", "translation", "rotation": [rows]}],
//!              "derivatives": {"efforts_held", "rnea": {"dq", "dv"}, "aba": {"dq", "dv", "dtau"},
//!                              "crba": [∂M/∂q_j]} | null,   (only with `--derivatives`)
//!              "errors": {"aba": "message"}}]}      (only when a quantity failed)
//! ```

use std::collections::BTreeMap;
use std::fmt;

use nalgebra::DVector;
use serde::ser::SerializeMap;
use serde::{Deserialize, Serialize, Serializer};

use super::batch_derivatives::{state_derivatives, StateDerivatives};
use crate::dynamics::algorithms::{aba, crba, forward_kinematics, rnea};
use crate::dynamics::efforts::Efforts;
use crate::dynamics::joint::JointType;
use crate::dynamics::loops::Stabilisation;
use crate::dynamics::model::Model;
use crate::prepare::Prepared;
use crate::simulate::system::{MechanicalSystem, SystemError};

/// One state to evaluate: positions, velocities (zero when absent), and accelerations (for the
/// inverse dynamics) or generalised forces (for the forward dynamics), or both.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct StateInput {
    pub q: Vec<f64>,
    #[serde(default)]
    pub v: Option<Vec<f64>>,
    #[serde(default)]
    pub a: Option<Vec<f64>>,
    #[serde(default)]
    pub tau: Option<Vec<f64>>,
}

/// Reads a states file's text: `{"states": [...]}` or the bare list. Its form is told apart
/// before the states are read, so that an error names what is wrong in them (`missing field
/// `q``) rather than the two forms it matches neither of.
pub fn parse_states(text: &str) -> Result<Vec<StateInput>, StatesError> {
    use serde::de::Error as _;
    use serde_json::Value;
    let value: Value = serde_json::from_str(text).map_err(StatesError::Syntax)?;
    let list = match value {
        Value::Object(mut fields) if fields.len() == 1 && fields.contains_key("states") => {
            fields.remove("states").unwrap_or_default()
        }
        list @ Value::Array(_) => list,
        _ => {
            let message = "the file is neither an object with one `states` list nor a list";
            return Err(StatesError::Syntax(serde_json::Error::custom(message)));
        }
    };
    serde_json::from_value(list).map_err(StatesError::Syntax)
}

/// A body's pose in the fixed frame: its origin and the rotation matrix (rows) whose columns
/// are its axes.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct FramePose {
    pub body: String,
    pub translation: [f64; 3],
    pub rotation: [[f64; 3]; 3],
}

/// The quantities at one state. In JSON, `rnea` (`aba`) is present when `a` (`tau`) was given,
/// `null` when it could not be computed, and `errors` only when a quantity could not be.
#[derive(Clone, Debug, Deserialize)]
pub struct StateOutput {
    /// Generalised forces that give the accelerations `a` (when `a` was given and they could be
    /// computed).
    #[serde(default)]
    pub rnea: Option<Vec<f64>>,
    /// The mass matrix, by rows.
    pub crba: Vec<Vec<f64>>,
    /// Accelerations under the generalised forces `tau` (when `tau` was given and they could be
    /// computed: not where the mass matrix is singular).
    #[serde(default)]
    pub aba: Option<Vec<f64>>,
    pub frames: Vec<FramePose>,
    /// The derivatives of RNEA, ABA and CRBA (`--derivatives`).
    #[serde(default)]
    pub derivatives: Option<StateDerivatives>,
    /// Why a quantity could not be computed, by its name (`rnea`, `aba`).
    #[serde(default)]
    pub errors: BTreeMap<String, String>,
}

impl StateOutput {
    /// Whether the JSON shows `quantity`: it was computed, or it was asked for and failed.
    fn shows(&self, value: &Option<Vec<f64>>, quantity: &str) -> bool {
        value.is_some() || self.errors.contains_key(quantity)
    }
}

impl Serialize for StateOutput {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        let mut map = serializer.serialize_map(None)?;
        if self.shows(&self.rnea, "rnea") {
            map.serialize_entry("rnea", &self.rnea)?;
        }
        map.serialize_entry("crba", &self.crba)?;
        if self.shows(&self.aba, "aba") {
            map.serialize_entry("aba", &self.aba)?;
        }
        map.serialize_entry("frames", &self.frames)?;
        if self.derivatives.is_some() || self.errors.contains_key("derivatives") {
            map.serialize_entry("derivatives", &self.derivatives)?;
        }
        if !self.errors.is_empty() {
            map.serialize_entry("errors", &self.errors)?;
        }
        map.end()
    }
}

#[derive(Clone, Debug, Serialize)]
pub struct Evaluation {
    /// Names of the entries of q and of v (and a, τ, and the rows of the mass matrix).
    pub positions: Vec<String>,
    pub velocities: Vec<String>,
    /// Complementary links left out: the algorithms work on the spanning tree.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub complementary_links_ignored: Vec<String>,
    pub states: Vec<StateOutput>,
}

/// Names of the entries of q: `join.coordinate` for a chain, the position `join.px..pz` and
/// the unit quaternion `join.qw..qz` (w first) for a free or spherical joint.
pub fn position_names(model: &Model) -> Vec<String> {
    let mut names = Vec::with_capacity(model.nq);
    for joint in &model.joints {
        let name = &joint.chain.name;
        match joint.kind {
            JointType::Chain => names.extend(
                joint
                    .chain
                    .coordinate_names
                    .iter()
                    .map(|c| format!("{name}.{c}")),
            ),
            JointType::Spherical { .. } => {
                names.extend(["qw", "qx", "qy", "qz"].map(|c| format!("{name}.{c}")))
            }
            JointType::Free { .. } => names
                .extend(["px", "py", "pz", "qw", "qx", "qy", "qz"].map(|c| format!("{name}.{c}"))),
        }
    }
    names
}

/// Evaluates every state. A quantity that cannot be computed at a state is left out of it, with
/// the reason in its `errors`; a state whose input is wrong, or at which the geometry cannot be
/// evaluated, stops the batch with its index and the reason.
pub fn evaluate_states(
    prepared: &Prepared,
    states: &[StateInput],
) -> Result<Evaluation, StatesError> {
    evaluate_states_with(prepared, states, false)
}

/// `evaluate_states`, with the derivatives of each quantity when `derivatives` is set
/// (`batch_derivatives`).
pub fn evaluate_states_with(
    prepared: &Prepared,
    states: &[StateInput],
    derivatives: bool,
) -> Result<Evaluation, StatesError> {
    let model = &prepared.model;
    let reference = prepared.coordinates.clone();
    let mut system = MechanicalSystem::new(model, reference, Stabilisation::None);
    let mut outputs = Vec::with_capacity(states.len());
    for (index, state) in states.iter().enumerate() {
        let output = evaluate_state(&mut system, state, derivatives)
            .map_err(|error| StatesError::State { index, error })?;
        outputs.push(output);
    }
    Ok(Evaluation {
        positions: position_names(model),
        velocities: (0..model.nv).map(|i| model.velocity_name(i)).collect(),
        complementary_links_ignored: model.loops.iter().map(|l| l.name.clone()).collect(),
        states: outputs,
    })
}

/// Checks positions and velocities: their lengths, finite entries, unit quaternions.
pub fn check_state(model: &Model, q: &[f64], v: &[f64]) -> Result<(), StateError> {
    check_length("q", q, model.nq)?;
    check_length("v", v, model.nv)?;
    check_quaternions(model, q)
}

/// Checks that `values` has `expected` entries, all finite.
pub fn check_length(
    quantity: &'static str,
    values: &[f64],
    expected: usize,
) -> Result<(), StateError> {
    if values.len() != expected {
        return Err(StateError::Length {
            quantity,
            given: values.len(),
            expected,
        });
    }
    if let Some(index) = values.iter().position(|x| !x.is_finite()) {
        return Err(StateError::NotFinite { quantity, index });
    }
    Ok(())
}

/// Quaternions must be unit: a tool that gives another one means something else by q.
fn check_quaternions(model: &Model, q: &[f64]) -> Result<(), StateError> {
    for joint in &model.joints {
        let start = match joint.kind {
            JointType::Chain => continue,
            JointType::Spherical { .. } => joint.q_offset,
            JointType::Free { .. } => joint.q_offset + 3,
        };
        let norm = q[start..start + 4]
            .iter()
            .map(|x| x * x)
            .sum::<f64>()
            .sqrt();
        if (norm - 1.0).abs() > 1e-9 {
            return Err(StateError::NotUnitQuaternion {
                join: joint.chain.name.clone(),
                start,
                norm,
            });
        }
    }
    Ok(())
}

fn evaluate_state(
    system: &mut MechanicalSystem<'_>,
    state: &StateInput,
    derivatives: bool,
) -> Result<StateOutput, StateError> {
    let model = system.model;
    let zero = vec![0.0; model.nv];
    let v = state.v.as_deref().unwrap_or(&zero);
    check_state(model, &state.q, v)?;
    if let Some(a) = &state.a {
        check_length("a", a, model.nv)?;
    }
    if let Some(tau) = &state.tau {
        check_length("tau", tau, model.nv)?;
    }
    let q_full = [state.q.as_slice(), &vec![0.0; model.nc]].concat();
    let v_full = [v, &vec![0.0; model.nc]].concat();
    let efforts = system.efforts(0.0, &q_full, &v_full);
    if efforts.is_err() {
        // Without the kinematics nothing can be computed; with it, only RNEA and ABA need the
        // efforts.
        forward_kinematics(model, &mut system.scratch.data, &state.q, v)
            .map_err(|e| StateError::Geometry(e.into()))?;
    }
    let frames = frame_poses(system);
    let mut errors = BTreeMap::new();
    let rnea_tau = match (&state.a, &efforts) {
        (None, _) => None,
        (Some(_), Err(e)) => kept(&mut errors, "rnea", Err(e.clone())),
        (Some(a), Ok(efforts)) => {
            let tau = inverse_dynamics(system, &state.q, v, a, efforts);
            kept(&mut errors, "rnea", tau)
        }
    };
    let accelerations = match (&state.tau, &efforts) {
        (None, _) => None,
        (Some(_), Err(e)) => kept(&mut errors, "aba", Err(e.clone())),
        (Some(tau), Ok(efforts)) => {
            let a = forward_dynamics(system, &state.q, v, tau, efforts);
            kept(&mut errors, "aba", a)
        }
    };
    let mass = crba(model, &mut system.scratch.data, &state.q)
        .map_err(|e| StateError::Geometry(e.into()))?;
    let crba_rows = mass
        .row_iter()
        .map(|row| row.iter().copied().collect())
        .collect();
    let derivatives = match (derivatives, &efforts) {
        (false, _) => None,
        (true, Err(e)) => {
            errors.insert("derivatives".into(), e.to_string());
            None
        }
        (true, Ok(efforts)) => {
            let total = state
                .tau
                .as_ref()
                .map(|tau| DVector::from_column_slice(tau) + efforts.tau.rows(0, model.nv));
            let changes = match system.effort_derivatives(0.0, &q_full, &v_full) {
                Ok(found) => found.map(|d| d.efforts.clone()),
                Err(e) => {
                    errors.insert("derivatives".into(), e.to_string());
                    None
                }
            };
            let found = state_derivatives(
                model,
                &mut system.scratch.data,
                (&state.q, v),
                (state.a.as_deref(), total.as_ref().map(|t| t.as_slice())),
                &efforts.external,
                changes.as_ref(),
            );
            found
                .map_err(|e| errors.insert("derivatives".into(), e))
                .ok()
        }
    };
    Ok(StateOutput {
        rnea: rnea_tau,
        crba: crba_rows,
        aba: accelerations,
        frames,
        derivatives,
        errors,
    })
}

/// The generalised forces along the velocities that give the accelerations `a` at (q, v)
/// together with the program's `efforts` (evaluated at the state): τ = RNEA(q, v, a) − τ_f.
/// The system's data must hold the forward kinematics of (q, v), as `efforts` leaves it.
pub fn inverse_dynamics(
    system: &mut MechanicalSystem<'_>,
    q: &[f64],
    v: &[f64],
    a: &[f64],
    efforts: &Efforts,
) -> Result<Vec<f64>, SystemError> {
    let model = system.model;
    let tau = rnea(model, &mut system.scratch.data, q, v, a, &efforts.external)?;
    let tau = tau - efforts.tau.rows(0, model.nv);
    Ok(tau.iter().copied().collect())
}

/// The accelerations at (q, v) under the generalised forces `tau` added to the program's
/// `efforts` (evaluated at the state): ABA. Fails where the mass matrix is singular.
pub fn forward_dynamics(
    system: &mut MechanicalSystem<'_>,
    q: &[f64],
    v: &[f64],
    tau: &[f64],
    efforts: &Efforts,
) -> Result<Vec<f64>, SystemError> {
    let model = system.model;
    let total = DVector::from_column_slice(tau) + efforts.tau.rows(0, model.nv);
    let data = &mut system.scratch.data;
    let a = aba(model, data, q, v, total.as_slice(), &efforts.external)
        .map_err(|e| system.dynamics_error(&e))?;
    Ok(a.iter().copied().collect())
}

/// The value of a quantity, or `None` with its error's message recorded under its name.
fn kept(
    errors: &mut BTreeMap<String, String>,
    quantity: &str,
    value: Result<Vec<f64>, SystemError>,
) -> Option<Vec<f64>> {
    value
        .map_err(|e| errors.insert(quantity.to_string(), e.to_string()))
        .ok()
}

/// World poses of the bodies; the system's data must hold the forward kinematics of the state.
fn frame_poses(system: &MechanicalSystem<'_>) -> Vec<FramePose> {
    let model = system.model;
    (1..=model.body_count())
        .map(|i| {
            let pose = &system.scratch.data.world[i];
            let r = pose.rotation.to_rotation_matrix();
            let m = r.matrix();
            FramePose {
                body: model.body_names[i - 1].clone(),
                translation: [pose.translation.x, pose.translation.y, pose.translation.z],
                rotation: [0, 1, 2].map(|row| [m[(row, 0)], m[(row, 1)], m[(row, 2)]]),
            }
        })
        .collect()
}

/// Why a batch of states cannot be evaluated.
#[derive(Debug)]
pub enum StatesError {
    /// The states file is not JSON of the expected shape.
    Syntax(serde_json::Error),
    /// The state at `index` (from 0) fails as a whole.
    State { index: usize, error: StateError },
}

/// Why one state fails as a whole: its input, or the geometry at it.
#[derive(Debug)]
pub enum StateError {
    /// `quantity` (`q`, `v`, `a` or `tau`) has `given` entries instead of `expected`.
    Length {
        quantity: &'static str,
        given: usize,
        expected: usize,
    },
    /// Entry `index` of `quantity` is not a finite number.
    NotFinite {
        quantity: &'static str,
        index: usize,
    },
    /// The quaternion of `join`, `q[start..start + 4]`, has this norm instead of 1.
    NotUnitQuaternion {
        join: String,
        start: usize,
        norm: f64,
    },
    /// The kinematics or the mass matrix cannot be evaluated at the state.
    Geometry(SystemError),
    /// A quantity evaluated alone (`state_batch`: RNEA or ABA) cannot be computed at the
    /// state: the efforts cannot be evaluated, or the mass matrix is singular.
    Unavailable {
        quantity: &'static str,
        error: SystemError,
    },
}

impl fmt::Display for StatesError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            StatesError::Syntax(e) => write!(
                f,
                "{e}\nhelp: expected {{\"states\": [{{\"q\": [...], \"v\": [...], \"a\": [...], \"tau\": [...]}}, ...]}} with `v`, `a` and `tau` optional"
            ),
            StatesError::State { index, error } => write!(f, "state {index}: {error}"),
        }
    }
}

impl fmt::Display for StateError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            StateError::Length {
                quantity,
                given,
                expected,
            } => write!(
                f,
                "`{quantity}` has {given} entries, the mechanism has {expected}"
            ),
            StateError::NotFinite { quantity, index } => {
                write!(f, "`{quantity}[{index}]` is not a finite number")
            }
            StateError::NotUnitQuaternion { join, start, norm } => write!(
                f,
                "the quaternion of `{join}` (q[{start}..{}]) has norm {norm}, not 1",
                start + 4
            ),
            StateError::Geometry(error) => write!(f, "{error}"),
            StateError::Unavailable { quantity, error } => write!(f, "{quantity}: {error}"),
        }
    }
}

impl std::error::Error for StatesError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            StatesError::Syntax(e) => Some(e),
            StatesError::State { error, .. } => Some(error),
        }
    }
}

impl std::error::Error for StateError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            StateError::Geometry(error) | StateError::Unavailable { error, .. } => Some(error),
            _ => None,
        }
    }
}
