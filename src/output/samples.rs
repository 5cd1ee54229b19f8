//! Where a run's samples go: the [`SampleWriter`] of a [`SampleFormat`] (CSV rows streamed as
//! the run computes them, one JSON document written at its end).

use std::io::Write;

use super::csv::CsvWriter;
use super::json::JsonWriter;
pub use super::sample_writer::SampleWriter;
use crate::prepare::Prepared;
use crate::simulate::run::{output_names_of, reaction_names_of};

/// The formats of a run's samples.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SampleFormat {
    Csv,
    Json,
}

/// The writer of `format` for the runs of `prepared`, writing to `out` (a CSV header at once).
pub fn writer(
    format: SampleFormat,
    out: Box<dyn Write>,
    prepared: &Prepared,
) -> Box<dyn SampleWriter> {
    match format {
        SampleFormat::Csv => Box::new(CsvWriter::new(
            out,
            &prepared.coordinate_names,
            &reaction_names_of(prepared),
            &output_names_of(prepared),
        )),
        SampleFormat::Json => Box::new(JsonWriter::new(out, &prepared.outputs.frame_names)),
    }
}
