//! The dynamic model, compiled once from the mechanism and never changed: the tree's joints
//! (with their types), the bodies' spatial inertias, and the efforts to evaluate at each state.

use nalgebra::{Matrix3, Vector3};

use super::joint::{classify, Joint, JointType};
use super::spatial::{self, Inertia, Pose};
use crate::diag::Diagnostic;
use crate::elab::mechanism::{EffortKind, Mechanism};
use crate::elab::value::{BodyRef, JoinId, Scalar, Vector};
use crate::kinematics::eval::{eval, EvalError, UnknownValues};
use crate::kinematics::model::{constant_pose, KinematicModel};

#[derive(Clone, Debug)]
pub struct BodyInertia {
    pub mass: f64,
    /// Centre of mass in the body frame.
    pub com: Vector3<f64>,
    /// Spatial inertia about the body frame's origin.
    pub inertia: Inertia,
    /// Zero mass and inertia: skipped by the algorithms.
    pub massless: bool,
}

/// A force on a point of a body, or a torque on a body, from `apply`.
#[derive(Clone, Debug)]
pub struct AppliedEffort {
    pub kind: EffortKind,
    /// Body number (1..n).
    pub body: usize,
    /// Point of application in the body frame (forces).
    pub point: Vector3<f64>,
    pub value: Vector,
    /// Body whose basis the value is written in (0 = the fixed basis).
    pub basis: usize,
}

/// A known link effort (`force`, `torque`, `forceN`, `torqueN`).
#[derive(Clone, Debug)]
pub struct LinkEffort {
    /// Index into `Model::joints`.
    pub joint: usize,
    pub kind: EffortKind,
    /// 0 for the plain form (in the chain's first frame), N for the N-th step's frame.
    pub step: u8,
    pub value: Vector,
}

#[derive(Clone, Debug)]
pub struct Model {
    /// `joints[j - 1]` reaches body j.
    pub joints: Vec<Joint>,
    pub bodies: Vec<BodyInertia>,
    pub body_names: Vec<String>,
    pub nq: usize,
    pub nv: usize,
    pub applied: Vec<AppliedEffort>,
    pub link_efforts: Vec<LinkEffort>,
    pub unknowns: UnknownValues,
    /// Join of each joint, and where each join's declared coordinates start.
    pub declared_offsets: Vec<usize>,
    pub declared_count: usize,
}

impl Model {
    pub fn body_count(&self) -> usize {
        self.joints.len()
    }

    pub fn joint_of(&self, join: JoinId) -> Option<usize> {
        self.joints.iter().position(|j| j.chain.join == join)
    }
}

/// The model describes trees: a complementary link is refused, naming it.
pub fn loops_not_supported(mechanism: &Mechanism, join: JoinId) -> Diagnostic {
    Diagnostic::error("E0808", "closed loops cannot be simulated yet")
        .primary(mechanism.join(join).span, format!("join `{}` closes a loop", mechanism.join_name(join)))
        .help("`lsdc tree` and `lsdc assemble` handle loops; simulation handles trees")
}

fn missing(mechanism: &Mechanism, error: EvalError, what: &str) -> Diagnostic {
    match error {
        EvalError::Missing(id) => {
            let name = crate::kinematics::eval::unknown_label(mechanism, id);
            Diagnostic::error("E0806", format!("{what} needs a value for {name}"))
                .primary(mechanism.unknowns[id.0 as usize].span, "no value given")
                .help("give it a number in the program (`mass = 2`), or a value with `--set`")
        }
        EvalError::NotGeometric(detail) => Diagnostic::error("E0807", format!("{what} cannot depend on {detail}")),
    }
}

fn constant_vector(v: &Vector, unknowns: &UnknownValues) -> Result<Vector3<f64>, EvalError> {
    Ok(Vector3::new(eval(&v[0], unknowns, &[])?, eval(&v[1], unknowns, &[])?, eval(&v[2], unknowns, &[])?))
}

fn constant(s: &Scalar, unknowns: &UnknownValues) -> Result<f64, EvalError> {
    eval(s, unknowns, &[])
}

/// Builds the dynamic model of a tree mechanism.
pub fn build(mechanism: &Mechanism, kinematics: &KinematicModel) -> Result<Model, Vec<Diagnostic>> {
    if let Some(joint) = kinematics.complementary().first() {
        return Err(vec![loops_not_supported(mechanism, joint.join)]);
    }
    let unknowns = &kinematics.unknowns;
    let topology = &kinematics.topology;
    let mut errors = Vec::new();
    let mut joints = Vec::new();
    let (mut nq, mut nv) = (0, 0);
    let mut declared_offsets = Vec::new();
    let mut declared = 0;
    for (link, chain) in topology.principal.iter().zip(kinematics.principal()) {
        let (on_parent, on_child) = if link.first_on_parent { (chain.first, chain.second) } else { (chain.second, chain.first) };
        let joint = Joint {
            chain: chain.clone(),
            kind: classify(chain),
            parent: link.parent,
            child: link.child,
            first_on_parent: link.first_on_parent,
            on_parent,
            on_child,
            q_offset: nq,
            v_offset: nv,
        };
        nq += joint.nq();
        nv += joint.nv();
        declared_offsets.push(declared);
        declared += chain.coordinate_count();
        joints.push(joint);
    }
    let mut bodies = Vec::new();
    let mut body_names = Vec::new();
    for &id in &topology.bodies {
        let name = mechanism.body_name(BodyRef::Body(id));
        match body_inertia(mechanism, id, unknowns) {
            Ok(b) => bodies.push(b),
            Err(e) => errors.push(missing(mechanism, e, &format!("the inertia of `{name}`"))),
        }
        body_names.push(name);
    }
    let applied = applied_efforts(mechanism, kinematics, &mut errors);
    let link_efforts = link_efforts(mechanism, &joints);
    if !errors.is_empty() {
        return Err(errors);
    }
    Ok(Model { joints, bodies, body_names, nq, nv, applied, link_efforts, unknowns: unknowns.clone(), declared_offsets, declared_count: declared })
}

