//! Consistent initial conditions for a mechanism with loops: the configuration is assembled from
//! the `initial` values (holding the `fixed` ones), then the initial rates are completed so the
//! loops stay closed: the rates the program gives are kept, the others are the smallest that
//! satisfy the velocity constraints.

use nalgebra::{DMatrix, DVector};

use crate::diag::Diagnostic;
use crate::dynamics::algorithms::Data;
use crate::dynamics::angles::AngleReference;
use crate::dynamics::loops::{close_configuration, constraints, decompose, Extent};
use crate::dynamics::model::Model;
use crate::elab::mechanism::Mechanism;
use crate::kinematics::assembly::AssemblyOptions;
use crate::kinematics::initial::assemble_initial;
use crate::kinematics::model::KinematicModel;

/// A starting state that closes every loop.
pub struct ConsistentState {
    /// Declared coordinates and rates of the whole mechanism.
    pub coordinates: Vec<f64>,
    pub rates: Vec<f64>,
    /// The given values assembly had to move (W0801).
    pub warnings: Vec<Diagnostic>,
}

/// Declared coordinates and rates (of the whole mechanism) that close every loop, and a warning
/// for the given coordinates assembly had to move.
pub fn initial_state(
    mechanism: &Mechanism,
    kinematics: &KinematicModel,
    model: &Model,
    rates: &[f64],
) -> Result<ConsistentState, Vec<Diagnostic>> {
    let initial = assemble_initial(mechanism, kinematics, &AssemblyOptions::default())?;
    let coordinates = initial.assembled.q;
    let evaluation = |e| {
        vec![Diagnostic::error(
            "E0804",
            format!(
                "cannot evaluate the initial state: {}",
                crate::kinematics::eval::describe(&e, mechanism)
            ),
        )]
    };
    let (mut q, mut v) = model
        .state_from_declared(&coordinates, rates)
        .map_err(evaluation)?;
    let given = given_velocities(mechanism, model);
    let mut data = Data::new(model);
    // Assembly stops at 1e-12: finish at round-off.
    close_configuration(model, &mut data, &mut q).map_err(evaluation)?;
    let c = constraints(model, &mut data, &q, &v, Extent::Rows).map_err(evaluation)?;
    complete_rates(&c.jacobian.dense(), &given, &mut v)
        .map_err(|opening| vec![incompatible_rates(mechanism, &given, opening)])?;
    let mut warnings = initial.warnings;
    warnings.extend(amplified_rates(mechanism, model, &given, &v));
    let reference = AngleReference::at_rest(coordinates);
    let (coordinates, rates) = model
        .declared((0.0, &q, &v), &reference)
        .map_err(evaluation)?;
    Ok(ConsistentState {
        coordinates,
        rates,
        warnings,
    })
}

/// Completed rates beyond this multiple of the largest rate given are reported (W0802).
const AMPLIFIED_RATES: f64 = 1e3;

/// W0802 when the loops complete the given rates with a rate more than `AMPLIFIED_RATES` times
/// the largest given: the configuration is close to one where the loops' velocity map is
/// singular (they lock, or change branch), and the motion asked for is much faster than it
/// reads.
fn amplified_rates(
    mechanism: &Mechanism,
    model: &Model,
    given: &[(usize, String)],
    v: &[f64],
) -> Option<Diagnostic> {
    let largest_given = given
        .iter()
        .max_by(|a, b| v[a.0].abs().total_cmp(&v[b.0].abs()))?;
    let given_rate = v[largest_given.0];
    let completed = completed_velocities(given, v.len());
    let fastest = completed.max_by(|&a, &b| v[a].abs().total_cmp(&v[b].abs()))?;
    let ratio = v[fastest].abs() / given_rate.abs();
    if given_rate == 0.0 || ratio.is_nan() || ratio <= AMPLIFIED_RATES {
        return None;
    }
    let message = format!(
        "the loops turn the given initial rates into rates {ratio:.1e} times larger: `{}'` = {:.3e} with `{}` = {given_rate}",
        model.velocity_name(fastest),
        v[fastest],
        largest_given.1,
    );
    let mut warning = Diagnostic::warning("W0802", message).help(
        "the configuration is close to one where the loops lock or change branch; check the `initial` positions, or give the rate of a coordinate that moves freely there",
    );
    if let Some(initial) = mechanism.initial.iter().find(|i| i.order == 1) {
        warning = warning.primary(initial.span, "given here");
    }
    Some(warning)
}

