//! Whether a model is planar, decided once from the model as built (its joints' kernels and
//! frames, its bodies, its efforts as the program writes them): every joint a turn about axes
//! parallel to one normal n or a translation perpendicular to it, every loop closed by such a
//! joint (the kinematic model decides these and n, `kinematics::plane`, with no dynamics, for
//! `lsdc tree`), the gravity field and every applied effort in the plane (a force with no
//! component along n, a torque along n alone, each by the expression the program wrote being
//! the constant zero). Then every body moves in a plane perpendicular to n, in every
//! configuration: a joint's axis is fixed in its parent, which turns about n only, so checking
//! the axes at one configuration (every coordinate zero) decides them all.
//!
//! What keeps the spatial form, with the reason: joints of several coordinates or of
//! quaternions (spherical, free), rheonomic chains, ball joints closing loops, contacts,
//! position drives and geared rotors.

use nalgebra::{Matrix3, Vector2, Vector3};

use super::algebra::{PlanarInertia, PlanarMotion};
use super::model::{PlanarJoint, PlanarJointKind, PlanarLoop, PlanarLoopKind, PlanarModel};
use crate::dynamics::algorithms::{forward_kinematics, Data};
use crate::dynamics::joint::{JointType, Kernel};
use crate::dynamics::model::Model;
use crate::elab::mechanism::EffortKind;
use crate::kinematics::eval::eval;
use crate::kinematics::model::{KinematicModel, SingleMotion};
use crate::kinematics::plane::{motion_plane, ROUND_OFF};

/// The model's planar form, or why it keeps the spatial form: the plane its joints move the
/// bodies in (`kinematics::plane`, from the kinematic model `kinematics` it was built from),
/// then what the dynamics add.
pub fn decide(kinematics: &KinematicModel, model: &Model) -> Result<PlanarModel, String> {
    refuse_elements(model)?;
    let normal = motion_plane(kinematics)?;
    let mut data = Data::new(model);
    let zeros = vec![0.0; model.nq.max(model.nv)];
    forward_kinematics(model, &mut data, &zeros[..model.nq], &zeros[..model.nv])
        .map_err(|_| "its joints cannot be evaluated at zero".to_string())?;
    let world = |body: usize| -> Matrix3<f64> {
        match body {
            0 => Matrix3::identity(),
            b => *data.world[b].rotation.to_rotation_matrix().matrix(),
        }
    };
    let basis = plane_basis(&normal);
    // A vector of body b, in its planar frame: Wᵀ R_b.
    let to_planar: Vec<Matrix3<f64>> = (0..=model.body_count())
        .map(|b| basis.transpose() * world(b))
        .collect();
    let mut joints = Vec::new();
    for &k in &model.dynamic_joints {
        joints.push(planar_joint(model, &to_planar, k)?);
    }
    let loops = (0..model.loops.len())
        .map(|k| planar_loop(model, &to_planar, k))
        .collect::<Result<Vec<_>, _>>()?;
    let gravity = basis.transpose() * model.gravity;
    let in_plane = gravity.z.abs() <= ROUND_OFF * model.gravity.norm();
    if !in_plane {
        return Err("its gravity field is not in the plane".to_string());
    }
    refuse_efforts_out_of_plane(model, &to_planar)?;
    let (bodies, massless) = model
        .dynamic_bodies
        .iter()
        .enumerate()
        .map(|(i, body)| {
            let r = &to_planar[i + 1];
            let first = r * body.rigid.first;
            let rotational = r.row(2) * body.rigid.rotational * r.row(2).transpose();
            let inertia = PlanarInertia {
                mass: body.rigid.mass,
                first: first.xy(),
                rotational: rotational[(0, 0)],
            };
            (inertia, body.massless)
        })
        .unzip();
    Ok(PlanarModel {
        rows: axis_rows(&basis),
        basis,
        joints,
        to_planar,
        bodies,
        massless,
        base_acceleration: PlanarMotion::new(0.0, -gravity.x, -gravity.y),
        loops,
    })
}

/// The parts of a model that keep the spatial form whatever their axes.
fn refuse_elements(model: &Model) -> Result<(), String> {
    let refusals = [
        (model.has_contacts(), "contacts"),
        (!model.position_drives.is_empty(), "position drives"),
        (!model.rotors.is_empty(), "geared rotors"),
        (
            model.loop_balls.iter().any(Option::is_some),
            "a ball joint closing a loop",
        ),
    ];
    match refusals.iter().find(|(present, _)| *present) {
        Some((_, what)) => Err(format!("it has {what}")),
        None => Ok(()),
    }
}

/// A right-handed basis (e₁, e₂, n) of the fixed axes: e₁ from the fixed axis least along n.
fn plane_basis(normal: &Vector3<f64>) -> Matrix3<f64> {
    let least = normal.iamin();
    let mut axis = Vector3::zeros();
    axis[least] = 1.0;
    let e1 = (axis - normal * normal.dot(&axis)).normalize();
    let e2 = normal.cross(&e1);
    Matrix3::from_columns(&[e1, e2, *normal])
}

