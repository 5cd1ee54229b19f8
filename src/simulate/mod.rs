//! Simulation of tree mechanisms: the equations of motion as an ODE system, integrated from the
//! program's initial values, with outputs and a run report.

pub mod prepare;
pub mod run;
pub mod system;
pub mod variational;
