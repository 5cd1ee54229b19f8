//! `lsdc test --calibrate`: tolerances from a convergence study. The case runs at its own
//! tolerance (or step) and at a coarser one, ten times the tolerance (twice the step); their
//! difference estimates what the integration's error, and a reordering of floating-point
//! operations amplified by the mechanism, can move each variable. The proposed absolute
//! tolerance of a variable is that difference times a safety factor, rounded up to one
//! significant digit; a change of the dynamics larger than the integration's error still fails.

use serde::Serialize;

use super::case::{as_table, compile, prepare_case, Stop};
use super::manifest::Case;
use crate::simulate::precision::Reference;
use crate::simulate::prepare::{Integrator, Prepared};
use crate::simulate::run::{self, Simulation};

/// The proposed tolerance is this many times the observed difference.
pub const SAFETY: f64 = 2.0;

/// A tolerance never proposed below this fraction of the variable's largest magnitude (or of 1,
/// for a variable that stays near 0): round-off's own size.
const FLOOR: f64 = 1e-12;

/// A case's calibration.
#[derive(Clone, Debug, Serialize)]
pub struct Calibration {
    pub name: String,
    /// The setting of the case's run and of the coarser one (`tolerance` or `step`).
    pub setting: &'static str,
    pub fine: f64,
    pub coarse: f64,
    pub variables: Vec<Proposal>,
}

/// A variable's observed difference and proposed absolute tolerance.
#[derive(Clone, Debug, Serialize)]
pub struct Proposal {
    pub variable: String,
    pub difference: f64,
    pub time: f64,
    pub absolute: f64,
}

/// Runs the case at two settings and proposes a tolerance per compared variable.
pub fn calibrate(case: &Case) -> Result<Calibration, String> {
    let compilation = compile(case).map_err(stop_message)?;
    let mut prepared = prepare_case(case, &compilation).map_err(stop_message)?;
    let fine = run_checked(&prepared)?;
    let (setting, fine_value, coarse_value) = coarsen(&mut prepared);
    let coarse = run_checked(&prepared)?;
    let (fine, coarse) = (as_table(&fine), as_table(&coarse));
    let names = case.outputs.clone().unwrap_or_else(|| fine.columns.clone());
    let variables = (names.iter())
        .map(|name| propose(name, &fine, &coarse))
        .collect::<Result<_, _>>()?;
    Ok(Calibration {
        name: case.name.clone(),
        setting,
        fine: fine_value,
        coarse: coarse_value,
        variables,
    })
}

fn stop_message(stop: Stop) -> String {
    match stop {
        Stop::Program(m) | Stop::Setup(m) => m,
    }
}

fn run_checked(prepared: &Prepared) -> Result<Simulation, String> {
    let simulation = run::run(prepared, &mut |_| {});
    match &simulation.report.failure {
        Some(f) => Err(format!("the run failed at t = {}: {}", f.time, f.message)),
        None => Ok(simulation),
    }
}

/// Makes the run coarser: ten times the tolerances of an adaptive integrator, twice the step of
/// a fixed-step one. Returns which setting changed, and from what to what.
fn coarsen(prepared: &mut Prepared) -> (&'static str, f64, f64) {
    let settings = &mut prepared.settings;
    let fixed_step = matches!(
        settings.integrator,
        Integrator::Rk4 | Integrator::Symplectic
    );
    match settings.step {
        Some(step) if fixed_step => {
            settings.step = Some(2.0 * step);
            ("step", step, 2.0 * step)
        }
        _ => {
            let tolerance = settings.rtol;
            (settings.rtol, settings.atol) = (10.0 * settings.rtol, 10.0 * settings.atol);
            ("tolerance", tolerance, 10.0 * tolerance)
        }
    }
}

/// The largest difference of a variable between the two runs at the fine run's times, and the
/// tolerance it suggests.
fn propose(name: &str, fine: &Reference, coarse: &Reference) -> Result<Proposal, String> {
    let column = |table: &Reference| {
        (table.columns.iter())
            .position(|c| c == name)
            .ok_or_else(|| format!("the run has no output `{name}`"))
    };
    let (f, c) = (column(fine)?, column(coarse)?);
    let (mut difference, mut time, mut magnitude) = (0.0_f64, 0.0, 0.0_f64);
    for (t, row) in &fine.rows {
        let other = coarse
            .at(*t)
            .ok_or_else(|| format!("the coarse run has no output at t = {t}"))?;
        let d = (row[f] - other[c]).abs();
        if d > difference {
            (difference, time) = (d, *t);
        }
        magnitude = magnitude.max(row[f].abs());
    }
    let floor = FLOOR * magnitude.max(1.0);
    Ok(Proposal {
        variable: name.to_string(),
        difference,
        time,
        absolute: round_up((SAFETY * difference).max(floor)),
    })
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
        "# {}: {} {:e} against {:e}; tolerance = {SAFETY} × the largest difference\n[case.variables]\n",
        calibration.name, calibration.setting, calibration.fine, calibration.coarse
    );
    for p in &calibration.variables {
        text += &format!(
            "\"{}\" = {{ absolute = {:e} }}  # difference {:.2e} at t = {}\n",
            p.variable, p.absolute, p.difference, p.time
        );
    }
    text
}
