//! Output: text renderings of reports (JSON comes from their `Serialize` forms).

pub mod text;
