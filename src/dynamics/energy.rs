//! Kinetic energy, the potential energy (of constant forces in the fixed basis, such as gravity
//! written as a force, and the potentials the program declares for its force elements), and the
//! total momentum; `data` must hold the forward kinematics of the state.

use nalgebra::Vector3;

use super::algorithms::Data;
use super::model::Model;
use super::spatial::{self, Force};
use crate::elab::mechanism::EffortKind;
use crate::kinematics::eval::eval;

pub fn kinetic_energy(model: &Model, data: &Data) -> f64 {
    model
        .bodies
        .iter()
        .enumerate()
        .filter(|(_, b)| !b.massless)
        .map(|(k, b)| 0.5 * data.velocity[k + 1].dot(&(b.inertia * data.velocity[k + 1])))
        .sum()
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
    /// Whether the links' declared potentials count (every link effort belongs to a link that
    /// declares one).
    pub links: bool,
}

/// `None` if some effort is neither a constant force in the fixed basis nor declares a
/// potential: then the efforts can do work that no potential accounts for.
pub fn conservative_forces(model: &Model) -> Option<Conservative> {
    let declared = |joint: usize| model.link_potentials.iter().any(|(k, _)| *k == joint);
    if !model.link_efforts.iter().all(|e| declared(e.joint)) {
        return None;
    }
    let weights = model.bodies.iter().enumerate().filter(|(_, b)| !b.massless).map(|(k, b)| (k + 1, b.com, b.mass * model.gravity));
    let mut constant: Vec<ConstantForce> = weights.collect();
    let mut applied = Vec::new();
    for (k, e) in model.applied.iter().enumerate() {
        if e.potential.is_some() {
            applied.push(k);
            continue;
        }
        if e.kind != EffortKind::Force || e.basis != 0 {
            return None;
        }
        let value = |i: usize| eval(&e.value[i], &model.unknowns, &[]).ok();
        constant.push((e.body, e.point, Vector3::new(value(0)?, value(1)?, value(2)?)));
    }
    Some(Conservative { constant, applied, links: !model.link_potentials.is_empty() })
}

/// The potential of the constant forces.
pub fn constant_potential(forces: &[ConstantForce], data: &Data) -> f64 {
    forces.iter().map(|(body, point, force)| -force.dot(&(data.world[*body] * nalgebra::Point3::from(*point)).coords)).sum()
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
