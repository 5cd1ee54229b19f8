//! Geared rotors (a link's `rotor_inertia`, `gear_ratio`, `rotor_axis`; Llibre §2.2–2.5): a
//! motor's rotor carried by the body of the join's first frame, spinning about `rotor_axis`
//! relative to it at n q̇ (n the ratio, q the link's coordinate), with moment of inertia J about
//! its axis. Its mass and transverse inertia belong to the carrying body; what it adds is its
//! spin, of kinetic energy ½ J (ε·ω_B + n q̇)², ω_B the carrier's angular velocity and ε the
//! axis. Hence the mass matrix gains J w wᵀ, w_j = ε·ω_B(e_j) + n δ_jk: the reflected inertia
//! n² J on the coordinate's diagonal and the coupling n J ε·ω_B(e_j) with the joints that turn
//! the carrier; inverse dynamics gains the rotor's torque on its carrier,
//! τ_r = J[(ε·ω̇_B + n q̈) ε + (ε·ω_B + n q̇) ω_B × ε], and n ε·τ_r on the coordinate.

use nalgebra::{DMatrix, DVector, Vector3};

use super::algorithms::{body_motions, Data};
use super::joint::{Joint, JointType};
use super::model::Model;
use crate::diag::Diagnostic;
use crate::elab::mechanism::{LinkRotor, Mechanism};
use crate::kinematics::eval::{eval, UnknownValues};
use crate::kinematics::model::JointModel;
use crate::spatial::{Force, Motion};

/// One geared rotor, in the model's numbering.
#[derive(Clone, Debug)]
pub struct Rotor {
    /// The joint it drives (index into `Model::joints`) and its velocity's index.
    pub joint: usize,
    pub velocity: usize,
    /// The body number that carries it (0 for earth) and its axis there (unit).
    pub carrier: usize,
    pub axis: Vector3<f64>,
    pub inertia: f64,
    pub ratio: f64,
}

/// The rotors of the tree's links. A link with a rotor must have one coordinate (E0453) in a
/// tree mechanism (E0454), and give all three fields as numbers with a non-zero axis (E0453).
pub fn build(
    mechanism: &Mechanism,
    joints: &[Joint],
    loops: &[JointModel],
    unknowns: &UnknownValues,
    errors: &mut Vec<Diagnostic>,
) -> Vec<Rotor> {
    let mut rotors = Vec::new();
    for (k, joint) in joints.iter().enumerate() {
        let join = mechanism.join(joint.chain.join);
        let link = mechanism.link(join.link);
        if !has_rotor(&link.rotor) {
            continue;
        }
        let name = &joint.chain.name;
        if !loops.is_empty() {
            errors.push(
                Diagnostic::error(
                    "E0454",
                    format!("`{name}` has a geared rotor in a mechanism with closed loops"),
                )
                .primary(join.span, "rotors are simulated in tree mechanisms only")
                .help("remove `rotor_inertia`, `gear_ratio` and `rotor_axis`, or open the loop"),
            );
            continue;
        }
        let single = joint.chain.coordinate_count() == 1
            && joint.kind == JointType::Chain
            && joint.nv() == 1;
        match (single, rotor_values(&link.rotor, unknowns)) {
            (true, Some((inertia, ratio, axis))) => {
                let frame = if joint.first_on_parent { joint.on_parent } else { joint.on_child };
                rotors.push(Rotor {
                    joint: k,
                    velocity: joint.v_offset,
                    carrier: if joint.first_on_parent { joint.parent } else { joint.child },
                    axis: frame.rotation * axis.normalize(),
                    inertia,
                    ratio,
                });
            }
            (false, _) => errors.push(
                Diagnostic::error("E0453", format!("`{name}` has a geared rotor but {} coordinates", joint.chain.coordinate_count()))
                    .primary(link.span, "a rotor drives a link with one coordinate")
                    .help("put the rotor on a revolute or prismatic link (`geared_revolute` in `joints`)"),
            ),
            (true, None) => errors.push(
                Diagnostic::error("E0453", format!("the geared rotor of `{name}` is incomplete"))
                    .primary(link.span, "needs `rotor_inertia` (≥ 0), `gear_ratio` and a non-zero `rotor_axis`, as numbers")
                    .help("give all three fields, e.g. `rotor_inertia = 2e-5, gear_ratio = 100, rotor_axis = [0, 0, 1]`"),
            ),
        }
    }
    rotors
}

