//! The efforts at a state: forces applied on frames and torques on bodies (from `apply`), as
//! spatial forces in body frames, and the known link efforts (`force`, `torque`, `forceN`,
//! `torqueN` of the links) as generalised forces. Their values may depend on every join's
//! coordinates and rates and on the time.

use nalgebra::{DMatrix, DVector, Matrix6, Vector3};

use super::algorithms::Data;
use super::compiled::{EffortState, EffortTape};
use super::energy::{constant_potential, Conservative};
use super::joint::JointType;
use super::model::{AppliedGroup, LinkEffort, Model};
use crate::elab::mechanism::EffortKind;
use crate::kinematics::eval::EvalError;
use crate::kinematics::model::ChainMotion;
use crate::spatial::{self, Force};

/// The efforts at one state.
#[derive(Clone, Debug)]
pub struct Efforts {
    /// Per body (index = body number, 0 unused), in the body's frame.
    pub external: Vec<Force>,
    /// Generalised forces of the link efforts.
    pub tau: DVector<f64>,
    /// The power of the efforts that derive from no potential (dampers, motors, …): the rate
    /// of the work the energy balance counts.
    pub power: f64,
    /// What the link efforts compute on the way, kept between evaluations.
    links: LinkScratch,
}

/// The link efforts' scratch: a chain's motion, one step's twists per coordinate, the
/// generalised forces on the declared coordinates, unit rates.
#[derive(Clone, Debug, Default)]
struct LinkScratch {
    chain: ChainMotion,
    step: DMatrix<f64>,
    on_declared: Vec<f64>,
}

impl Efforts {
    /// No effort at all (a model whose only load is its gravity field, or none).
    pub fn none(model: &Model) -> Efforts {
        Efforts {
            external: vec![Force::zeros(); model.body_count() + 1],
            tau: DVector::zeros(model.velocities()),
            power: 0.0,
            links: LinkScratch::default(),
        }
    }
}

impl Model {
    /// Whether the program applies any effort besides the gravity field (actuators included),
    /// or has states (whose rates the efforts' tape gives).
    pub fn has_efforts(&self) -> bool {
        !self.applied.is_empty()
            || !self.link_efforts.is_empty()
            || self.actuation.is_some()
            || !self.states.is_empty()
    }
}

/// Declared coordinates and rates of every join, and the values of the states, for
/// expressions.
pub struct Declared<'a> {
    pub model: &'a Model,
    pub coordinates: &'a [f64],
    pub rates: &'a [f64],
    pub states: &'a [f64],
}

impl<'a> Declared<'a> {
    /// Evaluates the model's effort tape at this state (with `energy`, the potentials too),
    /// into `data`'s scratch.
    fn evaluate_tape(
        &self,
        data: &mut Data,
        time: f64,
        energy: bool,
    ) -> Result<&'a EffortTape, EvalError> {
        let tape = self.model.effort_tape.as_ref().map_err(Clone::clone)?;
        let state = EffortState {
            world: &data.world,
            velocity: &data.velocity,
            coordinates: self.coordinates,
            rates: self.rates,
            states: self.states,
            time,
            model: &[],
        };
        tape.eval(&self.model.effort_frames, &state, energy, &mut data.efforts);
        Ok(tape)
    }
}

/// The components of an effort's value among the tape's roots.
fn vector(tape: &EffortTape, data: &Data, roots: [usize; 3]) -> Vector3<f64> {
    let value = |k: usize| tape.root(&data.efforts, roots[k]);
    Vector3::new(value(0), value(1), value(2))
}

/// The potential energy of a conservative mechanism at a state: the constant forces' and the
/// declared potentials; `data` must hold the forward kinematics of the state.
pub fn potential_energy(
    model: &Model,
    data: &mut Data,
    conservative: &Conservative,
    declared: &Declared<'_>,
    time: f64,
) -> Result<f64, EvalError> {
    let tape = declared.evaluate_tape(data, time, true)?;
    let mut total = constant_potential(&conservative.constant, data);
    for &k in &conservative.applied {
        if let Some(root) = model.applied[k].potential_root {
            total += tape.root(&data.efforts, root);
        }
    }
    for potential in &model.link_potentials {
        total += tape.root(&data.efforts, potential.root);
    }
    Ok(total)
}

/// Evaluates every effort; `data` must hold the forward kinematics of the state.
pub fn evaluate(
    model: &Model,
    data: &mut Data,
    declared: &Declared<'_>,
    time: f64,
) -> Result<Efforts, EvalError> {
    let mut efforts = Efforts::none(model);
    evaluate_into(model, data, declared, time, &mut efforts)?;
    Ok(efforts)
}

/// `evaluate` writing into `efforts` (made by `Efforts::none` for this model), reusing its
/// vectors.
pub fn evaluate_into(
    model: &Model,
    data: &mut Data,
    declared: &Declared<'_>,
    time: f64,
    efforts: &mut Efforts,
) -> Result<(), EvalError> {
    let tape = declared.evaluate_tape(data, time, false)?;
    let Efforts {
        external,
        tau,
        power,
        links,
    } = efforts;
    external.fill(Force::zeros());
    tau.fill(0.0);
    *power = 0.0;
    for group in &model.applied_groups {
        let wrench = applied_wrench(data, group, vector(tape, data, group.value_roots));
        if let Some(roots) = group.nonconservative_roots {
            let nonconservative = applied_wrench(data, group, vector(tape, data, roots));
            *power += nonconservative.dot(&data.velocity[group.body]);
        }
        external[group.body] += wrench;
    }
    for effort in &model.link_efforts {
        let value = vector(tape, data, effort.value_roots);
        let link_power = link_effort(model, effort, value, declared, links, tau)?;
        if !effort.conservative {
            *power += link_power;
        }
    }
    Ok(())
}

