//! Kinetic energy, the potential energy (of constant forces in the fixed basis, such as gravity
//! written as a force, and the potentials the program declares for its force elements), and the
//! total momentum; `data` must hold the forward kinematics of the state.

use nalgebra::Vector3;

use super::algorithms::Data;
use super::model::constant_fixed_force;
use super::model::Model;
use crate::spatial::{self, Force};

pub fn kinetic_energy(model: &Model, data: &Data) -> f64 {
    model
        .bodies
        .iter()
        .enumerate()
        .filter(|(_, b)| !b.massless)
        .map(|(k, b)| 0.5 * data.velocity[k + 1].dot(&(b.inertia * data.velocity[k + 1])))
        .sum::<f64>()
        + super::algorithms::rotor_kinetic_energy(model, data)
}

/// A constant force in the fixed basis: (body number, point in the body frame, force).
pub type ConstantForce = (usize, Vector3<f64>, Vector3<f64>);

/// The efforts of a conservative mechanism: constant forces in the fixed basis (a potential −F·p
/// each), and efforts whose potential the program declares (`potential = ...` of a force, a
/// torque or a link), taken to derive from it.
pub struct Conservative {
    pub constant: Vec<ConstantForce>,
    /// Indices into `Model::applied` of the efforts with a declared potential.
    pub applied: Vec<usize>,
    /// Whether every effort is conservative: then the energy is conserved, and its drift
    /// measures the integration.
    pub complete: bool,
}

/// The conservative efforts of a mechanism: those whose potential the energy report counts.
pub fn conservative_forces(model: &Model) -> Conservative {
    let weights = model
        .bodies
        .iter()
        .enumerate()
        .filter(|(_, b)| !b.massless)
        .map(|(k, b)| (k + 1, b.com, b.mass * model.gravity));
    let mut constant: Vec<ConstantForce> = weights.collect();
    let mut applied = Vec::new();
    for (k, e) in model.applied.iter().enumerate() {
        if e.potential.is_some() {
            applied.push(k);
        } else if let Some(force) = constant_fixed_force(e, &model.unknowns) {
            constant.push((e.body, e.point, force));
        }
    }
    let complete = model.applied.iter().all(|e| e.conservative)
        && model.link_efforts.iter().all(|e| e.conservative)
        // Coulomb friction dissipates: its power is tracked as work (see `simulate::system`).
        && model.contacts.iter().all(|c| c.friction.is_none())
        && model.frictions.iter().all(|f| f.dry == 0.0 && f.viscous == 0.0)
        // A drive does work on the mechanism: tracked as work too.
        && model.drives.is_empty()
        && model.position_drives.is_empty();
    Conservative {
        constant,
        applied,
        complete,
    }
}

/// The potential of the constant forces.
pub fn constant_potential(forces: &[ConstantForce], data: &Data) -> f64 {
    forces
        .iter()
        .map(|(body, point, force)| {
            -force.dot(&(data.world[*body] * nalgebra::Point3::from(*point)).coords)
        })
        .sum()
}

/// Total momentum in the fixed frame: angular momentum about its origin, then linear momentum.
pub fn momentum(model: &Model, data: &Data) -> Force {
    let mut total = Force::zeros();
    for (k, body) in model.bodies.iter().enumerate().filter(|(_, b)| !b.massless) {
        let own = body.inertia * data.velocity[k + 1];
        total += spatial::force_to_parent(&data.world[k + 1], &own);
    }
    total
}
