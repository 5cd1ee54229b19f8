//! Named frames on the numbered mechanism: a frame the program names (or a body's reference
//! frame) resolved to a body number and a pose on that body, and its state — position,
//! orientation, velocity — at given coordinates and rates.

use nalgebra::{UnitQuaternion, Vector3};
use serde::Serialize;

use super::eval::{describe, EvalError};
use super::forward::{forward, Configuration};
use super::model::{constant_pose, KinematicModel};
use crate::diag::suggest;
use crate::elab::mechanism::Mechanism;
use crate::spatial::{self, Pose};

/// A frame of the mechanism: on body `body` (0 = earth), at `offset` from its reference frame.
#[derive(Clone, Debug)]
pub struct FramePoint {
    pub name: String,
    pub body: usize,
    pub offset: Pose,
}

/// Resolves a frame name (see `Mechanism::frame_named`) on the numbered tree; the error says
/// why, with the closest known name.
pub fn resolve(
    mechanism: &Mechanism,
    model: &KinematicModel,
    name: &str,
) -> Result<FramePoint, String> {
    let Some(frame) = mechanism.frame_named(name) else {
        let names = mechanism.frame_names();
        let hint = suggest::did_you_mean(name, names.iter().map(String::as_str))
            .map_or(String::new(), |close| format!(" (did you mean `{close}`?)"));
        return Err(format!(
            "no frame named `{name}`{hint}: name a frame with `let {name} = ... @ body;`, or give a body's name"
        ));
    };
    let offset = constant_pose(&frame.displacement, &model.unknowns).map_err(|e| {
        format!(
            "the frame `{name}` is not constant on its body: {}",
            describe(&e, mechanism)
        )
    })?;
    let body = model.topology.number(frame.body);
    Ok(FramePoint {
        name: name.to_string(),
        body,
        offset,
    })
}

/// A frame's state in the fixed frame.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct FrameState {
    pub position: [f64; 3],
    /// Unit quaternion `[w, x, y, z]` of the frame's axes in the fixed axes.
    pub orientation: [f64; 4],
    /// Velocity of the frame's origin.
    pub velocity: [f64; 3],
    pub angular_velocity: [f64; 3],
}

/// The names of a frame state's components, in [`FrameState::values`] order.
pub const STATE_COMPONENTS: [&str; 13] = [
    "x", "y", "z", "qw", "qx", "qy", "qz", "vx", "vy", "vz", "wx", "wy", "wz",
];

impl FrameState {
    /// The 13 numbers, in [`STATE_COMPONENTS`] order.
    #[cfg(lsdc_internals)]
    pub fn values(&self) -> impl Iterator<Item = f64> + '_ {
        self.position
            .iter()
            .chain(&self.orientation)
            .chain(&self.velocity)
            .chain(&self.angular_velocity)
            .copied()
    }
}

impl FramePoint {
    /// The frame's pose in the fixed frame.
    pub fn pose(&self, configuration: &Configuration) -> Pose {
        configuration.poses[self.body] * self.offset
    }

    /// The frame's state for the configuration and coordinate rates `rates`.
    pub fn state(&self, configuration: &Configuration, rates: &[f64]) -> FrameState {
        let pose = self.pose(configuration);
        let twist = configuration.twist(self.body, rates);
        let origin = pose.translation.vector;
        FrameState {
            position: array(&origin),
            orientation: quaternion(&pose.rotation),
            velocity: array(&spatial::point_velocity(&twist, &origin)),
            angular_velocity: array(&spatial::angular(&twist)),
        }
    }
}

fn array(v: &Vector3<f64>) -> [f64; 3] {
    [v.x, v.y, v.z]
}

/// `[w, x, y, z]`, with w ≥ 0 so that a frame at rest always gives the same four numbers.
pub fn quaternion(q: &UnitQuaternion<f64>) -> [f64; 4] {
    let sign = if q.w < 0.0 { -1.0 } else { 1.0 };
    [q.w, q.i, q.j, q.k].map(|c| sign * c + 0.0)
}

/// The states of `frames` at declared coordinates and rates, in order.
pub fn states(
    model: &KinematicModel,
    frames: &[FramePoint],
    coordinates: &[f64],
    rates: &[f64],
) -> Result<Vec<FrameState>, EvalError> {
    let configuration = forward(model, coordinates)?;
    Ok(frames
        .iter()
        .map(|frame| frame.state(&configuration, rates))
        .collect())
}
