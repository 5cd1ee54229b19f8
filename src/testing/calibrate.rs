//! `lsdc test --calibrate`: tolerances from a convergence study. The case runs at its own
//! tolerance (or step) and at a finer one, a tenth of the tolerance (half the step); their
//! difference estimates the error of the case's own run. That error is also how far a
//! reordering of floating-point operations can move the run: round-off changes which steps an
//! adaptive integrator takes, and a run along other steps differs by about its error, however
//! much the mechanism amplifies the round-off itself. The proposed absolute tolerance of a
//! variable is that difference times a safety factor, rounded up to one significant digit; a
//! change of the dynamics larger than the integration's error still fails.
//!
//! Two round-off probes widen it where the mechanism amplifies round-off: a run from initial
//! coordinates moved by a relative 1e-14, and runs of the program with its own decimal numbers
//! (its lengths, masses, …) moved by a relative 1e-15 each, in directions that differ from run
//! to run, as another parsing or order of operations would leave them.

use serde::Serialize;

use super::case::{as_table, compile_and_prepare, run_failure};
use super::manifest::Case;
use super::record::rounded;
use crate::elab::Perturbation;
use crate::prepare::Prepared;
use crate::simulate::run::{self, Simulation};
use crate::studies::precision::Reference;

/// The proposed tolerance is this many times the observed difference.
pub const SAFETY: f64 = 2.0;

/// A tolerance never proposed below this fraction of the variable's largest magnitude (or of 1,
/// for a variable that stays near 0): round-off's own size, amplified.
const FLOOR: f64 = 1e-12;

/// The smallest relative tolerance proposed for a reference recorded to `digits` significant
/// digits: the safety factor times the most its rounding moves a value (half a unit of its last
/// digit).
fn rounding_floor(digits: usize) -> f64 {
    SAFETY * 0.5 * 10f64.powi(1 - digits as i32)
}

/// A case's calibration.
#[derive(Clone, Debug, Serialize)]
pub struct Calibration {
    pub name: String,
    /// The setting of the case's run and of the finer one (`tolerance` or `step`).
    pub setting: &'static str,
    pub own: f64,
    pub fine: f64,
    pub variables: Vec<Proposal>,
}

/// A variable's observed differences and proposed absolute tolerance.
#[derive(Clone, Debug, Serialize)]
pub struct Proposal {
    pub variable: String,
    /// The largest difference between the case's run and the finer one, and its time.
    pub difference: f64,
    pub time: f64,
    /// The largest difference between the case's run and the run from a perturbed initial
    /// configuration, and its time.
    pub round_off: f64,
    pub round_off_time: f64,
    /// The largest difference between the case's run and the runs with the program's decimal
    /// numbers moved by round-off, and its time.
    pub geometry: f64,
    pub geometry_time: f64,
    pub absolute: f64,
}

/// The relative change of each initial coordinate of the round-off probe: a few units of
/// round-off, as a reordering of floating-point operations leaves after the assembly.
pub const PROBE: f64 = 1e-14;

/// The relative move of each decimal number of the program in the probe of the geometry: a
/// few units of round-off (one unit in the last place is 1.1e-16 to 2.2e-16 of a number).
pub const GEOMETRY_PROBE: f64 = 1e-15;

/// The runs of the probe of the geometry, each moving the numbers in other directions.
pub const GEOMETRY_RUNS: u64 = 8;

/// Runs the case at its settings, at finer ones, from a perturbed initial configuration and
/// with its numbers perturbed, and proposes a tolerance per compared variable.
pub fn calibrate(case: &Case) -> Result<Calibration, String> {
    let mut prepared = compile_and_prepare(case)?;
    let own = as_table(&run_as_expected(case, &prepared)?);
    let assembled = prepared.coordinates.clone();
    perturb(&mut prepared.coordinates);
    let perturbed = as_table(&run_as_expected(case, &prepared)?);
    prepared.coordinates = assembled;
    let (setting, own_value, fine_value) = refine(&mut prepared);
    let fine = as_table(&run_as_expected(case, &prepared)?);
    let geometry = (1..=GEOMETRY_RUNS)
        .map(|seed| perturbed_numbers(case, seed))
        .collect::<Result<Vec<_>, _>>()?;
    let names = case.outputs.clone().unwrap_or_else(|| own.columns.clone());
    let runs = Runs {
        own: &own,
        fine: &fine,
        perturbed: &perturbed,
        geometry: &geometry,
    };
    let variables = (names.iter())
        .map(|name| propose(name, &runs, case.precision))
        .collect::<Result<_, _>>()?;
    Ok(Calibration {
        name: case.name.clone(),
        setting,
        own: own_value,
        fine: fine_value,
        variables,
    })
}

/// The case's run with the program's decimal numbers moved by [`GEOMETRY_PROBE`].
fn perturbed_numbers(case: &Case, seed: u64) -> Result<Reference, String> {
    let case = Case {
        numbers: Some(Perturbation {
            relative: GEOMETRY_PROBE,
            seed,
        }),
        ..case.clone()
    };
    let prepared = compile_and_prepare(&case)?;
    Ok(as_table(&run_as_expected(&case, &prepared)?))
}

