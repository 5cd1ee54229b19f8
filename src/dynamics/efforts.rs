//! The efforts at a state: forces applied on frames and torques on bodies (from `apply`), as
//! spatial forces in body frames, and the known link efforts (`force`, `torque`, `forceN`,
//! `torqueN` of the links) as generalised forces. Their values may depend on every join's
//! coordinates and rates and on the time.

use std::rc::Rc;

use nalgebra::{DMatrix, DVector, Matrix3, Vector3};

use super::algorithms::Data;
use super::energy::{constant_potential, Conservative};
use super::joint::JointType;
use super::model::{LinkEffort, Model};
use super::spatial::{self, Force, Pose};
use crate::elab::mechanism::EffortKind;
use crate::elab::value::{BodyRef, Frame, FrameQuantity, JoinId, Vector};
use crate::kinematics::eval::{eval_jet, Env, EvalError};
use crate::kinematics::model::{constant_pose, Step};

/// The efforts at one state.
pub struct Efforts {
    /// Per body (index = body number, 0 unused), in the body's frame.
    pub external: Vec<Force>,
    /// Generalised forces of the link efforts.
    pub tau: DVector<f64>,
    /// The power of the efforts that derive from no potential (dampers, motors, …): the rate
    /// of the work the energy balance counts.
    pub power: f64,
}

impl Efforts {
    /// No effort at all (a model whose only load is its gravity field, or none).
    pub fn none(model: &Model) -> Efforts {
        Efforts {
            external: vec![Force::zeros(); model.body_count() + 1],
            tau: DVector::zeros(model.velocities()),
            power: 0.0,
        }
    }
}

impl Model {
    /// Whether the program applies any effort besides the gravity field.
    pub fn has_efforts(&self) -> bool {
        !self.applied.is_empty() || !self.link_efforts.is_empty()
    }
}

/// Declared coordinates and rates of every join, for expressions.
pub struct Declared<'a> {
    pub model: &'a Model,
    pub coordinates: &'a [f64],
    pub rates: &'a [f64],
}

impl Declared<'_> {
    fn value(&self, join: JoinId, index: usize, order: u32) -> Option<f64> {
        let offset = self.model.declared_offset(join)? + index;
        match order {
            0 => self.coordinates.get(offset).copied(),
            1 => self.rates.get(offset).copied(),
            _ => None,
        }
    }
}

fn vector(v: &Vector, model: &Model, env: &Env<'_>) -> Result<Vector3<f64>, EvalError> {
    let value = |i: usize| eval_jet(&v[i], &model.unknowns, env, &[]).map(|j| j.value);
    Ok(Vector3::new(value(0)?, value(1)?, value(2)?))
}

/// A frame's state at one instant, in the fixed axes.
struct FrameValues {
    position: Vector3<f64>,
    velocity: Vector3<f64>,
    angular_velocity: Vector3<f64>,
    orientation: Matrix3<f64>,
}

impl FrameValues {
    /// The frame at `offset` on `body`; `data` holds the forward kinematics of the state.
    fn new(data: &Data, body: usize, offset: &Pose) -> FrameValues {
        let pose = data.world[body] * offset;
        let velocity = &data.velocity[body];
        let (spin, linear) = (
            Vector3::new(velocity[0], velocity[1], velocity[2]),
            Vector3::new(velocity[3], velocity[4], velocity[5]),
        );
        let turn = |v: Vector3<f64>| data.world[body].rotation * v;
        FrameValues {
            position: pose.translation.vector,
            velocity: turn(linear + spin.cross(&offset.translation.vector)),
            angular_velocity: turn(spin),
            orientation: *pose.rotation.to_rotation_matrix().matrix(),
        }
    }

    fn component(&self, quantity: FrameQuantity) -> f64 {
        match quantity {
            FrameQuantity::Position(i) => self.position[i as usize],
            FrameQuantity::Velocity(i) => self.velocity[i as usize],
            FrameQuantity::AngularVelocity(i) => self.angular_velocity[i as usize],
            FrameQuantity::Orientation(i, j) => self.orientation[(i as usize, j as usize)],
        }
    }
}

/// The state of every frame the efforts use, computed once per evaluation (efforts mention the
/// same frames many times: a spring's direction, its length, its rate).
struct FrameStates<'a> {
    model: &'a Model,
    data: &'a Data,
    known: Vec<FrameValues>,
}

