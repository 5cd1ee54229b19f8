//! Output: text renderings of reports, simulation samples as CSV, plots (JSON comes from the
//! reports' `Serialize` forms).

pub mod csv;
pub mod plot;
pub mod precision_plot;
pub mod text;
pub mod urdf;
pub mod xml;
