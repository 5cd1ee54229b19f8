//! The equations of motion as expressions (Papegay 1992, §3.3): a hash-consed expression DAG
//! (`expr`) where equal subexpressions are one node, vectors and matrices of expressions
//! (`vector`), program scalars lowered to it (`program` for their structure, `lower` for the equations'
//! variables), frames moving with the mechanism
//! (`kinematics`), the equations M q̇ = S + F + Δᵀ Λ, Δ q = 0 (`equations`), their
//! simplification (`simplify`), and their emitters (`emit`).

pub mod articulated;
mod closure;
pub mod closure_poses;
pub mod emit;
pub mod equations;
pub mod exponential_profile;
pub mod expr;
pub mod form;
mod forward;
mod generator;
mod inertia;
mod kane;
pub mod kept_rows_solve;
pub mod kinematics;
mod loads;
pub mod lower;
mod newton_euler;
pub mod program;
pub mod quaternion_joints;
pub mod simplify;
mod tape_code;
pub mod vector;

pub use equations::{generate, generate_in, generate_in_state, Equations};
pub use form::Form;
