//! Batch evaluation (`lsdc eval`): the recursive algorithms at a list of states, for
//! cross-checking with other multibody libraries. For each state (q, v and a or τ) it computes
//! the inverse dynamics (RNEA), the mass matrix (CRBA), the forward dynamics (ABA) and the pose
//! of every body in the fixed frame.
//!
//! The efforts are the program's own (`apply` and link efforts, evaluated at time 0): a URDF
//! imported with gravity applies each link's weight. A mechanism with loops is evaluated on its
//! spanning tree, without the complementary links; the output names them.

use std::cell::RefCell;
use std::rc::Rc;

use nalgebra::DVector;
use serde::{Deserialize, Serialize};

use super::prepare::Prepared;
use super::system::{evaluation_message, MechanicalSystem};
use crate::dynamics::algorithms::{aba, crba, rnea};
use crate::dynamics::joint::JointType;
use crate::dynamics::loops::Stabilisation;
use crate::dynamics::model::Model;

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

/// The states file: `{"states": [...]}` or the bare list.
#[derive(Deserialize)]
#[serde(untagged)]
enum StatesFile {
    Wrapped { states: Vec<StateInput> },
    Bare(Vec<StateInput>),
}

/// Reads a states file's text.
pub fn parse_states(text: &str) -> Result<Vec<StateInput>, String> {
    match serde_json::from_str::<StatesFile>(text) {
        Ok(StatesFile::Wrapped { states }) | Ok(StatesFile::Bare(states)) => Ok(states),
        Err(e) => Err(format!(
            "{e}\nhelp: expected {{\"states\": [{{\"q\": [...], \"v\": [...], \"a\": [...], \"tau\": [...]}}, ...]}} with `v`, `a` and `tau` optional"
        )),
    }
}

/// A body's pose in the fixed frame: its origin and the rotation matrix (rows) whose columns
/// are its axes.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct FramePose {
    pub body: String,
    pub translation: [f64; 3],
    pub rotation: [[f64; 3]; 3],
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct StateOutput {
    /// Generalised forces that give the accelerations `a` (present when `a` was given).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rnea: Option<Vec<f64>>,
    /// The mass matrix, by rows.
    pub crba: Vec<Vec<f64>>,
    /// Accelerations under the generalised forces `tau` (present when `tau` was given).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub aba: Option<Vec<f64>>,
    pub frames: Vec<FramePose>,
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
            JointType::Chain => names.extend(joint.chain.coordinate_names.iter().map(|c| format!("{name}.{c}"))),
            JointType::Spherical { .. } => names.extend(["qw", "qx", "qy", "qz"].map(|c| format!("{name}.{c}"))),
            JointType::Free { .. } => names.extend(["px", "py", "pz", "qw", "qx", "qy", "qz"].map(|c| format!("{name}.{c}"))),
        }
    }
    names
}

/// Evaluates every state; the first state that cannot be evaluated stops the batch with its
/// index and the reason.
pub fn evaluate_states(prepared: &Prepared, states: &[StateInput]) -> Result<Evaluation, String> {
    let model = &prepared.model;
    let reference = Rc::new(RefCell::new(prepared.coordinates.clone()));
    let mut system = MechanicalSystem::new(model, reference, Stabilisation::None);
    let mut outputs = Vec::with_capacity(states.len());
    for (index, state) in states.iter().enumerate() {
        let output = evaluate_state(&mut system, state).map_err(|e| format!("state {index}: {e}"))?;
        outputs.push(output);
    }
    Ok(Evaluation {
        positions: position_names(model),
        velocities: (0..model.nv).map(|i| model.velocity_name(i)).collect(),
        complementary_links_ignored: model.loops.iter().map(|l| l.name.clone()).collect(),
        states: outputs,
    })
}

fn check_length(what: &str, values: &[f64], expected: usize) -> Result<(), String> {
    if values.len() != expected {
        return Err(format!("`{what}` has {} entries, the mechanism has {expected}", values.len()));
    }
    if let Some(i) = values.iter().position(|x| !x.is_finite()) {
        return Err(format!("`{what}[{i}]` is not a finite number"));
    }
    Ok(())
}

/// Quaternions must be unit: a tool that gives another one means something else by q.
fn check_quaternions(model: &Model, q: &[f64]) -> Result<(), String> {
    for joint in &model.joints {
        let start = match joint.kind {
            JointType::Chain => continue,
            JointType::Spherical { .. } => joint.q_offset,
            JointType::Free { .. } => joint.q_offset + 3,
        };
        let norm = q[start..start + 4].iter().map(|x| x * x).sum::<f64>().sqrt();
        if (norm - 1.0).abs() > 1e-9 {
            return Err(format!("the quaternion of `{}` (q[{start}..{}]) has norm {norm}, not 1", joint.chain.name, start + 4));
        }
    }
    Ok(())
}

fn evaluate_state(system: &mut MechanicalSystem<'_>, state: &StateInput) -> Result<StateOutput, String> {
    let model = system.model;
    let zero = vec![0.0; model.nv];
    let v = state.v.as_deref().unwrap_or(&zero);
    check_length("q", &state.q, model.nq)?;
    check_length("v", v, model.nv)?;
    check_quaternions(model, &state.q)?;
    let q_full = [state.q.as_slice(), &vec![0.0; model.nc]].concat();
    let v_full = [v, &vec![0.0; model.nc]].concat();
    let efforts = system.efforts(0.0, &q_full, &v_full)?;
    let link_tau = efforts.tau.rows(0, model.nv).into_owned();
    let frames = frame_poses(system);
    let rnea_tau = match &state.a {
        Some(a) => {
            check_length("a", a, model.nv)?;
            let tau = rnea(model, &mut system.data, &state.q, v, a, &efforts.external).map_err(|e| evaluation_message(&e))?;
            Some((tau - &link_tau).iter().copied().collect())
        }
        None => None,
    };
    let accelerations = match &state.tau {
        Some(tau) => {
            check_length("tau", tau, model.nv)?;
            let total = DVector::from_column_slice(tau) + &link_tau;
            let a = aba(model, &mut system.data, &state.q, v, total.as_slice(), &efforts.external).map_err(|e| system.dynamics_message(&e))?;
            Some(a.iter().copied().collect())
        }
        None => None,
    };
    let mass = crba(model, &mut system.data, &state.q).map_err(|e| evaluation_message(&e))?;
    let crba_rows = mass.row_iter().map(|row| row.iter().copied().collect()).collect();
    Ok(StateOutput { rnea: rnea_tau, crba: crba_rows, aba: accelerations, frames })
}

/// World poses of the bodies; the system's data must hold the forward kinematics of the state.
fn frame_poses(system: &MechanicalSystem<'_>) -> Vec<FramePose> {
    let model = system.model;
    (1..=model.body_count())
        .map(|i| {
            let pose = &system.data.world[i];
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
