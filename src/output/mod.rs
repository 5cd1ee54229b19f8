//! Output: text renderings of reports (a linearisation also for MATLAB), simulation samples (CSV, JSON) behind one writer,
//! sensitivities (CSV, JSON), plots
//! (the reports' JSON comes from their `Serialize` forms).

pub mod csv;
pub mod exact_mobility;
pub mod fmi;
pub mod json;
pub mod linearization;
pub mod plot;
pub mod plot_columns;
pub mod precision_plot;
pub mod sample_writer;
pub mod samples;
pub mod sensitivity;
pub mod text;
pub mod urdf;
pub mod workspace_plot;
pub mod xml;