fn has_rotor(rotor: &LinkRotor) -> bool {
    rotor.inertia.is_some() || rotor.ratio.is_some() || rotor.axis.is_some()
}

fn rotor_values(rotor: &LinkRotor, unknowns: &UnknownValues) -> Option<(f64, f64, Vector3<f64>)> {
    let inertia = eval(rotor.inertia.as_ref()?, unknowns).ok()?;
    let ratio = eval(rotor.ratio.as_ref()?, unknowns).ok()?;
    let axis = rotor.axis.as_ref()?;
    let axis = Vector3::new(
        eval(&axis[0], unknowns).ok()?,
        eval(&axis[1], unknowns).ok()?,
        eval(&axis[2], unknowns).ok()?,
    );
    let valid = inertia >= 0.0 && inertia.is_finite() && ratio.is_finite() && axis.norm() > 0.0;
    valid.then_some((inertia, ratio, axis))
}

/// The rate of a one-coordinate joint, from its state's motion S q̇.
fn joint_rate(data: &Data, joint: usize) -> f64 {
    let state = &data.states[joint];
    let column = state.subspace.column(0);
    column.dot(&state.velocity) / column.norm_squared()
}

fn angular(motion: &Motion) -> Vector3<f64> {
    motion.fixed_rows::<3>(0).into_owned()
}

/// The rotor's spin rate ε·ω_B + n q̇ from the body velocities in `data`.
fn spin(rotor: &Rotor, data: &Data) -> f64 {
    let carried = rotor.axis.dot(&angular(&data.velocity[rotor.carrier]));
    carried + rotor.ratio * joint_rate(data, rotor.joint)
}

/// The rotors' kinetic energy, ½ J (ε·ω_B + n q̇)² each, from the kinematics in `data`.
pub fn kinetic_energy(model: &Model, data: &Data) -> f64 {
    let spin_energy = |r: &Rotor| 0.5 * r.inertia * spin(r, data).powi(2);
    model.rotors.iter().map(spin_energy).sum()
}

/// Adds the rotors' J w wᵀ to the mass matrix, `data` holding the joint transforms at q.
pub fn add_to_mass(model: &Model, data: &Data, mass: &mut DMatrix<f64>) {
    if model.rotors.is_empty() {
        return;
    }
    let mut motions = vec![Motion::zeros(); model.body_count() + 1];
    let mut unit = vec![0.0; model.nv];
    let mut rows = vec![DVector::zeros(model.nv); model.rotors.len()];
    for j in 0..model.nv {
        unit[j] = 1.0;
        body_motions(model, data, &unit, &mut motions);
        unit[j] = 0.0;
        for (row, rotor) in rows.iter_mut().zip(&model.rotors) {
            row[j] = rotor.axis.dot(&angular(&motions[rotor.carrier]));
        }
    }
    for (mut row, rotor) in rows.into_iter().zip(&model.rotors) {
        row[rotor.velocity] += rotor.ratio;
        *mass += rotor.inertia * &row * row.transpose();
    }
}

/// Inverse dynamics of the rotors, between RNEA's passes: adds each rotor's torque τ_r to its
/// carrier's force (so the pass back carries it to the joints that turn the carrier) and
/// returns, per rotor, n ε·τ_r to add to its coordinate's effort afterwards.
pub fn add_torques(model: &Model, data: &mut Data, a: &[f64]) -> Vec<f64> {
    let mut own = Vec::with_capacity(model.rotors.len());
    for rotor in &model.rotors {
        let omega = angular(&data.velocity[rotor.carrier]);
        let omega_dot = match rotor.carrier {
            0 => Vector3::zeros(),
            b => angular(&data.acceleration[b]),
        };
        let axis = rotor.axis;
        let spin_rate = rotor.axis.dot(&omega_dot) + rotor.ratio * a[rotor.velocity];
        let torque = rotor.inertia * (spin_rate * axis + spin(rotor, data) * omega.cross(&axis));
        if rotor.carrier != 0 {
            data.force[rotor.carrier] += Force::new(torque.x, torque.y, torque.z, 0.0, 0.0, 0.0);
        }
        own.push(rotor.ratio * axis.dot(&torque));
    }
    own
}
