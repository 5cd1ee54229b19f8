//! A scene that asks only for kinematics builds no dynamics ("model only what a scene needs").
//!
//! When every coordinate of a scene's mechanism follows a drive or is fixed by the loops given
//! the driven ones, its motion is the loops' closure along the drives' laws at each instant:
//! the masses and efforts change nothing in it. If the scene then reads nothing that needs
//! them (its outputs are poses, velocities and values of coordinates; it has no state, stop,
//! contact, mimic or actuator; no reactions are asked for), its run assembles the mechanism at
//! each output time instead of integrating the equations of motion (`simulate::kinematic`),
//! and its model is prepared as `lsdc kinematics` prepares it (`dynamic_model::build_kinematic`:
//! no inertia, effort, rotor, friction or state). The drives' efforts, the energies and the
//! reactions are dynamics, so that such a run does not write them; a scene that wants them
//! names them, and is run with its dynamics.
//!
//! The rates are those of the closure: with J the closure's Jacobian (`kinematics::closure`),
//! J q̇ = 0 along the motion, so that the free coordinates' rates solve
//! J_free q̇_free = −J_driven law'(t), J_free of full column rank (checked at the start: a
//! coordinate neither driven nor fixed by the loops, such as a rod spinning between two ball
//! joints, leaves the scene to the dynamics, which decide its motion).

use nalgebra::{DMatrix, DVector};

use super::outputs::Outputs;
use super::{prepare_parts, Override, Prepared, Settings};
use crate::elab::mechanism::Mechanism;
use crate::kinematics::closure::closure;
use crate::kinematics::eval::EvalError;
use crate::kinematics::model::KinematicModel;

/// Singular values of the free coordinates' closure Jacobian below this fraction of its
/// largest count as zero: the loops then leave a free coordinate undetermined.
const RANK_TOLERANCE: f64 = 1e-9;

/// The scene prepared without its dynamics, when it asks only for kinematics (see the
/// module's comment); `None` otherwise, and for a program without scenes, which is prepared
/// as written.
pub fn prepare(
    mechanism: &Mechanism,
    overrides: &[Override],
    defaults: &Settings,
) -> Option<Prepared> {
    if mechanism.scene.is_none() || !reads_only_kinematics(mechanism) {
        return None;
    }
    let mut prepared = prepare_parts(mechanism, overrides, defaults, false).ok()?;
    let model = &prepared.model;
    let coordinates = prepared.kinematics.coordinate_count;
    let structural = model.stops.is_empty()
        && model.mimics.is_empty()
        && model.contacts.is_empty()
        && model.position_drives.is_empty()
        && !model.drives.is_empty()
        && coordinates == model.declared_count;
    if !structural {
        return None;
    }
    let outputs = Outputs::compile(mechanism, model).ok()?;
    if outputs.reads_model {
        return None;
    }
    let driven = driven_mask(&prepared);
    let driven_rates: Vec<f64> = (prepared.model.drives.iter())
        .map(|d| prepared.rates[d.declared])
        .collect();
    let determined = rates_along_drives(
        &prepared.kinematics,
        &prepared.coordinates,
        &driven,
        &driven_rates,
    );
    if !matches!(determined, Ok(Some(_))) {
        return None;
    }
    prepared.outputs = outputs;
    prepared.kinematics_only = true;
    prepared.planar = Err("a scene that asks only for kinematics builds no dynamics".to_string());
    if let Some(scene) = &mut prepared.scene {
        scene.kinematics_only = true;
    }
    Some(prepared)
}

/// Whether nothing the program declares beyond its joints and drives needs the dynamics to be
/// read: no state (a controller's, a motor's), no actuator, no contact, no frame's path.
fn reads_only_kinematics(mechanism: &Mechanism) -> bool {
    mechanism.states.is_empty()
        && mechanism.actuators.is_empty()
        && mechanism.contacts.is_empty()
        && mechanism.position_drives.is_empty()
        && !mechanism.drives.is_empty()
}

/// Which declared coordinates follow a drive.
pub fn driven_mask(prepared: &Prepared) -> Vec<bool> {
    let mut driven = vec![false; prepared.model.declared_count];
    for drive in &prepared.model.drives {
        driven[drive.declared] = true;
    }
    driven
}

/// The declared coordinates' rates at the closed configuration `q`, the driven ones given
/// (`driven_rates`, in the order of `driven`'s true entries): the free ones from the closure's
/// Jacobian (see the module's comment). `None` when the loops leave a free coordinate
/// undetermined there.
pub fn rates_along_drives(
    kinematics: &KinematicModel,
    q: &[f64],
    driven: &[bool],
    driven_rates: &[f64],
) -> Result<Option<Vec<f64>>, EvalError> {
    let free: Vec<usize> = (0..q.len()).filter(|&i| !driven[i]).collect();
    let mut rates = vec![0.0; q.len()];
    let mut given = driven_rates.iter();
    for (i, _) in driven.iter().enumerate().filter(|(_, &d)| d) {
        rates[i] = *given.next().expect("a rate per driven coordinate");
    }
    if free.is_empty() {
        return Ok(Some(rates));
    }
    let closed = closure(kinematics, q)?;
    let jacobian = &closed.jacobian.dense();
    if jacobian.nrows() < free.len() {
        return Ok(None);
    }
    let mut free_columns = DMatrix::zeros(jacobian.nrows(), free.len());
    for (k, &i) in free.iter().enumerate() {
        free_columns.set_column(k, &jacobian.column(i));
    }
    let mut right = DVector::zeros(jacobian.nrows());
    for (i, _) in driven.iter().enumerate().filter(|(_, &d)| d) {
        right -= jacobian.column(i) * rates[i];
    }
    let Some(svd) = crate::linalg::svd(free_columns, true, true) else {
        return Err(EvalError::NotFinite);
    };
    let largest = svd.singular_values.max();
    let smallest = svd.singular_values.min();
    if !(largest > 0.0 && smallest > RANK_TOLERANCE * largest) {
        return Ok(None);
    }
    let solved = svd.solve(&right, 0.0).map_err(|_| EvalError::NotFinite)?;
    for (k, &i) in free.iter().enumerate() {
        rates[i] = solved[k];
    }
    Ok(Some(rates))
}
