//! Kinetic energy, the potential of constant forces in the fixed basis (gravity written as a
//! force), and the total momentum; `data` must hold the forward kinematics of the state.

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

/// The constant forces written in the fixed basis, with their points: a potential −F·p each.
/// `None` if some applied effort or link effort is not of that kind (then the efforts can do work
/// that no potential accounts for).
/// A constant force in the fixed basis: (body number, point in the body frame, force).
pub type ConstantForce = (usize, Vector3<f64>, Vector3<f64>);

pub fn conservative_forces(model: &Model) -> Option<Vec<ConstantForce>> {
    if !model.link_efforts.is_empty() {
        return None;
    }
    let weights = model.bodies.iter().enumerate().filter(|(_, b)| !b.massless).map(|(k, b)| Some((k + 1, b.com, b.mass * model.gravity)));
    model
        .applied
        .iter()
        .map(|e| {
            if e.kind != EffortKind::Force || e.basis != 0 {
                return None;
            }
            let value = |i: usize| eval(&e.value[i], &model.unknowns, &[]).ok();
            Some((e.body, e.point, Vector3::new(value(0)?, value(1)?, value(2)?)))
        })
        .chain(weights)
        .collect()
}

pub fn potential_energy(forces: &[ConstantForce], data: &Data) -> f64 {
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
