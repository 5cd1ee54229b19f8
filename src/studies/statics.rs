//! Statics: the efforts actuators must apply along chosen coordinates to hold a mechanism at rest
//! in its initial (assembled) configuration against the program's efforts (gravity, springs…).
//! At rest the equations of motion reduce to f(q) + B τ + Gᵀλ = 0; projected on the motions the
//! loops allow (the null space N of G) this is (NᵀB) τ = −Nᵀf, solved in the least-squares sense.

use std::fmt;

use nalgebra::{DMatrix, DVector};
use serde::Serialize;

use crate::dynamics::algorithms::rnea;
use crate::dynamics::contacts;
use crate::dynamics::loops::{self, Extent, Stabilisation};
use crate::prepare::Prepared;
use crate::simulate::system::{MechanicalSystem, SystemError};

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
pub fn holding_efforts(prepared: &Prepared, actuated: &[String]) -> Result<Holding, StaticsError> {
    let model = &prepared.model;
    if let Some(driven) = model.drives.first() {
        return Err(StaticsError::ImposedMotion {
            name: driven.coordinate.clone(),
        });
    }
    let indices = actuated
        .iter()
        .map(|name| velocity_index(prepared, name))
        .collect::<Result<Vec<usize>, StaticsError>>()?;
    let (q, _) = model
        .state_from_declared(&prepared.coordinates, &prepared.rates)
        .map_err(SystemError::from)?;
    let rest = vec![0.0; model.velocities()];
    let reference = prepared.coordinates.clone();
    let mut system = MechanicalSystem::new(model, reference, Stabilisation::Projection);
    let efforts = system.efforts(0.0, &q, &rest)?;
    let applied = rnea(
        model,
        &mut system.scratch.data,
        &q,
        &rest,
        &rest[..model.nv],
        &efforts.external,
    )
    .map_err(SystemError::from)?;
    let mut force = efforts.tau;
    let mut tree = force.rows_mut(0, model.nv);
    tree -= applied;
    let allowed = if model.has_loops() {
        let c = loops::constraints(model, &mut system.scratch.data, &q, &rest, Extent::Rows)
            .map_err(SystemError::from)?;
        loops::decompose(&c.jacobian.dense()).null_space
    } else if model.has_contacts() {
        // At rest a sliding contact's friction has no direction: only its normal row holds.
        let rows = contacts::contact_rows(model, &mut system.scratch.data, &rest, false);
        let candidates = contacts::candidate_rows(model);
        loops::decompose(&rows.jacobian.select_rows(&candidates)).null_space
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

/// The state velocity of coordinate `join.coordinate` (a coordinate in its own right: not a
/// quaternion joint's angle).
pub fn velocity_index(prepared: &Prepared, name: &str) -> Result<usize, StaticsError> {
    let model = &prepared.model;
    let Some(declared) = prepared.coordinate_names.iter().position(|n| n == name) else {
        let suggestion = crate::diag::suggest::did_you_mean(
            name,
            prepared.coordinate_names.iter().map(String::as_str),
        )
        .map(str::to_string);
        return Err(StaticsError::UnknownCoordinate {
            name: name.to_string(),
            suggestion,
        });
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
        .ok_or_else(|| StaticsError::NotInTree {
            name: name.to_string(),
        })?;
    if model.joints[joint].is_quaternion() {
        return Err(StaticsError::QuaternionAngle {
            name: name.to_string(),
        });
    }
    Ok(model.joints[joint].v_offset + declared - model.declared_offsets[joint])
}

/// Why the holding efforts cannot be computed.
#[derive(Debug)]
pub enum StaticsError {
    /// `name` is no declared coordinate; `suggestion` is the closest one, if any is close.
    UnknownCoordinate {
        name: String,
        suggestion: Option<String>,
    },
    /// `name` is a declared coordinate but not one of the tree's joints.
    NotInTree { name: String },
    /// `name` is an angle of a ball or free joint, whose motion is not along it.
    QuaternionAngle { name: String },
    /// `name` is imposed by a law of time (a drive, or `time` in a dof chain): the mechanism
    /// is not at rest, and its coordinates are not all free to be held.
    ImposedMotion { name: String },
    /// The efforts or the loops cannot be evaluated at the initial configuration.
    System(SystemError),
}

impl From<SystemError> for StaticsError {
    fn from(error: SystemError) -> Self {
        StaticsError::System(error)
    }
}

impl fmt::Display for StaticsError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            StaticsError::UnknownCoordinate { name, suggestion } => {
                write!(f, "`{name}` is not a coordinate of the mechanism")?;
                if let Some(suggestion) = suggestion {
                    write!(f, "; did you mean `{suggestion}`?")?;
                }
                Ok(())
            }
            StaticsError::NotInTree { name } => {
                write!(f, "`{name}` is not a coordinate of the tree")
            }
            StaticsError::QuaternionAngle { name } => write!(
                f,
                "`{name}` is an angle of a ball or free joint, not a coordinate an actuator can drive"
            ),
            StaticsError::ImposedMotion { name } => write!(
                f,
                "`{name}` is imposed by a law of time: the efforts that impose a motion are `lsdc inverse`'s, and the efforts that hold a mechanism at rest need its coordinates free"
            ),
            StaticsError::System(error) => write!(f, "{error}"),
        }
    }
}

impl std::error::Error for StaticsError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            StaticsError::System(error) => Some(error),
            _ => None,
        }
    }
}
