//! The kinematic models of a mechanism at a configuration (`lsdc kinematics`): the Jacobian
//! from the actuated coordinates to a frame's motion (the direct velocity model, MCD), its
//! inverse (MCI, the Delta seed's α̇ = J·Ṗ), the acceleration terms at given rates (MAD and MAI:
//! the frame's acceleration when the actuators do not accelerate, and the seed's H·α̇), their
//! conditioning and the singularity the configuration is at, classified.
//!
//! The method (Gosselin & Angeles, "Singularity analysis of closed-loop kinematic chains", IEEE
//! Trans. Robotics and Automation 6(3), 1990, generalised to any loop structure): the motions the
//! loops allow are the null space N of the constraint Jacobian G (for a tree, every motion).
//! Among them, the idle ones move neither an actuated coordinate nor the frame (a rod spinning
//! between two ball joints) and are set aside: on an orthonormal basis W of the others, the
//! actuated rates are A·ξ and the frame's motion B·ξ. Then
//! - type 2 (direct, parallel) singularity: A loses rank, some motion moves the frame with the
//!   actuators locked;
//! - type 1 (inverse, serial) singularity: B loses rank, some motion moves the actuators with the
//!   frame held (for a tree: the frame's Jacobian loses rank);
//! - elsewhere the direct model is B·A⁺ and the inverse one A·B⁺.
//!
//! Every decision is taken in the mechanism's units: velocities of sliding coordinates and the
//! frame's linear velocity are divided by the mechanism's characteristic length L (that of
//! `loops::structure`), so that the same mechanism in millimetres decides alike.
//! The acceleration terms come from the loops' exact velocity-product term γ = Ġ v and the
//! bodies' bias accelerations (no differences).
//!
//! One concept per file: what the models map (`output`), the motions the loops allow in the
//! mechanism's units (`motion_basis`), the second-order terms (`second_order`), the singular
//! value decompositions (`singular_values`), the models and the singularity (`models`), and
//! why they cannot be computed (`error`).

mod error;
mod models;
mod motion_basis;
mod output;
mod second_order;
mod singular_values;

pub use error::KinematicsError;
pub use models::{models_at, KinematicModels, Rows, SingularKind, SingularMotion};
pub(crate) use motion_basis::motion_basis;
pub use output::{actuation, Actuation, Output, OutputKind};
pub(crate) use second_order::second_order;

/// A measure below this is a singular configuration (both measures are singular values of
/// dimensionless matrices, at most about 1: see `Singularity`).
pub const SINGULAR_TOLERANCE: f64 = 1e-6;