/// State velocities whose value the program gives (`initial j.q' = …`), and the driven ones (their laws'
/// rates). A quaternion joint's
/// velocities are not its declared rates, so they are never held.
fn given_velocities(mechanism: &Mechanism, model: &Model) -> Vec<(usize, String)> {
    let mut given = Vec::new();
    for initial in mechanism.initial.iter().filter(|i| i.order == 1) {
        let name = mechanism.join_name(initial.join);
        let index = match model.joint_of(initial.join) {
            Some(j) if !model.joints[j].is_quaternion() => {
                model.joints[j].v_offset + initial.coordinate
            }
            Some(_) => continue,
            None => match model.loops.iter().position(|l| l.join == initial.join) {
                Some(k) => model.nv + model.loop_offset(k) + initial.coordinate,
                None => continue,
            },
        };
        let coordinate = &mechanism
            .link(mechanism.join(initial.join).link)
            .coordinates[initial.coordinate];
        given.push((index, format!("{name}.{coordinate}'")));
    }
    // A driven coordinate's rate is its law's (`initial_state` of `prepare`): kept too.
    for drive in &model.drives {
        if !given.iter().any(|(index, _)| *index == drive.velocity) {
            given.push((drive.velocity, format!("{}'", drive.coordinate)));
        }
    }
    given
}

/// The velocities (of `count`) whose rates the program does not give: the loops complete them.
fn completed_velocities(
    given: &[(usize, String)],
    count: usize,
) -> impl Iterator<Item = usize> + '_ {
    (0..count).filter(|i| !given.iter().any(|(g, _)| g == i))
}

/// Changes the velocities not given as little as possible so that G v = 0; when the given ones
/// make that impossible, the rate at which the loops still open (m/s or rad/s).
fn complete_rates(
    jacobian: &DMatrix<f64>,
    given: &[(usize, String)],
    v: &mut [f64],
) -> Result<(), f64> {
    let free: Vec<usize> = completed_velocities(given, v.len()).collect();
    let velocity = DVector::from_column_slice(v);
    let error = jacobian * &velocity;
    // Rates that already keep the loops closed (a start at rest) need no correction: the
    // pseudo-inverse of the free columns (a dense SVD, the cube of a long chain's length: 20 s
    // of the ladder of 300 loops' start) would multiply zeros.
    if error.iter().all(|&e| e == 0.0) {
        return Ok(());
    }
    let free_columns =
        DMatrix::from_fn(jacobian.nrows(), free.len(), |r, c| jacobian[(r, free[c])]);
    let correction = decompose(&free_columns).pseudo_inverse * &error;
    for (k, &i) in free.iter().enumerate() {
        v[i] -= correction[k];
    }
    let left = (jacobian * DVector::from_column_slice(v)).amax();
    let scale = velocity.amax().max(1e-300) * jacobian.amax().max(1e-300);
    if left > 1e-9 * scale {
        return Err(left);
    }
    Ok(())
}

fn incompatible_rates(
    mechanism: &Mechanism,
    given: &[(usize, String)],
    opening: f64,
) -> Diagnostic {
    let names: Vec<String> = given.iter().map(|(_, n)| format!("`{n}`")).collect();
    let mut diagnostic = Diagnostic::error("E0815", format!("the initial rates {} are not compatible with the loops: they leave the loops opening at {opening:.3e} (m/s or rad/s)", names.join(", ")))
        .help("give the rates of independent coordinates only (as many as the mobility); the others follow from the loops");
    if let Some(initial) = mechanism.initial.iter().find(|i| i.order == 1) {
        diagnostic = diagnostic.primary(initial.span, "given here");
    }
    diagnostic
}
