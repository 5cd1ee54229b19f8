//! Simulation samples as CSV: one row per output time, a header of readable names
//! (`time`, `swing.q`, `swing.q'`, …, energies). A failed run ends with a comment line saying
//! when and why, after the rows computed before the failure.

use std::fmt::Write;

use crate::simulate::run::Simulation;

pub fn to_csv(simulation: &Simulation) -> String {
    let mut out = String::from("time");
    for name in &simulation.coordinate_names {
        let _ = write!(out, ",{name}");
    }
    for name in &simulation.coordinate_names {
        let _ = write!(out, ",{name}'");
    }
    out.push_str(",kinetic_energy,potential_energy");
    for name in &simulation.reaction_names {
        for part in ["mx", "my", "mz", "fx", "fy", "fz"] {
            let _ = write!(out, ",{name}.reaction.{part}");
        }
    }
    out.push('\n');
    for sample in &simulation.samples {
        let _ = write!(out, "{:e}", sample.time);
        for value in sample.coordinates.iter().chain(&sample.rates) {
            let _ = write!(out, ",{value:e}");
        }
        let potential = sample
            .potential_energy
            .map_or(String::new(), |p| format!("{p:e}"));
        let _ = write!(out, ",{:e},{potential}", sample.kinetic_energy);
        for value in &sample.reactions {
            let _ = write!(out, ",{value:e}");
        }
        out.push('\n');
    }
    if let Some(failure) = &simulation.report.failure {
        let _ = writeln!(
            out,
            "# the run failed at t = {}: {}",
            failure.time, failure.message
        );
    }
    out
}
