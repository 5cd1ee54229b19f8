//! The integration tests, one module per area, linked into a single test binary: each
//! separate binary under `tests/` would link the library and its dependencies again.
//! Run one area with `cargo test --test suite <module>::`, e.g. `cargo test --test suite golden::`.

mod common;

mod allocations;
mod architecture;
mod arrays;
mod assembly;
mod cli;
mod closed_loops;
mod constrained;
mod drag;
mod dynamics;
mod examples;
mod force_elements;
mod format;
mod frame_efforts;
mod generated_code;
mod golden;
mod hard_loops;
mod integrate_projection;
mod integrators;
mod kinematics;
mod loop_properties;
mod loops;
mod lsp;
mod mampey;
mod methods;
mod native;
mod pinocchio_fixtures;
mod properties;
mod regression;
mod runs;
mod simulation;
mod stops;
mod symbolic;
mod symbolic_equations;
mod symplectic_groups;
mod textmate;
mod threads;
mod tree_jacobian;
mod unit_diag;
mod unit_dynamics;
mod unit_integrate;
mod unit_kinematics;
mod unit_load;
mod unit_output;
mod unit_symbolic;
mod unit_syntax;
mod unit_testing;
mod unit_topology;
mod urdf_export;
mod urdf_import;
mod view;
mod welds;
