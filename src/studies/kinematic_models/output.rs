//! What the kinematic models map: the actuated (or named) coordinates, and the frame and the
//! part of its motion the models give.

use serde::Serialize;

use super::error::KinematicsError;
use crate::kinematics::frames::FramePoint;
use crate::prepare::Prepared;
use crate::studies::statics::{velocity_index, StaticsError};

/// What part of a frame's motion the models map to.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum OutputKind {
    /// The velocity of the frame's origin (3 rows).
    Point,
    /// The frame's twist: angular velocity, then the velocity of its origin (6 rows).
    Twist,
}

/// The frame the models map to, and which part of its motion.
#[derive(Clone, Debug)]
pub struct Output {
    pub frame: FramePoint,
    pub kind: OutputKind,
}

impl Output {
    /// `frame.vx`, … for each row of the models.
    pub fn names(&self) -> Vec<String> {
        let components: &[&str] = match self.kind {
            OutputKind::Point => &["vx", "vy", "vz"],
            OutputKind::Twist => &["wx", "wy", "wz", "vx", "vy", "vz"],
        };
        (components.iter())
            .map(|c| format!("{}.{c}", self.frame.name))
            .collect()
    }

    pub(crate) fn rows(&self) -> usize {
        match self.kind {
            OutputKind::Point => 3,
            OutputKind::Twist => 6,
        }
    }

    /// Whether row r is a linear velocity (in metres per second).
    pub(crate) fn linear(&self, r: usize) -> bool {
        self.kind == OutputKind::Point || r >= 3
    }
}

/// The actuated (or named) coordinates: their names and their indices among the state's
/// velocities.
#[derive(Clone, Debug)]
pub struct Actuation {
    pub names: Vec<String>,
    pub velocities: Vec<usize>,
}

/// The coordinates `names` (`join.coordinate`); without any, every velocity of a tree (a
/// mechanism with loops needs them named).
pub fn actuation(prepared: &Prepared, names: &[String]) -> Result<Actuation, KinematicsError> {
    let model = &prepared.model;
    if names.is_empty() {
        if model.has_loops() {
            return Err(KinematicsError::ActuatedNeeded);
        }
        return Ok(Actuation {
            names: (0..model.nv).map(|v| model.velocity_name(v)).collect(),
            velocities: (0..model.nv).collect(),
        });
    }
    let velocities = names
        .iter()
        .map(|name| velocity_index(prepared, name))
        .collect::<Result<Vec<usize>, StaticsError>>()
        .map_err(KinematicsError::Coordinate)?;
    for (k, v) in velocities.iter().enumerate() {
        if velocities[..k].contains(v) {
            return Err(KinematicsError::Repeated(names[k].clone()));
        }
    }
    Ok(Actuation {
        names: names.to_vec(),
        velocities,
    })
}
