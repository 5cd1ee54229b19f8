//! Where a run's samples go: one [`SampleWriter`] per format (CSV rows streamed as the run
//! computes them, one JSON document written at its end), chosen by [`SampleFormat`].

use std::io::{self, Write};

use super::csv::CsvWriter;
use super::json::JsonWriter;
use crate::simulate::prepare::Prepared;
use crate::simulate::run::{reaction_names_of, Sample, Simulation};

/// The formats of a run's samples.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SampleFormat {
    Csv,
    Json,
}

/// Writes a run's samples in one format.
pub trait SampleWriter {
    /// Takes a sample as soon as the run has computed it.
    fn write_sample(&mut self, sample: &Sample);

    /// Ends the output once the run is over (with everything the simulation holds): the first
    /// write error, if any.
    fn finish(self: Box<Self>, simulation: &Simulation) -> io::Result<()>;

    /// Whether the run must keep its samples for [`finish`](SampleWriter::finish) (a writer of
    /// one document at the end, rather than of rows as they come).
    fn needs_kept_samples(&self) -> bool;
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
            &prepared.outputs.names,
        )),
        SampleFormat::Json => Box::new(JsonWriter::new(out, &prepared.outputs.frame_names)),
    }
}
