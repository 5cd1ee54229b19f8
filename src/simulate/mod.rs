//! Simulation of mechanisms (trees and closed loops): the equations of motion as an ODE system, integrated from the
//! program's initial values, with outputs and a run report.

pub mod branch;
pub mod clock;
pub mod compiled;
pub mod constraints;
pub mod inputs;
mod kinematic;
pub mod lie_group;
pub mod model_exchange;
mod ode;
pub mod report;
pub mod run;
pub mod run_state;
mod sample;
mod sampler;
pub mod sampling;
pub mod simulator;
pub mod stiffness;
mod summary;
pub mod system;
pub mod variational;
