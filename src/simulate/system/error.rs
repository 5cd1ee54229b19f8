//! Why the equations of motion cannot be evaluated at a state, in the words a run reports.

use std::fmt;

use crate::kinematics::eval::EvalError;

/// Why the equations of motion cannot be evaluated at a state.
#[derive(Clone, Debug, PartialEq)]
pub enum SystemError {
    /// An effort or expression has no value there.
    Evaluation(EvalError),
    /// An effort drives a motion that moves no mass; `velocity` names the coordinate it moves
    /// most.
    MasslessMotion { velocity: String },
    /// `join` carries no inertia along its motion (nor do `body` and the bodies beyond it).
    SingularInertia { join: String, body: String },
    /// The mass matrix could not be factorised.
    SingularMassMatrix,
    /// The acceleration of `join` is not finite.
    AccelerationNotFinite { join: String, cause: NotFiniteCause },
    /// The loops are exactly at a singular configuration: the constraint `row` of the
    /// complementary link `join` is no longer independent of the others.
    SingularConfiguration { join: String, row: &'static str },
    /// A projection could not close the loops at `time`: `row` of `join` stays open by `left`
    /// (radians, or metres per metre of the mechanism's size).
    LoopsOpen {
        time: f64,
        join: String,
        row: &'static str,
        left: f64,
    },
    /// The run starts at a singular configuration, where `row` of `join` is implied by the other
    /// constraints though it is not at the closed configurations around it.
    SingularStart { join: String, row: &'static str },
    /// The kept rows of the contacts stopped being independent: `row` of `contact`.
    SingularContact { contact: String, row: &'static str },
    /// The disc of `contact` (`rolling_disc`, `sliding_disc`) lies flat on its plane, or passed
    /// lying flat: every point of its rim is lowest, and the contact has no point.
    DiscFlat { contact: String },
    /// An impact on a stop could not be resolved, or left a coordinate resting on its stop.
    Impact(String),
    /// The rate of the program's state `state` is not finite.
    StateRateNotFinite { state: String },
    /// The update of the program's sampled state `state` at an instant is not finite.
    UpdateNotFinite { state: String },
    /// The model read by the actuators' laws has no value: the actuated coordinates leave a
    /// motion with mass free, or the loops fix a combination of them.
    ActuatedUndetermined,
}

/// What made an acceleration infinite or NaN.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NotFiniteCause {
    /// The efforts are finite: the state itself grew too large.
    StateTooLarge,
    /// An effort evaluated to NaN or infinity.
    EffortNotANumber,
}

impl From<EvalError> for SystemError {
    fn from(error: EvalError) -> Self {
        SystemError::Evaluation(error)
    }
}

impl fmt::Display for SystemError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SystemError::Evaluation(EvalError::Missing(_)) => {
                write!(f, "an effort needs a value that was not given")
            }
            SystemError::Evaluation(EvalError::NotGeometric(what)) => {
                write!(f, "an expression cannot depend on {what} there")
            }
            SystemError::Evaluation(EvalError::NotFinite) => {
                write!(f, "the geometry is not a finite number at this state")
            }
            SystemError::MasslessMotion { velocity } => write!(
                f,
                "an effort drives a motion that moves no mass (it moves `{velocity}` most): give the bodies it moves mass or inertia"
            ),
            SystemError::SingularInertia { join, body } => write!(
                f,
                "the mass matrix is singular: join `{join}` carries no inertia along its motion (body `{body}` and the bodies beyond it)"
            ),
            SystemError::SingularMassMatrix => write!(f, "the mass matrix is singular"),
            SystemError::ActuatedUndetermined => write!(
                f,
                "the actuated coordinates do not determine the motion here, so the model the actuators' laws read has no value: actuate as many coordinates as the mechanism has motions with mass, away from a singular configuration"
            ),
            SystemError::SingularConfiguration { join, row } => write!(
                f,
                "the loops reached a singular configuration: the {row} constraint of `{join}` is no longer independent of the others"
            ),
            SystemError::LoopsOpen { time, join, row, left } => write!(
                f,
                "the loops came open at t = {time}: projecting the state back left the {row} constraint of `{join}` open by {left:.1e} (relative to the mechanism's size); the integration strayed too far from the loops: use a tighter tolerance or a smaller step"
            ),
            SystemError::SingularStart { join, row } => write!(
                f,
                "the loops start at a singular configuration (the {row} constraint of `{join}` is implied by the others here, not at the configurations around it), where the motion may leave along several branches: start away from it, or give initial values on one branch"
            ),
            SystemError::SingularContact { contact, row } => write!(
                f,
                "the contacts reached a singular configuration: the {row} row of `{contact}` is no longer independent of the other contacts' rows"
            ),
            SystemError::DiscFlat { contact } => write!(
                f,
                "the disc of the contact `{contact}` fell flat on its plane: every point of its rim touches it there, so the contact has no point and the motion beyond is an impact that rolling and sliding do not model"
            ),
            SystemError::Impact(message) => f.write_str(message),
            SystemError::UpdateNotFinite { state } => write!(
                f,
                "the update of sampled state `{state}` is not finite: its `update` is not a number there (a square root or logarithm of a negative value, a division by zero), or its values grew too large"
            ),
            SystemError::StateRateNotFinite { state } => write!(
                f,
                "the rate of state `{state}` is not finite: its value grew too large, or its `rate` is not a number there (a square root or logarithm of a negative value, a division by zero)"
            ),
            SystemError::AccelerationNotFinite { join, cause } => {
                write!(f, "the acceleration of join `{join}` is not finite: {cause}")
            }
        }
    }
}

impl fmt::Display for NotFiniteCause {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            NotFiniteCause::StateTooLarge => "the state became too large",
            NotFiniteCause::EffortNotANumber => {
                "an effort is not a number (a square root or logarithm of a negative value, a division by zero)"
            }
        })
    }
}

impl std::error::Error for SystemError {}
