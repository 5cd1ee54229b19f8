//! Statics: the efforts actuators must apply along chosen coordinates to hold a mechanism at rest
//! in its initial (assembled) configuration against the program's efforts (gravity, springs…).
//! At rest the equations of motion reduce to f(q) + B τ + Gᵀλ = 0; projected on the motions the
//! loops allow (the null space N of G) this is (NᵀB) τ = −Nᵀf, solved in the least-squares sense.

use nalgebra::{DMatrix, DVector};
use serde::Serialize;

use super::prepare::Prepared;
use super::system::MechanicalSystem;
use crate::dynamics::algorithms::rnea;
use crate::dynamics::loops::{self, Stabilisation};

#[derive(Clone, Debug, Serialize)]
pub struct HeldCoordinate {
    pub name: String,
    /// Generalised effort along the coordinate (N·m for an angle, N for a length).
    pub effort: f64,
}

#[derive(Clone, Debug, Serialize)]
pub struct Holding {
    pub efforts: Vec<HeldCoordinate>,
    /// Largest generalised force the actuators leave unbalanced on a motion the loops allow
    /// (zero when they hold the mechanism).
    pub unbalanced: f64,
}

/// The efforts along `actuated` (names `join.coordinate` of coordinates in their own right: not
/// a quaternion joint's) that hold the mechanism at rest at its initial configuration.
pub fn holding_efforts(prepared: &Prepared, actuated: &[String]) -> Result<Holding, String> {
    let model = &prepared.model;
    let indices = actuated
        .iter()
        .map(|name| velocity_index(prepared, name))
        .collect::<Result<Vec<usize>, String>>()?;
    let (q, _) = model
        .state_from_declared(&prepared.coordinates, &prepared.rates)
        .map_err(|e| format!("{e:?}"))?;
    let rest = vec![0.0; model.velocities()];
    let reference = std::rc::Rc::new(std::cell::RefCell::new(prepared.coordinates.clone()));
    let mut system = MechanicalSystem::new(model, reference, Stabilisation::Projection);
    let efforts = system.efforts(0.0, &q, &rest)?;
    let applied = rnea(
        model,
        &mut system.data,
        &q,
        &rest,
        &rest[..model.nv],
        &efforts.external,
    )
    .map_err(|e| format!("{e:?}"))?;
    let mut force = efforts.tau;
    let mut tree = force.rows_mut(0, model.nv);
    tree -= applied;
    let allowed = if model.has_loops() {
        let c = loops::constraints(model, &mut system.data, &q, &rest, false)
            .map_err(|e| format!("{e:?}"))?;
        loops::decompose(&c.jacobian).null_space
    } else {
        DMatrix::identity(model.velocities(), model.velocities())
    };
    let selection = DMatrix::from_fn(model.velocities(), indices.len(), |r, c| {
        if r == indices[c] {
            1.0
        } else {
            0.0
        }
    });
    let on_motions = allowed.transpose() * &selection;
    let target = -(allowed.transpose() * &force);
    let efforts = loops::decompose(&on_motions).pseudo_inverse * &target;
    let unbalanced: DVector<f64> = &on_motions * &efforts - &target;
    Ok(Holding {
        efforts: actuated
            .iter()
            .zip(efforts.iter())
            .map(|(name, &effort)| HeldCoordinate {
                name: name.clone(),
                effort,
            })
            .collect(),
        unbalanced: unbalanced.amax(),
    })
}

/// The state velocity of coordinate `join.coordinate`.
fn velocity_index(prepared: &Prepared, name: &str) -> Result<usize, String> {
    let model = &prepared.model;
    let Some(declared) = prepared.coordinate_names.iter().position(|n| n == name) else {
        let suggestion = crate::diag::suggest::did_you_mean(
            name,
            prepared.coordinate_names.iter().map(String::as_str),
        )
        .map(|s| format!("; did you mean `{s}`?"))
        .unwrap_or_default();
        return Err(format!(
            "`{name}` is not a coordinate of the mechanism{suggestion}"
        ));
    };
    let tree = model.declared_count - model.nc;
    if declared >= tree {
        return Ok(model.nv + declared - tree);
    }
    let joint = (0..model.joints.len())
        .find(|&j| {
            (model.declared_offsets[j]
                ..model.declared_offsets[j] + model.joints[j].chain.coordinate_count())
                .contains(&declared)
        })
        .ok_or_else(|| format!("`{name}` is not a coordinate of the tree"))?;
    if model.joints[joint].is_quaternion() {
        return Err(format!(
            "`{name}` is an angle of a ball or free joint, not a coordinate an actuator can drive"
        ));
    }
    Ok(model.joints[joint].v_offset + declared - model.declared_offsets[joint])
}
