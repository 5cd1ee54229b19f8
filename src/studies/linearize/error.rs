//! Why a linearisation refuses or fails: the parts of a program it does not handle
//! (`Unsupported`, E0850), motions imposed in time where it does not handle them (E0491), and
//! the errors of its inputs, coordinates and operating point.

use std::fmt;

use super::chart::ChartError;
use crate::diag::Diagnostic;
use crate::elab::imposed_motion::refused_by;
use crate::elab::mechanism::Mechanism;
use crate::elab::value::JoinId;
use crate::simulate::system::SystemError;
use crate::studies::statics::StaticsError;

/// What a linearisation does not handle.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Unsupported {
    /// A spherical or free joint: its orientation is a quaternion, not coordinates to
    /// differentiate along.
    Quaternion,
    /// A contact: its rolling rows constrain velocities, not positions.
    Contact,
    /// A coupled (mimic) joint: its coordinate is not independent, nor closed by a loop.
    Mimic,
    /// Joint friction: not smooth at rest.
    Friction,
}

impl Unsupported {
    pub fn what(self) -> &'static str {
        match self {
            Unsupported::Quaternion => "a spherical or free joint",
            Unsupported::Contact => "a contact",
            Unsupported::Mimic => "a coupled (mimic) joint",
            Unsupported::Friction => "a joint with friction",
        }
    }

    fn help(self) -> &'static str {
        match self {
            Unsupported::Quaternion => "its orientation is a quaternion, not coordinates to linearise along: write the joint as a chain of revolutes (`link(a, b, c) dof = ...`)",
            Unsupported::Contact => "a contact constrains velocities, not positions: independent coordinates do not describe it",
            Unsupported::Mimic => "write the coupling as a loop of the mechanism, or linearise without it",
            Unsupported::Friction => "friction is not smooth at rest: linearise without it, or with a viscous damper written as an effort",
        }
    }
}

/// Where a linearisation refuses motions imposed in time.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImposedContext {
    Loops,
    Equilibrium,
    /// A frame's position imposed (`drive position(F) = law`), whose rows the chart does not
    /// keep.
    Path,
}

impl ImposedContext {
    /// The command as the user ran it, for the refusal.
    fn command(self) -> &'static str {
        match self {
            ImposedContext::Loops => "`lsdc linearize` of a mechanism with closed loops",
            ImposedContext::Equilibrium => "`lsdc linearize --equilibrium`",
            ImposedContext::Path => {
                "`lsdc linearize` of a mechanism whose frame's position is imposed"
            }
        }
    }

    fn help(self) -> &'static str {
        match self {
            ImposedContext::Loops => "linearise the mechanism without the motion imposed in time (remove the drive, or the time from the dof chain); a tree is linearised with its drives on their laws",
            ImposedContext::Equilibrium => "a coordinate imposed in time is not at rest: linearise about the initial state, or a run's state with --at-time T, where the drives are on their laws",
            ImposedContext::Path => "linearise the mechanism without its position drive, or drive its coordinates instead (`drive crank.q = law`)",
        }
    }
}

/// Why a mechanism cannot be linearised as asked.
#[derive(Debug)]
pub enum LinearizeError {
    /// An input or coordinate names no coordinate that can carry one (see `StaticsError`).
    Name(StaticsError),
    /// A coordinate named twice among the inputs or the coordinates.
    Repeated {
        name: String,
    },
    /// `--coordinate` for a tree, whose coordinates are all independent.
    TreeCoordinates,
    /// As many independent coordinates as the motions with mass are needed; the run's choice.
    CoordinateCount {
        given: usize,
        with_mass: usize,
        run_choice: Vec<String>,
    },
    /// The run's free coordinates include spherical or free joints' velocities, which are no
    /// coordinate's rates, beyond the massless motions: coordinates must be named.
    FreeQuaternion {
        with_mass: usize,
        run_choice: Vec<String>,
    },
    /// The coordinates named leave some of the others undetermined by the loops.
    NotIndependent {
        given: Vec<String>,
        run_choice: Vec<String>,
    },
    /// An input along a coordinate a drive imposes: no force moves it.
    DrivenInput {
        name: String,
    },
    /// A state named as an input whose rate is not zero: holding it at the input's value
    /// would not be the program's model.
    VaryingStateInput {
        name: String,
    },
    /// A coordinate imposed in time (`name`) where it is not handled.
    ImposedMotion {
        name: String,
        context: ImposedContext,
    },
    /// A join or contact (`name`) of a kind a linearisation does not handle.
    Unsupported {
        name: String,
        kind: Unsupported,
    },
    /// At an equilibrium the inputs do not hold the mechanism: the largest acceleration left.
    NotAnEquilibrium {
        coordinate: String,
        acceleration: f64,
    },
    /// The run to the operating point failed.
    RunFailed {
        time: f64,
        message: String,
    },
    /// The loops cannot be closed at a state near the operating point.
    Chart(ChartError),
    System(SystemError),
    /// The eigenvalues of A could not be computed (a value not finite).
    NoEigenvalues,
}

