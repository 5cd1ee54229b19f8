//! The commands of `lsdc`, one file each: its arguments and a `run` that calls the library and
//! prints the result. `shared` holds what they share (`--quiet`, usage errors, diagnostics).

pub mod assemble;
pub mod check;
pub mod compile;
pub mod drag;
pub mod eval;
pub mod export_fmu;
pub mod export_urdf;
pub mod fmi_library;
pub mod fmt;
pub mod identify;
pub mod import_urdf;
pub mod inverse;
pub mod kinematics;
pub mod linearize;
pub mod lsp;
pub mod parse;
pub mod precision;
pub mod sensitivity;
pub mod shared;
pub mod simulate;
pub mod statics;
pub mod sweep;
pub mod test;
pub mod tree;
pub mod view;
pub mod workspace;
