//! Simulation samples as CSV: one row per output time, a header of readable names
//! (`time`, `swing.q`, `swing.q'`, …, energies). A failed run ends with a comment line saying
//! when and why, after the rows computed before the failure; an interrupted run with a comment
//! line saying when and by what (the marker line).
//!
//! [`CsvWriter`] writes the rows as the run produces them, so that a long run's samples are on
//! disk as it goes (flushed at least every `FLUSH_EVERY`), not held in memory.

use std::fmt::Write as _;
use std::io::{self, Write};
use std::time::{Duration, Instant};

use super::sample_writer::SampleWriter;
use super::text::signal_name;
use crate::simulate::run::{Report, Sample, Simulation};

/// The longest a written row waits in the buffer before it reaches the file.
const FLUSH_EVERY: Duration = Duration::from_millis(200);

/// The whole CSV text of a finished simulation.
pub fn to_csv(simulation: &Simulation) -> String {
    let mut out = header(
        &simulation.coordinate_names,
        &simulation.reaction_names,
        &simulation.output_names,
    );
    for sample in &simulation.samples {
        out += &row(sample);
    }
    out += &ending(&simulation.report);
    out
}

/// The header line: time, the declared coordinates, their rates, the energies, the
/// reactions' components and the `extra` columns (the outputs: the program's, then the frames'
/// states of `--output-frame`).
pub fn header(coordinate_names: &[String], reaction_names: &[String], extra: &[String]) -> String {
    let mut out = String::from("time");
    for name in coordinate_names {
        let _ = write!(out, ",{name}");
    }
    for name in coordinate_names {
        let _ = write!(out, ",{name}'");
    }
    out.push_str(",kinetic_energy,potential_energy");
    for name in reaction_names {
        for part in ["mx", "my", "mz", "fx", "fy", "fz"] {
            let _ = write!(out, ",{name}.reaction.{part}");
        }
    }
    for name in extra {
        let _ = write!(out, ",{name}");
    }
    out.push('\n');
    out
}

/// One sample's line, ending with its outputs.
pub fn row(sample: &Sample) -> String {
    // Every number is written into the line itself: a string per number cost as much again
    // as its formatting (a row of 100 four-bars, 606 numbers: 1.47 M instructions a row).
    let mut out = String::new();
    write_exponent(&mut out, sample.time);
    // A run that models no mass (a scene that asks only for kinematics) knows no energy: its
    // cells are left empty.
    let kinetic = Some(sample.kinetic_energy).filter(|x| !x.is_nan());
    let values = (sample.coordinates.iter().chain(&sample.rates))
        .map(|&x| Some(x))
        .chain([kinetic, sample.potential_energy])
        .chain((sample.reactions.iter().chain(&sample.outputs)).map(|&x| Some(x)));
    for value in values {
        out.push(',');
        if let Some(x) = value {
            write_exponent(&mut out, x);
        }
    }
    out.push('\n');
    out
}

/// A number in exponent notation, as Rust reads it back, at the end of `out`; −0 is written
/// 0e0.
fn write_exponent(out: &mut String, x: f64) {
    let _ = write!(out, "{:e}", x + 0.0);
}

/// The comment lines after the rows: why the run failed, or when it was interrupted (the
/// marker line); nothing after a run that reached its end.
pub fn ending(report: &Report) -> String {
    let mut out = String::new();
    if let Some(failure) = &report.failure {
        let _ = writeln!(
            out,
            "# the run failed at t = {}: {}",
            failure.time, failure.message
        );
    }
    if let Some(stop) = &report.interrupted {
        let _ = writeln!(
            out,
            "# interrupted by {} at t = {}: the rows above are the outputs up to there",
            signal_name(stop.signal),
            stop.time
        );
    }
    out
}

/// Writes the rows of a run as they come; keeps the first write error, after which it writes
/// nothing more.
pub struct CsvWriter<W: Write> {
    out: W,
    flushed: Instant,
    error: Option<io::Error>,
}

impl<W: Write> CsvWriter<W> {
    /// Starts the file with its header (see [`header`]); `extra` are the outputs' columns.
    pub fn new(
        out: W,
        coordinate_names: &[String],
        reaction_names: &[String],
        extra: &[String],
    ) -> Self {
        let mut writer = CsvWriter {
            out,
            flushed: Instant::now(),
            error: None,
        };
        writer.write(&header(coordinate_names, reaction_names, extra));
        writer.flush();
        writer
    }

    fn write(&mut self, text: &str) {
        if self.error.is_none() {
            self.error = self.out.write_all(text.as_bytes()).err();
        }
    }

    fn flush(&mut self) {
        if self.error.is_none() {
            self.error = self.out.flush().err();
        }
        self.flushed = Instant::now();
    }
}

impl<W: Write> SampleWriter for CsvWriter<W> {
    /// Writes the sample's row.
    fn write_sample(&mut self, sample: &Sample) {
        self.write(&row(sample));
        if self.flushed.elapsed() >= FLUSH_EVERY {
            self.flush();
        }
    }

    /// Ends the file after the run (see [`ending`]) and flushes it.
    fn finish(mut self: Box<Self>, simulation: &Simulation) -> io::Result<()> {
        self.write(&ending(&simulation.report));
        self.flush();
        self.error.map_or(Ok(()), Err)
    }

    fn needs_kept_samples(&self) -> bool {
        false
    }
}
