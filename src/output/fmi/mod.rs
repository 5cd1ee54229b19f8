//! FMI units (Functional Mock-up Interface 3.0 and 2.0, co-simulation) made from a program by
//! `lsdc export-fmu`: their variables, their model description and their ZIP container. The
//! shared library inside, which runs the program, is the crate in `fmi/` (docs/fmi.md).

pub mod archive;
pub mod model_description;
pub mod variables;