/// The wrench, in its body's frame, of an applied effort of value `value` (in its basis).
fn applied_wrench(data: &Data, group: &AppliedGroup, value: Vector3<f64>) -> Force {
    let in_world = if group.basis == 0 {
        value
    } else {
        data.world[group.basis].rotation * value
    };
    let in_body = data.world[group.body]
        .rotation
        .inverse_transform_vector(&in_world);
    match group.kind {
        EffortKind::Force => spatial_force(group.point.cross(&in_body), in_body),
        EffortKind::Torque => spatial_force(in_body, Vector3::zeros()),
    }
}

fn spatial_force(moment: Vector3<f64>, force: Vector3<f64>) -> Force {
    Force::new(moment.x, moment.y, moment.z, force.x, force.y, force.z)
}

/// Adds a link effort of value `value` to the generalised forces `tau` on the joint's velocities;
/// returns its power.
fn link_effort(
    model: &Model,
    effort: &LinkEffort,
    value: Vector3<f64>,
    declared: &Declared<'_>,
    scratch: &mut LinkScratch,
    tau: &mut DVector<f64>,
) -> Result<f64, EvalError> {
    // A complementary link's coordinates are its velocities: no quaternion to map through.
    let (chain, joint, start) = match model.joints.get(effort.joint) {
        Some(joint) => (&joint.chain, Some(joint), joint.v_offset),
        None => {
            let k = effort.joint - model.joints.len();
            (&model.loops[k], None, model.nv + model.loop_offset(k))
        }
    };
    let offset = model.declared_offset(chain.join).unwrap_or(0);
    let n = chain.coordinate_count();
    let coordinates = &declared.coordinates[offset..offset + n];
    let rates = &declared.rates[offset..offset + n];
    let wrench = match effort.kind {
        EffortKind::Force => spatial_force(Vector3::zeros(), value),
        EffortKind::Torque => spatial_force(value, Vector3::zeros()),
    };
    // Generalised forces on the declared coordinates: the wrench against each coordinate's twist.
    let twists = if effort.step == 0 {
        let chain_motion = &mut scratch.chain;
        chain.chain_motion_into(coordinates, None, chain_motion)?;
        &chain_motion.subspace
    } else {
        let step = effort.step as usize - 1;
        chain.step_columns_into(coordinates, step, &mut scratch.chain, &mut scratch.step)?;
        &scratch.step
    };
    let on_declared = &mut scratch.on_declared;
    on_declared.clear();
    on_declared.extend(twists.column_iter().map(|twist| twist.dot(&wrench)));
    let power = on_declared.iter().zip(rates).map(|(f, r)| f * r).sum();
    match joint {
        Some(joint) if joint.kind != JointType::Chain => {
            // Quaternion joints: map through the declared rates' dependence on the velocities.
            let jacobian =
                declared_rate_jacobian(model, effort.joint, coordinates, &mut scratch.chain)?;
            for (k, column) in jacobian.column_iter().take(joint.nv()).enumerate() {
                let along: f64 = column
                    .iter()
                    .zip(on_declared.iter())
                    .map(|(j, f)| j * f)
                    .sum();
                tau[start + k] += along;
            }
        }
        _ => {
            for (k, f) in on_declared.iter().enumerate() {
                tau[start + k] += f;
            }
        }
    }
    Ok(power)
}

/// ∂(declared rates)/∂(velocities) of a quaternion joint at given declared coordinates: the
/// first `nv` columns of the 6 × 6 result, its first rows for the declared coordinates (at most
/// six); `motion` is scratch. Fixed-size matrices throughout: nothing is allocated.
fn declared_rate_jacobian(
    model: &Model,
    joint: usize,
    coordinates: &[f64],
    motion: &mut ChainMotion,
) -> Result<Matrix6<f64>, EvalError> {
    let joint = &model.joints[joint];
    joint.chain.chain_motion_into(coordinates, None, motion)?;
    let mut chain_twists = Matrix6::zeros();
    for k in 0..joint.nv() {
        let mut unit = spatial::Motion::zeros();
        unit[k] = 1.0;
        let twist = if joint.first_on_parent {
            spatial::motion_to_parent(&motion.pose, &unit)
        } else {
            -unit
        };
        chain_twists.set_column(k, &twist);
    }
    let subspace = DMatrix::from_column_slice(6, 6, motion.padded_subspace().as_slice());
    let pseudo_inverse = crate::linalg::pseudo_inverse(subspace, 1e-12)
        .map(|p| Matrix6::from_column_slice(p.as_slice()))
        .ok_or(EvalError::NotGeometric("a degenerate joint"))?;
    Ok(pseudo_inverse * chain_twists)
}
