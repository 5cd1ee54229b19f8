//! lsdc: the compiler and simulator for LSD, a declarative language for describing mechanisms.
//!
//! Start with [`api`]: a program from text or a file, its diagnostics, its mechanism, a prepared
//! simulation and its run, the dynamics at given states.
//!
//! The pipeline, one module per phase, data flowing one way (no module uses a later one):
//! `source` (files, spans) → `syntax` (text to AST) → `load` (imports, libraries, URDF) →
//! `check` (names and types) → `elab` (values: bodies, frames, links, joins, efforts,
//! unknowns) → `topology` (numbering, principal and complementary links) → `kinematics` →
//! `dynamics` → `prepare` (a program made ready to run) → `integrate` and `simulate` → `studies` (built on runs) → `output`; `symbolic` writes the equations from the
//! mechanism. `diag` holds the diagnostics every phase reports.

pub mod api;
pub mod check;
pub mod corrector;
pub mod diag;
pub mod driver;
pub mod dynamics;
pub mod elab;
pub mod ide;
pub mod integrate;
pub mod integrators;
pub mod kinematics;
pub mod linalg;
pub mod load;
pub mod output;
pub mod prepare;
pub mod simulate;
pub mod source;
pub mod spatial;
pub mod studies;
pub mod symbolic;
pub mod syntax;
pub mod testing;
pub mod topology;
pub mod view;
