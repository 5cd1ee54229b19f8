//! Closed loops: the complementary links' constraint rows (`rows`), their Jacobian stored by loop
//! (`jacobian`), the decisions taken once on them at the start of a run (`structure`: which rows
//! are independent, in units that do not depend on the user's, and which coordinates
//! parametrise the motions they allow, and how many of those move no mass, from the bodies'
//! inertias: `massless`), the sparse factorisation of those rows (`factored`), the
//! constrained equations of motion solved on them (`solve`, with the allowed motions' reduced
//! mass matrix from `inertia`; or, where the allowed motions outnumber the rows, on the rows
//! themselves by the articulated-body algorithm's responses, `range_space`), and the
//! projection of a state back onto the loops (`project`), then, near singular configurations,
//! of its velocities by the constraints' impulse (`momentum`), with an orthonormal basis of the allowed motions from the
//! sparse factorisation for the outputs (`orthonormal`). Which side of a singular configuration
//! a state lies on, seen from the last step's start, tells a step that jumps across one
//! (`orientation`). The derivatives of the constrained accelerations with respect to the state
//! and the efforts, in all the state's velocities and in independent coordinates: `derivatives`.
//! A planar mechanism's right-hand side computes its rows in planar form (`planar_rows`); the
//! translation rows of its long loops are evaluated in the plane with compensated sums for the
//! projections and the residuals reported (`planar_closure`).
//! A singular value decomposition (`basis`) and dense QR
//! factorisations serve the decisions taken once, never the equations of motion.
//! The method and its references: `docs/loops.md`.

pub mod basis;
pub mod derivatives;
pub mod elimination;
pub mod factored;
pub mod inertia;
pub mod jacobian;
pub mod massless;
pub mod momentum;
pub mod orientation;
pub mod orthonormal;
pub mod passes;
pub mod planar_closure;
pub mod planar_rows;
pub mod project;
pub mod range_space;
pub mod rows;
pub mod solve;
pub mod structure;
pub mod triples;

pub use basis::{decompose, decompose_with};
pub use factored::{Factored, RowChoice, Singular, DAMPING};
pub use jacobian::ConstraintJacobian;
pub use momentum::{project_momentum, MomentumBasis};
pub use orientation::Orientation;
pub use project::{close_configuration, project, project_from, ProjectionScratch, Residuals};
pub use range_space::{Method, Tree};
pub use rows::{
    active_rows, constraint_forces, constraints, constraints_into, seat_ball_angles, Constraints,
    Extent, ROW_NAMES,
};
pub use solve::{
    allowed_motions, multipliers, solve_range_space, solve_reduced, LoopError, LoopScratch,
    Stabilisation,
};
pub use structure::{Structure, StructureError};