/// The runs a calibration compares.
struct Runs<'a> {
    own: &'a Reference,
    fine: &'a Reference,
    perturbed: &'a Reference,
    geometry: &'a [Reference],
}

/// A run to its end, or to a failure that the case expects.
fn run_as_expected(case: &Case, prepared: &Prepared) -> Result<Simulation, String> {
    let simulation = run::run(prepared, &mut |_| {});
    match run_failure(&simulation) {
        Some(failure) if case.checks.expect_failure.is_none() => Err(failure),
        _ => Ok(simulation),
    }
}

/// Moves each value by a relative `PROBE`, the signs alternating (an absolute `PROBE` for a
/// value at 0).
fn perturb(values: &mut [f64]) {
    for (i, value) in values.iter_mut().enumerate() {
        let sign = if i % 2 == 0 { 1.0 } else { -1.0 };
        *value += sign * PROBE * value.abs().max(1.0);
    }
}

/// Makes the run finer: a tenth of the tolerances of an adaptive integrator, half the step of a
/// fixed-step one. Returns which setting changed, and from what to what.
fn refine(prepared: &mut Prepared) -> (&'static str, f64, f64) {
    let settings = &mut prepared.settings;
    let fixed_step = settings.integrator.fixed_step();
    match settings.step {
        Some(step) if fixed_step => {
            settings.step = Some(step / 2.0);
            ("step", step, step / 2.0)
        }
        _ => {
            let tolerance = settings.rtol;
            (settings.rtol, settings.atol) = (settings.rtol / 10.0, settings.atol / 10.0);
            ("tolerance", tolerance, tolerance / 10.0)
        }
    }
}

/// A variable's largest differences between the case's run and the finer one, the perturbed
/// one and those with perturbed numbers, and the tolerance they suggest.
fn propose(name: &str, runs: &Runs<'_>, digits: usize) -> Result<Proposal, String> {
    let (difference, time, magnitude) = largest_difference(name, runs.own, runs.fine)?;
    let (round_off, round_off_time, _) = largest_difference(name, runs.own, runs.perturbed)?;
    let (mut geometry, mut geometry_time) = (0.0_f64, 0.0);
    for run in runs.geometry {
        let (d, t, _) = largest_difference(name, runs.own, run)?;
        if d > geometry {
            (geometry, geometry_time) = (d, t);
        }
    }
    let floor = FLOOR.max(rounding_floor(digits)) * magnitude.max(1.0);
    let largest = difference.max(round_off).max(geometry);
    Ok(Proposal {
        variable: name.to_string(),
        difference,
        time,
        round_off,
        round_off_time,
        geometry,
        geometry_time,
        absolute: round_up((SAFETY * largest).max(floor)),
    })
}

/// The largest difference of a variable between two runs at the outputs of the first (those
/// both have, when a failure ends them), its time, and the variable's largest magnitude.
fn largest_difference(
    name: &str,
    own: &Reference,
    other: &Reference,
) -> Result<(f64, f64, f64), String> {
    let column = |table: &Reference| {
        (table.columns.iter())
            .position(|c| c == name)
            .ok_or_else(|| format!("the run has no output `{name}`"))
    };
    let (o, f) = (column(own)?, column(other)?);
    let (mut difference, mut time, mut magnitude) = (0.0_f64, 0.0, 0.0_f64);
    for (t, row) in &own.rows {
        let Some(values) = other.at(*t) else { break };
        let d = (row[o] - values[f]).abs();
        if d > difference {
            (difference, time) = (d, *t);
        }
        magnitude = magnitude.max(row[o].abs());
    }
    Ok((difference, time, magnitude))
}

/// Rounded up to one significant digit: 2.3e-9 → 3e-9.
pub fn round_up(x: f64) -> f64 {
    if !(x.is_finite() && x > 0.0) {
        return x;
    }
    let power = 10f64.powf(x.log10().floor());
    let leading = (x / power * (1.0 - 1e-12)).ceil();
    format!("{}e{}", leading, power.log10().round())
        .parse()
        .unwrap_or(x)
}

/// The proposal as the manifest's text: a `[case.variables]` table to put under the case.
pub fn as_manifest(calibration: &Calibration) -> String {
    let mut text = format!(
        "# {}: {} {} against {}; initial coordinates perturbed by {PROBE:e}; numbers by {GEOMETRY_PROBE:e} ({GEOMETRY_RUNS} runs); tolerance = {SAFETY} × the largest difference\n[case.variables]\n",
        calibration.name,
        calibration.setting,
        rounded(calibration.own, 12),
        rounded(calibration.fine, 12)
    );
    for p in &calibration.variables {
        text += &format!(
            "\"{}\" = {{ absolute = {:e} }}  # {:.1e} at t = {}, perturbed {:.1e} at t = {}, numbers {:.1e} at t = {}\n",
            p.variable,
            p.absolute,
            p.difference,
            rounded(p.time, 12),
            p.round_off,
            rounded(p.round_off_time, 12),
            p.geometry,
            rounded(p.geometry_time, 12)
        );
    }
    text
}
