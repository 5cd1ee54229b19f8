//! The studies built on the mechanism and its runs: the dynamics at given states (`lsdc eval`,
//! `batch`, with their derivatives `batch_derivatives`; each quantity alone at states given as
//! rows of arrays, `state_batch`), the efforts holding a mechanism at rest (`statics`), the integrators compared for
//! precision and cost (`precision`), the `tree` and `assemble` reports (`analysis`), a
//! point dragged along a path (`drag`), the efforts along the program's drives (`inverse`) or
//! along a motion read from a file (`motion_file`, made drives by `trajectory`),
//! the velocity and acceleration models and their singularities at configurations
//! (`kinematic_models`, closed by `configurations`) along runs (`singularities`), the singular points of the inverse geometric model
//! (`singular_points`), the
//! workspace of a point (`workspace`), the linear model about an operating point
//! (`linearize`), the derivatives of a run's quantities with respect to its parameters
//! (`sensitivity`), and many runs of one program over a grid, a list or a sample of values
//! (`sweep`).

pub mod analysis;
pub mod batch;
pub mod batch_derivatives;
pub mod configurations;
pub mod drag;
pub mod exact_mobility;
pub mod identify;
pub mod inverse;
pub mod kinematic_models;
pub mod linearize;
pub mod motion_file;
pub mod precision;
pub mod sensitivity;
pub mod singular_points;
pub mod singularities;
pub mod state_batch;
pub mod statics;
pub mod sweep;
pub mod trajectory;
pub mod workspace;
pub mod workspace_positions;