/// The spatial rows of a planar motion's three components (`PlanarModel::rows`), when the
/// basis's columns are fixed axes or their opposites.
fn axis_rows(basis: &Matrix3<f64>) -> Option<[(usize, f64); 3]> {
    let axis = |column: usize| {
        let c = basis.column(column);
        (0..3)
            .find(|&k| c[k].abs() == 1.0 && (0..3).all(|m| m == k || c[m] == 0.0))
            .map(|k| (k, c[k]))
    };
    let ((n, n_sign), (e1, e1_sign), (e2, e2_sign)) = (axis(2)?, axis(0)?, axis(1)?);
    Some([(n, n_sign), (3 + e1, e1_sign), (3 + e2, e2_sign)])
}

/// Tree joint `k` in the plane, from its spatial kernel at q = 0: every body's planar frame
/// then has the plane's axes, so the joint's transform is a translation alone.
fn planar_joint(
    model: &Model,
    to_planar: &[Matrix3<f64>],
    k: usize,
) -> Result<PlanarJoint, String> {
    let joint = &model.joints[k];
    let refused = |why: &str| format!("`{}` {why}", joint.chain.name);
    if joint.kind != JointType::Chain {
        return Err(refused("is a spherical or free joint"));
    }
    let (parent, child) = (joint.dynamic_parent, joint.child);
    let mut state = joint.new_state();
    joint
        .update_transform(&vec![0.0; joint.nq()], &mut state)
        .map_err(|_| refused("cannot be evaluated"))?;
    let origin = (to_planar[parent] * state.transform.translation).xy();
    let (column, kind) = match &joint.kernel {
        Kernel::Weld { .. } => (PlanarMotion::zeros(), PlanarJointKind::Weld { origin }),
        Kernel::Rotation { column, .. } | Kernel::Translation { column, .. } => {
            let angular = to_planar[child] * column.fixed_rows::<3>(0);
            let linear = to_planar[child] * column.fixed_rows::<3>(3);
            let size = column.norm();
            // Written so that a value that is not a number refuses.
            let in_plane = angular.xy().norm() <= ROUND_OFF * size
                && linear.z.abs() <= ROUND_OFF * size
                && size > 0.0;
            if !in_plane {
                return Err(refused("moves out of the plane of the others"));
            }
            let column = PlanarMotion::new(angular.z, linear.x, linear.y);
            let kind = match joint.kernel {
                Kernel::Rotation { .. } => {
                    let rate = angular.z;
                    // The child's origin moves with ω n̂ × (0 − c) = (ω c_y, −ω c_x).
                    let pivot_child = Vector2::new(-linear.y / rate, linear.x / rate);
                    PlanarJointKind::Revolute {
                        rate,
                        pivot_parent: origin + pivot_child,
                        pivot_child,
                    }
                }
                _ => PlanarJointKind::Prismatic {
                    origin,
                    direction: linear.xy(),
                },
            };
            (column, kind)
        }
        Kernel::General => return Err(refused("is not one rotation or translation")),
    };
    Ok(PlanarJoint {
        index: k,
        parent,
        child,
        q_offset: joint.q_offset,
        v_offset: joint.v_offset,
        kind,
        column,
    })
}

/// Complementary link `k` in the plane.
fn planar_loop(model: &Model, to_planar: &[Matrix3<f64>], k: usize) -> Result<PlanarLoop, String> {
    let chain = &model.loops[k];
    let refused = |why: &str| format!("`{}` {why}", chain.name);
    let to_first = to_planar[chain.first_body] * chain.first.rotation.to_rotation_matrix();
    let first = (to_planar[chain.first_body] * chain.first.translation.vector).xy();
    let kind = match chain.single_motion() {
        Some(SingleMotion::Rotation { axis, scale }) => {
            let axis = to_first * axis;
            if !(axis.xy().norm() <= ROUND_OFF * axis.norm() && axis.z != 0.0) {
                return Err(refused("turns about an axis out of the plane's normal"));
            }
            PlanarLoopKind::Revolute {
                rate: axis.z * scale,
            }
        }
        Some(SingleMotion::Translation { direction }) => {
            let direction = to_first * direction;
            let in_plane = direction.z.abs() <= ROUND_OFF * direction.norm();
            if !in_plane {
                return Err(refused("slides out of the plane"));
            }
            PlanarLoopKind::Prismatic {
                direction: direction.xy(),
            }
        }
        None => return Err(refused("is not one rotation or translation")),
    };
    Ok(PlanarLoop {
        first_body: chain.first_body,
        second_body: chain.second_body,
        first,
        kind,
    })
}

/// Refuses an applied effort unless the program wrote its component along the normal (a
/// force's) or across it (a torque's) as the constant zero, in axes where the normal is one of
/// the axes.
fn refuse_efforts_out_of_plane(model: &Model, to_planar: &[Matrix3<f64>]) -> Result<(), String> {
    for effort in &model.applied {
        // The normal in the axes the value is written in.
        let normal = to_planar[effort.basis].row(2).transpose();
        let along = (0..3).find(|&i| (normal[i].abs() - 1.0).abs() <= ROUND_OFF);
        let zero = |i: usize| eval(&effort.value[i], &model.unknowns) == Ok(0.0);
        let in_plane = along.is_some_and(|axis| match effort.kind {
            EffortKind::Force => zero(axis),
            EffortKind::Torque => (0..3).filter(|&i| i != axis).all(zero),
        });
        if !in_plane {
            let body = &model.body_names[effort.body - 1];
            return Err(format!(
                "an effort applied on `{body}` is not written in the plane"
            ));
        }
    }
    Ok(())
}
