//! lsdc: the compiler and simulator for LSD, a declarative language for describing mechanisms.
//!
//! The pipeline, one module per phase, data flowing one way:
//! `syntax` (text to AST) → `load` (imports, libraries) → `check` (names and types) →
//! `elab` (values: bodies, frames, links, joins, efforts, unknowns) → later phases.

pub mod analysis;
pub mod check;
pub mod diag;
pub mod driver;
pub mod dynamics;
pub mod elab;
pub mod integrate;
pub mod kinematics;
pub mod load;
pub mod output;
pub mod simulate;
pub mod source;
pub mod symbolic;
pub mod syntax;
pub mod topology;
