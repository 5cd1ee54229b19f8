//! Kinematics of the numbered mechanism: the numeric model, forward kinematics with analytic
//! Jacobians, closure of the complementary links, assembly, joint analysis and mobility.

pub mod assembly;
pub mod branch;
pub mod chain;
pub mod closure;
pub mod contacts;
pub mod drag;
pub mod drives;
pub mod eval;
pub mod exact;
pub mod forward;
pub mod frames;
pub mod initial;
pub mod isolation;
pub mod joint;
pub mod mobility;
pub mod model;
pub mod penalty;
pub mod plane;
pub mod position_drives;
pub mod rheonomic;
pub mod sphere_on_disc;
pub mod tabulated_law;
pub mod unknowns;

#[cfg(lsdc_internals)]
pub use initial::initial_coordinates;
