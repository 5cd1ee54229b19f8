//! Why the kinematic models cannot be computed.

use crate::kinematics::eval::{EvalError, NOT_FINITE};
use crate::studies::statics::StaticsError;

/// Why the models cannot be computed.
#[derive(Debug)]
pub enum KinematicsError {
    /// A mechanism with loops needs its actuated coordinates named.
    ActuatedNeeded,
    /// A coordinate named twice.
    Repeated(String),
    Coordinate(StaticsError),
    Evaluation(EvalError),
    /// A state of `--at` cannot be closed or read.
    State {
        index: usize,
        message: String,
    },
}

impl From<EvalError> for KinematicsError {
    fn from(error: EvalError) -> Self {
        KinematicsError::Evaluation(error)
    }
}

impl std::fmt::Display for KinematicsError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            KinematicsError::ActuatedNeeded => write!(
                f,
                "the mechanism has closed loops: name its actuated coordinates with `--actuate JOIN.COORDINATE`"
            ),
            KinematicsError::Repeated(name) => write!(f, "`{name}` is named twice"),
            KinematicsError::Coordinate(error) => write!(f, "{error}"),
            KinematicsError::Evaluation(EvalError::NotFinite) => {
                write!(f, "cannot evaluate the kinematics here: {NOT_FINITE}")
            }
            // A prepared program has a value for every unknown and a geometry of numbers.
            KinematicsError::Evaluation(error) => {
                write!(f, "cannot evaluate the kinematics here: {error:?}")
            }
            KinematicsError::State { index, message } => write!(f, "state {index}: {message}"),
        }
    }
}

impl std::error::Error for KinematicsError {}