impl<'a> FrameStates<'a> {
    fn new(model: &'a Model, data: &'a Data) -> FrameStates<'a> {
        let known = model
            .effort_frames
            .iter()
            .map(|f| FrameValues::new(data, f.body, &f.offset))
            .collect();
        FrameStates { model, data, known }
    }

    /// Component `quantity` of `frame`'s state.
    fn get(&self, frame: &Frame, quantity: FrameQuantity) -> Result<f64, EvalError> {
        if let Some(k) = self
            .model
            .effort_frames
            .iter()
            .position(|f| std::ptr::eq(Rc::as_ptr(&f.frame), frame))
        {
            return Ok(self.known[k].component(quantity));
        }
        let body = match frame.body {
            BodyRef::Earth => 0,
            BodyRef::Body(id) => *self
                .model
                .body_numbers
                .get(&id)
                .ok_or(EvalError::NotGeometric("a body outside the mechanism"))?,
        };
        let offset = constant_pose(&frame.displacement, &self.model.unknowns)?;
        Ok(FrameValues::new(self.data, body, &offset).component(quantity))
    }
}

/// The potential energy of a conservative mechanism at a state: the constant forces' and the
/// declared potentials; `data` must hold the forward kinematics of the state.
pub fn potential_energy(
    model: &Model,
    data: &Data,
    conservative: &Conservative,
    declared: &Declared<'_>,
    time: f64,
) -> Result<f64, EvalError> {
    let joins = |join: JoinId, index: usize, order: u32| declared.value(join, index, order);
    let states = FrameStates::new(model, data);
    let frames = |frame: &Frame, quantity: FrameQuantity| states.get(frame, quantity);
    let env = Env {
        coordinates: &[],
        rates: None,
        joins: Some(&joins),
        time: Some(time),
        frames: Some(&frames),
    };
    let mut total = constant_potential(&conservative.constant, data);
    for &k in &conservative.applied {
        if let Some(potential) = &model.applied[k].potential {
            total += eval_jet(potential, &model.unknowns, &env, &[])?.value;
        }
    }
    for (joint, potential) in &model.link_potentials {
        let chain = model
            .joints
            .get(*joint)
            .map(|j| &j.chain)
            .unwrap_or_else(|| &model.loops[joint - model.joints.len()]);
        let offset = model.declared_offset(chain.join).unwrap_or(0);
        let n = chain.coordinate_count();
        let link = Env {
            coordinates: &declared.coordinates[offset..offset + n],
            rates: Some(&declared.rates[offset..offset + n]),
            ..env
        };
        total += eval_jet(potential, &model.unknowns, &link, &[])?.value;
    }
    Ok(total)
}

/// Evaluates every effort; `data` must hold the forward kinematics of the state.
pub fn evaluate(
    model: &Model,
    data: &Data,
    declared: &Declared<'_>,
    time: f64,
) -> Result<Efforts, EvalError> {
    let joins = |join: JoinId, index: usize, order: u32| declared.value(join, index, order);
    let states = FrameStates::new(model, data);
    let frames = |frame: &Frame, quantity: FrameQuantity| states.get(frame, quantity);
    let env = Env {
        coordinates: &[],
        rates: None,
        joins: Some(&joins),
        time: Some(time),
        frames: Some(&frames),
    };
    let mut external = vec![Force::zeros(); model.body_count() + 1];
    let mut power = 0.0;
    for effort in &model.applied {
        let value = vector(&effort.value, model, &env)?;
        let in_world = if effort.basis == 0 {
            value
        } else {
            data.world[effort.basis].rotation * value
        };
        let in_body = data.world[effort.body].rotation.inverse() * in_world;
        let wrench = match effort.kind {
            EffortKind::Force => spatial_force(effort.point.cross(&in_body), in_body),
            EffortKind::Torque => spatial_force(in_body, Vector3::zeros()),
        };
        if !effort.conservative {
            power += wrench.dot(&data.velocity[effort.body]);
        }
        external[effort.body] += wrench;
    }
    let mut tau = DVector::zeros(model.velocities());
    for effort in &model.link_efforts {
        let (generalised, link_power) =
            link_effort(model, effort, declared, &joins, &frames, time)?;
        if !effort.conservative {
            power += link_power;
        }
        let (start, count) = match model.joints.get(effort.joint) {
            Some(joint) => (joint.v_offset, joint.nv()),
            None => {
                let k = effort.joint - model.joints.len();
                (
                    model.nv + model.loop_offset(k),
                    model.loops[k].coordinate_count(),
                )
            }
        };
        let mut rows = tau.rows_mut(start, count);
        rows += generalised;
    }
    Ok(Efforts {
        external,
        tau,
        power,
    })
}

