//! The one interface of the writers of a run's samples, one per format (`csv.rs`, `json.rs`).

use std::io;

use crate::simulate::run::{Sample, Simulation};

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