impl From<SystemError> for LinearizeError {
    fn from(error: SystemError) -> Self {
        LinearizeError::System(error)
    }
}

impl From<ChartError> for LinearizeError {
    fn from(error: ChartError) -> Self {
        LinearizeError::Chart(error)
    }
}

impl LinearizeError {
    /// The error as a diagnostic located in the program, where it is about a part of it (E0850).
    pub fn diagnostic(&self, mechanism: &Mechanism) -> Option<Diagnostic> {
        if let LinearizeError::ImposedMotion { context, .. } = self {
            return refused_by(mechanism, context.command(), context.help());
        }
        let LinearizeError::Unsupported { name, kind } = self else {
            return None;
        };
        let mut joins = (0..mechanism.joins.len() as u32).map(JoinId);
        let span = match joins.find(|&id| mechanism.join_name(id) == *name) {
            Some(id) => mechanism.join(id).span,
            None => {
                let index =
                    (0..mechanism.contacts.len()).find(|&k| mechanism.contact_name(k) == *name)?;
                mechanism.contacts[index].span
            }
        };
        Some(
            Diagnostic::error(
                "E0850",
                format!("`{name}` cannot be linearised: {}", kind.what()),
            )
            .primary(span, kind.what())
            .help(kind.help()),
        )
    }
}

impl fmt::Display for LinearizeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            LinearizeError::Name(error) => write!(f, "{error}"),
            LinearizeError::Repeated { name } => write!(f, "`{name}` is named twice"),
            LinearizeError::TreeCoordinates => write!(
                f,
                "--coordinate chooses the independent coordinates of closed loops; every coordinate of a tree is independent"
            ),
            LinearizeError::CoordinateCount {
                given,
                with_mass,
                run_choice,
            } => write!(
                f,
                "{given} coordinate(s) given with --coordinate, but the loops leave {with_mass} independent motion(s) with mass (the run's free coordinates: {})",
                quoted(run_choice)
            ),
            LinearizeError::FreeQuaternion { with_mass, run_choice } => write!(
                f,
                "the run's free coordinates ({}) include velocities of spherical joints, which are no coordinates' rates: name {with_mass} independent coordinates of revolute or prismatic joints with --coordinate (the actuated ones of a parallel robot)",
                quoted(run_choice)
            ),
            LinearizeError::NotIndependent { given, run_choice } => write!(
                f,
                "the loops do not determine the other coordinates from {}: choose coordinates that move independently, as the run's {}",
                quoted(given),
                quoted(run_choice)
            ),
            LinearizeError::Unsupported { name, kind } => {
                write!(f, "`{name}` cannot be linearised: {}", kind.what())
            }
            LinearizeError::DrivenInput { name } => write!(
                f,
                "`{name}` is imposed by a law of time: a force along it moves nothing (it becomes the drive's effort); name a free coordinate with --input"
            ),
            LinearizeError::VaryingStateInput { name } => write!(
                f,
                "the state `{name}` has a rate: an input is held at its value, so a state named with --input must be constant (`rate {name} = 0;`); its value is then the input's"
            ),
            LinearizeError::ImposedMotion { name, context } => write!(
                f,
                "`{name}` is imposed by a law of time, which {} does not handle: {}",
                context.command(),
                context.help()
            ),
            LinearizeError::NotAnEquilibrium { coordinate, acceleration } => write!(
                f,
                "the initial configuration is not an equilibrium: `{coordinate}` accelerates at {acceleration:.6e} with the inputs holding it as well as they can; name inputs (--input) that can hold it"
            ),
            LinearizeError::RunFailed { time, message } => {
                write!(f, "the run to the operating point failed at t = {time}: {message}")
            }
            LinearizeError::Chart(ChartError::NotClosed { residual }) => write!(
                f,
                "the loops cannot be closed near the operating point (a row left at {residual:.3e}): it may be a singular configuration"
            ),
            LinearizeError::Chart(ChartError::Evaluation(error)) => {
                write!(f, "{}", SystemError::from(error.clone()))
            }
            LinearizeError::System(error) => write!(f, "{error}"),
            LinearizeError::NoEigenvalues => {
                write!(f, "the eigenvalues of A cannot be computed: it has a value that is not finite")
            }
        }
    }
}

fn quoted(names: &[String]) -> String {
    let names: Vec<String> = names.iter().map(|n| format!("`{n}`")).collect();
    names.join(", ")
}

impl std::error::Error for LinearizeError {}