fn body_inertia(mechanism: &Mechanism, id: crate::elab::value::BodyId, unknowns: &UnknownValues) -> Result<BodyInertia, EvalError> {
    let body = mechanism.body(id);
    let mass = constant(body.mass.value(), unknowns)?;
    let moments = constant_vector(body.inertia.value(), unknowns)?;
    if mass == 0.0 && moments == Vector3::zeros() {
        return Ok(BodyInertia { mass, com: Vector3::zeros(), inertia: Inertia::zeros(), massless: true });
    }
    let frame: Pose = constant_pose(body.iframe.value(), unknowns)?;
    let rotation = frame.rotation.to_rotation_matrix();
    let central = rotation.matrix() * Matrix3::from_diagonal(&moments) * rotation.matrix().transpose();
    let com = frame.translation.vector;
    Ok(BodyInertia { mass, com, inertia: spatial::inertia(mass, &com, &central), massless: false })
}

fn applied_efforts(mechanism: &Mechanism, kinematics: &KinematicModel, errors: &mut Vec<Diagnostic>) -> Vec<AppliedEffort> {
    let topology = &kinematics.topology;
    let mut applied = Vec::new();
    for application in &mechanism.applications {
        let effort = mechanism.effort(application.effort);
        let body = topology.number(application.target.body);
        if body == 0 {
            continue; // An effort on earth moves nothing.
        }
        let point = match constant_pose(&application.target.displacement, &kinematics.unknowns) {
            Ok(p) => p.translation.vector,
            Err(e) => {
                errors.push(missing(mechanism, e, "the point of application of an effort"));
                continue;
            }
        };
        let point = if effort.kind == EffortKind::Torque { Vector3::zeros() } else { point };
        let basis = match effort.basis {
            BodyRef::Earth => 0,
            BodyRef::Body(id) => match topology.number_of.get(&id) {
                Some(&n) => n,
                None => {
                    errors.push(
                        Diagnostic::error("E0809", "an effort is written in the basis of a body outside the mechanism")
                            .primary(effort.span, "this effort"),
                    );
                    continue;
                }
            },
        };
        applied.push(AppliedEffort { kind: effort.kind, body, point, value: effort.value.value().clone(), basis });
    }
    applied
}

fn link_efforts(mechanism: &Mechanism, joints: &[Joint]) -> Vec<LinkEffort> {
    let mut efforts = Vec::new();
    for (index, joint) in joints.iter().enumerate() {
        let link = mechanism.link(mechanism.join(joint.chain.join).link);
        for (kind, list) in [(EffortKind::Force, &link.forces), (EffortKind::Torque, &link.torques)] {
            for (step, value) in list {
                efforts.push(LinkEffort { joint: index, kind, step: *step, value: value.clone() });
            }
        }
    }
    efforts
}

impl Joint {
    pub fn is_quaternion(&self) -> bool {
        !matches!(self.kind, JointType::Chain)
    }
}

impl Model {
    /// Splits a state (positions, velocities) and brings its quaternions back to unit length.
    pub fn split_state<'y>(&self, y: &'y [f64]) -> (Vec<f64>, &'y [f64]) {
        let (q, v) = y.split_at(self.nq);
        let mut q = q.to_vec();
        for joint in &self.joints {
            joint.normalize(&mut q[joint.q_offset..joint.q_offset + joint.nq()]);
        }
        (q, v)
    }

    /// Positions and velocities from the declared coordinates and rates of every join (in the
    /// joints' order).
    pub fn state_from_declared(&self, coordinates: &[f64], rates: &[f64]) -> Result<(Vec<f64>, Vec<f64>), EvalError> {
        let mut q = vec![0.0; self.nq];
        let mut v = vec![0.0; self.nv];
        for (joint, &offset) in self.joints.iter().zip(&self.declared_offsets) {
            let n = joint.chain.coordinate_count();
            let (jq, jv) = joint.from_declared(&coordinates[offset..offset + n], &rates[offset..offset + n], &self.unknowns)?;
            q[joint.q_offset..joint.q_offset + joint.nq()].copy_from_slice(&jq);
            v[joint.v_offset..joint.v_offset + joint.nv()].copy_from_slice(&jv);
        }
        Ok((q, v))
    }

    /// Declared coordinates and rates at (q, v); `previous` declared coordinates keep recovered
    /// angles continuous.
    pub fn declared(&self, q: &[f64], v: &[f64], previous: &[f64]) -> Result<(Vec<f64>, Vec<f64>), EvalError> {
        let mut coordinates = vec![0.0; self.declared_count];
        let mut rates = vec![0.0; self.declared_count];
        for (joint, &offset) in self.joints.iter().zip(&self.declared_offsets) {
            let n = joint.chain.coordinate_count();
            let (c, r) = joint.declared(
                &q[joint.q_offset..joint.q_offset + joint.nq()],
                &v[joint.v_offset..joint.v_offset + joint.nv()],
                &previous[offset..offset + n],
                &self.unknowns,
            )?;
            coordinates[offset..offset + n].copy_from_slice(&c);
            rates[offset..offset + n].copy_from_slice(&r);
        }
        Ok((coordinates, rates))
    }
}