fn spatial_force(moment: Vector3<f64>, force: Vector3<f64>) -> Force {
    Force::new(moment.x, moment.y, moment.z, force.x, force.y, force.z)
}

/// A link effort as generalised forces on the joint's velocities.
fn link_effort(
    model: &Model,
    effort: &LinkEffort,
    declared: &Declared<'_>,
    joins: &dyn Fn(JoinId, usize, u32) -> Option<f64>,
    frames: &dyn Fn(&Frame, FrameQuantity) -> Result<f64, EvalError>,
    time: f64,
) -> Result<(DVector<f64>, f64), EvalError> {
    // A complementary link's coordinates are its velocities: no quaternion to map through.
    let (chain, joint) = match model.joints.get(effort.joint) {
        Some(joint) => (&joint.chain, Some(joint)),
        None => (&model.loops[effort.joint - model.joints.len()], None),
    };
    let offset = model.declared_offset(chain.join).unwrap_or(0);
    let n = chain.coordinate_count();
    let coordinates = &declared.coordinates[offset..offset + n];
    let rates = &declared.rates[offset..offset + n];
    let env = Env {
        coordinates,
        rates: Some(rates),
        joins: Some(joins),
        time: Some(time),
        frames: Some(frames),
    };
    let value = vector(&effort.value, model, &env)?;
    let wrench = match effort.kind {
        EffortKind::Force => spatial_force(Vector3::zeros(), value),
        EffortKind::Torque => spatial_force(value, Vector3::zeros()),
    };
    // Generalised forces on the declared coordinates: the wrench against each coordinate's twist.
    let twists = if effort.step == 0 {
        chain
            .chain_motion(coordinates, None, &model.unknowns)?
            .subspace
    } else {
        step_columns(&chain.steps[effort.step as usize - 1], coordinates, model)?
    };
    let on_declared = twists.transpose() * DVector::from_column_slice(wrench.as_slice());
    let power = on_declared.dot(&DVector::from_column_slice(rates));
    if joint.is_none_or(|j| j.kind == JointType::Chain) {
        return Ok((on_declared, power));
    }
    // Quaternion joints: map through the declared rates' dependence on the velocities.
    let jacobian = declared_rate_jacobian(model, effort.joint, coordinates)?;
    Ok((jacobian.transpose() * on_declared, power))
}

/// Twists of one step of a chain per unit rate of each coordinate, in the step's own frame.
fn step_columns(
    step: &Step,
    coordinates: &[f64],
    model: &Model,
) -> Result<DMatrix<f64>, EvalError> {
    let n = coordinates.len();
    let env = Env {
        coordinates,
        ..Env::default()
    };
    let mut columns = DMatrix::zeros(6, n);
    let mut unit = vec![0.0; n];
    for k in 0..n {
        unit[k] = 1.0;
        let d = |s| eval_jet(s, &model.unknowns, &env, &unit).map(|j| j.first);
        match step {
            Step::Translation(v) => {
                for i in 0..3 {
                    columns[(3 + i, k)] = d(&v[i])?;
                }
            }
            Step::Rotation { angle, axis } => {
                let rate = d(angle)?;
                for i in 0..3 {
                    columns[(i, k)] = axis[i] * rate;
                }
            }
        }
        unit[k] = 0.0;
    }
    Ok(columns)
}

/// ∂(declared rates)/∂(velocities) of a quaternion joint at given declared coordinates.
fn declared_rate_jacobian(
    model: &Model,
    joint: usize,
    coordinates: &[f64],
) -> Result<DMatrix<f64>, EvalError> {
    let joint = &model.joints[joint];
    let motion = joint
        .chain
        .chain_motion(coordinates, None, &model.unknowns)?;
    let nv = joint.nv();
    let mut chain_twists = DMatrix::zeros(6, nv);
    for k in 0..nv {
        let mut unit = spatial::Motion::zeros();
        unit[k] = 1.0;
        let twist = if joint.first_on_parent {
            spatial::motion_to_parent(&motion.pose, &unit)
        } else {
            -unit
        };
        chain_twists.set_column(k, &twist);
    }
    let pseudo_inverse = motion
        .subspace
        .clone()
        .pseudo_inverse(1e-12)
        .map_err(|_| EvalError::NotGeometric("a degenerate joint"))?;
    Ok(pseudo_inverse * chain_twists)
}
