//! The parts of a dynamic model besides its joints: the bodies' inertia and the efforts applied
//! to bodies and carried by links, with their values still as expressions of the state.

use nalgebra::Vector3;

use crate::elab::mechanism::EffortKind;
use crate::elab::value::{Scalar, Vector};
use crate::spatial::{Inertia, Pose, RigidInertia};

#[derive(Clone, Debug)]
pub struct BodyInertia {
    pub mass: f64,
    /// Centre of mass in the body frame.
    pub com: Vector3<f64>,
    /// Spatial inertia about the body frame's origin, and the same in compact form: the two
    /// must agree (RNEA and ABA take the bodies' momenta from the compact form, ABA starts its
    /// articulated inertias from the matrix).
    pub inertia: Inertia,
    pub rigid: RigidInertia,
    /// Zero mass and inertia: skipped by the algorithms.
    pub massless: bool,
}

impl BodyInertia {
    /// No mass and no inertia.
    pub fn massless() -> BodyInertia {
        BodyInertia {
            mass: 0.0,
            com: Vector3::zeros(),
            inertia: Inertia::zeros(),
            rigid: RigidInertia::zeros(),
            massless: true,
        }
    }
}

/// A force on a point of a body, or a torque on a body, from `apply`.
#[derive(Clone, Debug)]
pub struct AppliedEffort {
    pub kind: EffortKind,
    /// Body number (1..n).
    pub body: usize,
    /// Point of application in the body frame (forces).
    pub point: Vector3<f64>,
    pub value: Vector,
    /// Body whose basis the value is written in (0 = the fixed basis).
    pub basis: usize,
    /// The potential energy it derives from, if the program declares one.
    pub potential: Option<Scalar>,
    /// The `apply` it comes from, for messages.
    pub span: crate::source::Span,
    /// Whether it derives from a potential the energy report counts: a constant force in the
    /// fixed basis, or an effort that declares its potential. Set when the model is built.
    pub conservative: bool,
    /// The position of its potential among the values of the model's effort tape (its value is
    /// applied with its group's: `AppliedGroup`). Set when the efforts are compiled.
    pub potential_root: Option<usize>,
}

/// The applied efforts that act alike (same kind, body, point and basis), summed into one when
/// the efforts are compiled: a spring and its damper on the same frame are one force to apply.
#[derive(Clone, Debug)]
pub struct AppliedGroup {
    pub kind: EffortKind,
    pub body: usize,
    pub point: Vector3<f64>,
    pub basis: usize,
    /// The sum of the members' values among the tape's values.
    pub value_roots: [usize; 3],
    /// The sum of the values of the members that derive from no potential, for the power the
    /// energy balance counts; `None` when every member is conservative.
    pub nonconservative_roots: Option<[usize; 3]>,
}

/// A frame an effort refers to: the frame as the expressions hold it (found by identity), its
/// body's number and its pose on the body.
#[derive(Clone, Debug)]
pub struct EffortFrame {
    pub frame: std::sync::Arc<crate::elab::value::Frame>,
    pub body: usize,
    pub offset: Pose,
}

/// A known link effort (`force`, `torque`, `forceN`, `torqueN`).
#[derive(Clone, Debug)]
pub struct LinkEffort {
    /// Index into `Model::joints`, then into `Model::loops` (`joints.len() + k`).
    pub joint: usize,
    pub kind: EffortKind,
    /// 0 for the plain form (in the chain's first frame), N for the N-th step's frame.
    pub step: u8,
    pub value: Vector,
    /// The join whose link declares it, for messages.
    pub span: crate::source::Span,
    /// Whether its link declares the potential it derives from.
    pub conservative: bool,
    /// The positions of its value's components among the values of the model's effort tape.
    /// Set when the efforts are compiled.
    pub value_roots: [usize; 3],
}

/// A link's declared potential.
#[derive(Clone, Debug)]
pub struct LinkPotential {
    /// Index into `Model::joints`, then into `Model::loops`.
    pub joint: usize,
    pub value: Scalar,
    /// Its position among the values of the model's effort tape.
    pub root: usize,
}
