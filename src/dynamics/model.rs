//! The dynamic model, compiled once from the mechanism and never changed: the tree's joints
//! (with their types), the bodies' spatial inertias, and the efforts to evaluate at each state.

use nalgebra::{Matrix3, Vector3};

use super::actuators::{self, Actuation};
use super::angles::{AngleReference, JointReference};
use super::compiled::{EffortTape, Link, TapeBuilder};
use super::drives::{self, DrivenCoordinate};
pub use super::elements::{
    AppliedEffort, AppliedGroup, BodyInertia, EffortFrame, LinkEffort, LinkPotential,
};
use super::friction::{self, Friction};
use super::joint::{classify, kernel, Joint, JointType, Kernel};
use super::mimics::{self, Mimic};
use super::rotors::{self, Rotor};
use super::states::{self, StateModel};
use super::stops::{self, Stop};
use super::welds;
use crate::diag::Diagnostic;
use crate::elab::mechanism::{inertia_problem, EffortKind, Mechanism};
use crate::elab::value::{BodyRef, JoinId, Scalar, Vector};
use crate::kinematics::contacts::{contact_models, ContactModel};
use crate::kinematics::eval::{eval, EvalError, UnknownValues};
use crate::kinematics::model::{constant_pose, ChainMotion, JointModel, KinematicModel};
use crate::kinematics::position_drives::{self, ResolvedPositionDrive};
use crate::source::Span;
use crate::spatial::{self, Inertia, Pose, RigidInertia, Transform};
use crate::symbolic::expr::ExprId;

#[derive(Clone, Debug)]
pub struct Model {
    /// `joints[j - 1]` reaches body j.
    pub joints: Vec<Joint>,
    pub bodies: Vec<BodyInertia>,
    pub body_names: Vec<String>,
    /// The number of each body of the tree, for efforts that refer to frames.
    pub body_numbers: std::collections::HashMap<crate::elab::value::BodyId, usize>,
    /// The joints RNEA, CRBA and ABA visit (all but the merged welds), the bodies' inertias as
    /// they see them (merged ones added to their anchor), and each body's pose in its anchor:
    /// see `welds`.
    pub dynamic_joints: Vec<usize>,
    pub dynamic_bodies: Vec<BodyInertia>,
    pub anchor_offsets: Vec<Transform>,
    /// Per joint, the velocities of the joint and of its ancestors among the dynamic joints:
    /// the rows of the mass matrix its columns reach (`branch_velocities`). Made at the first
    /// use: a chain of n joints has n (n + 1) / 2 of them, and a run by the articulated-body
    /// algorithm never reads them, so that its memory grows as n.
    branches: std::sync::OnceLock<Vec<Vec<usize>>>,
    /// Per velocity of the tree, the joint it belongs to (`joint_of_velocity`). Made at the
    /// first use, as `branches`: a table instead of a search of the joints, which the loops'
    /// scaling asks once per column of every loop.
    velocity_joints: std::sync::OnceLock<Vec<Option<usize>>>,
    pub nq: usize,
    pub nv: usize,
    pub applied: Vec<AppliedEffort>,
    /// A uniform gravity field (m/s², fixed basis), zero when there is none: the weights the
    /// program applies to every body with mass, recognised when the model is built and taken
    /// out of `applied`. The algorithms then give the base the acceleration −g, which costs
    /// nothing per body, instead of evaluating one force per body at each state.
    pub gravity: Vector3<f64>,
    pub link_efforts: Vec<LinkEffort>,
    /// The links' declared potentials, by joint (index into `joints`, then into `loops`).
    pub link_potentials: Vec<LinkPotential>,
    /// Every effort's value and potential compiled into one tape (see `compiled`), or why they
    /// cannot be evaluated.
    pub effort_tape: Result<EffortTape, EvalError>,
    /// The applied efforts as the right-hand side applies them: summed by kind, body, point and
    /// basis. Set when the efforts are compiled.
    pub applied_groups: Vec<AppliedGroup>,
    /// The frames whose state the efforts use (`position(F)`, …), placed on their bodies.
    pub effort_frames: Vec<EffortFrame>,
    pub unknowns: UnknownValues,
    /// Where each tree joint's declared coordinates start.
    pub declared_offsets: Vec<usize>,
    /// Per tree joint, whether the efforts read its declared coordinates or rates (the tape, a
    /// link effort or potential on it): only those are recovered from the state at each
    /// evaluation. Set when the efforts are compiled.
    pub declared_read: Vec<bool>,
    /// Declared coordinates of the whole mechanism: the tree's, then the complementary links'.
    pub declared_count: usize,
    /// The complementary links, which close the loops: their chains, with `offset` the index of
    /// their first coordinate among the declared coordinates. Their coordinates follow the
    /// tree's in the state, in position and in velocity alike (they carry no inertia).
    pub loops: Vec<JointModel>,
    /// Coordinates of the complementary links.
    pub nc: usize,
    /// For each complementary link that is a ball joint (three rotations about independent axes
    /// through one point), its axes: it constrains only the point, and its angles are recovered
    /// from the bodies' poses rather than integrated (no gimbal lock).
    pub loop_balls: Vec<Option<[Vector3<f64>; 3]>>,
    /// Contacts of round bodies on planes: constraints on the tree's velocities (see
    /// `contacts`).
    pub contacts: Vec<ContactModel>,
    /// The bounds of the tree's coordinates (links' `lower` and `upper`): events of a run.
    pub stops: Vec<Stop>,
    /// The geared rotors of the tree's links (`rotor_inertia`, `gear_ratio`, `rotor_axis`).
    pub rotors: Vec<Rotor>,
    /// The couplings of mimic joints to their leaders (`mimic`), eliminated from the dynamics.
    pub mimics: Vec<Mimic>,
    /// The friction in the tree's joints (`friction`, `damping`).
    pub frictions: Vec<Friction>,
    /// The coordinates imposed as laws of time (`drive`): rows of the constraint rows.
    pub drives: Vec<DrivenCoordinate>,
    /// The frames' positions imposed as laws of time (`drive position(F) = law`): three rows
    /// each (`driven_points`).
    pub position_drives: Vec<ResolvedPositionDrive>,
    /// The program's states (`state(x0)`), integrated with the motion after the velocities.
    pub states: Vec<StateModel>,
    /// The program's declared effort inputs (`input swing.q = 0;`): the names of the
    /// velocities they act along and their start values, which every run holds until its
    /// caller sets them (`Simulator`). Its value inputs are states (`StateModel::input`).
    pub effort_inputs: Vec<(String, f64)>,
    /// The actuators (`actuate`), whose laws may read the model; `None` without any.
    pub actuation: Option<Actuation>,
    /// Whether the model carries the dynamics: the bodies' inertias, the efforts, rotors,
    /// friction and states. False for a study that asks only for kinematics
    /// (`build_kinematic`): its bodies are all massless and it has no effort.
    pub dynamics: bool,
}

impl Model {
    pub fn body_count(&self) -> usize {
        self.joints.len()
    }

    /// The velocities of joint `k` and of its ancestors among the dynamic joints (its own
    /// first, then up the branch): the rows of the mass matrix its columns reach.
    pub fn branch_velocities(&self, k: usize) -> &[usize] {
        &self
            .branches
            .get_or_init(|| branch_velocities(&self.joints))[k]
    }

    /// The joint that velocity `velocity` of the tree belongs to; none for a loop's velocity
    /// (beyond `nv`). A weld, without velocities, shares its offset with the next joint's: it
    /// is not that joint.
    pub fn joint_of_velocity(&self, velocity: usize) -> Option<&Joint> {
        self.joint_index_of_velocity(velocity)
            .map(|k| &self.joints[k])
    }

    /// The index in `joints` of the joint `joint_of_velocity` gives.
    pub fn joint_index_of_velocity(&self, velocity: usize) -> Option<usize> {
        let table = self.velocity_joints.get_or_init(|| {
            let mut owner = vec![None; self.nv];
            for (k, joint) in self.joints.iter().enumerate() {
                let velocities = joint.v_offset..joint.v_offset + joint.nv();
                owner[velocities].iter_mut().for_each(|o| *o = Some(k));
            }
            owner
        });
        table.get(velocity).copied().flatten()
    }

    /// The bodies from `body` up to (and excluding) earth; body b is reached by joint b − 1.
    pub fn path_to_earth(&self, body: usize) -> impl Iterator<Item = usize> + '_ {
        let below_earth = |b: usize| (b != 0).then_some(b);
        std::iter::successors(below_earth(body), move |&b| {
            below_earth(self.joints[b - 1].parent)
        })
    }

    pub fn joint_of(&self, join: JoinId) -> Option<usize> {
        self.joints.iter().position(|j| j.chain.join == join)
    }

    /// Where the declared coordinates of a join (tree or complementary) start.
    pub fn declared_offset(&self, join: JoinId) -> Option<usize> {
        match self.joint_of(join) {
            Some(joint) => Some(self.declared_offsets[joint]),
            None => self.loops.iter().find(|l| l.join == join).map(|l| l.offset),
        }
    }

    pub fn has_loops(&self) -> bool {
        !self.loops.is_empty()
    }

    /// Where the angles recovered from quaternions (of spherical and free joints) lie among the
    /// declared coordinates: the last three of each such joint's.
    pub fn recovered_angles(&self) -> impl Iterator<Item = usize> + '_ {
        let joints = self.joints.iter().zip(&self.declared_offsets);
        joints
            .filter(|(joint, _)| joint.kind != JointType::Chain)
            .flat_map(|(joint, &offset)| {
                let end = offset + joint.chain.coordinate_count();
                end - 3..end
            })
    }

    /// Whether contacts (`rolling`, `sliding`) constrain the tree's motion.
    pub fn has_contacts(&self) -> bool {
        !self.contacts.is_empty()
    }

    /// Length of the position part of the state: the tree's, then the complementary links'.
    pub fn positions(&self) -> usize {
        self.nq + self.nc
    }

    /// Length of the velocity part of the state.
    pub fn velocities(&self) -> usize {
        self.nv + self.nc
    }

    /// A state velocity for people: `crank.q` for a coordinate, `ball.ω_x` for a quaternion
    /// joint's angular velocity (body axes), `free.v_x` for its linear one.
    pub fn velocity_name(&self, index: usize) -> String {
        if index >= self.nv {
            let names: Vec<String> = self
                .loops
                .iter()
                .flat_map(|l| {
                    l.coordinate_names
                        .iter()
                        .map(move |c| format!("{}.{c}", l.name))
                })
                .collect();
            return names.get(index - self.nv).cloned().unwrap_or_default();
        }
        let Some(joint) = self.joint_of_velocity(index) else {
            return String::new();
        };
        let k = index - joint.v_offset;
        match joint.kind {
            JointType::Chain => format!("{}.{}", joint.chain.name, joint.chain.coordinate_names[k]),
            _ => format!(
                "{}.{}",
                joint.chain.name,
                ["ω_x", "ω_y", "ω_z", "v_x", "v_y", "v_z"][k]
            ),
        }
    }

    /// Where complementary link `k`'s coordinates start in the complementary block.
    pub fn loop_offset(&self, k: usize) -> usize {
        self.loops[k].offset - (self.declared_count - self.nc)
    }
}

/// The error of a value that must be a constant number and is not; `at` is the declaration it
/// belongs to, where one is known.
fn missing(mechanism: &Mechanism, error: EvalError, what: &str, at: Option<Span>) -> Diagnostic {
    let located = |diagnostic: Diagnostic, label: &str| match at {
        Some(span) => diagnostic.primary(span, label.to_string()),
        None => diagnostic,
    };
    match error {
        EvalError::Missing(id) => {
            let name = crate::kinematics::eval::unknown_label(mechanism, id);
            Diagnostic::error("E0806", format!("{what} needs a value for {name}"))
                .primary(mechanism.unknowns[id.0 as usize].span, "no value given")
                .help("give it a number in the program (`mass = 2`), or a value with `--set`")
        }
        EvalError::NotGeometric(detail) => located(
            Diagnostic::error("E0807", format!("{what} cannot depend on {detail}"))
                .help("it is fixed for the whole motion: write it with numbers and unknowns only"),
            "declared here",
        ),
        EvalError::NotFinite => located(
            Diagnostic::error("E0807", format!("{what} is not a finite number")),
            "declared here",
        ),
    }
}

fn constant_vector(v: &Vector, unknowns: &UnknownValues) -> Result<Vector3<f64>, EvalError> {
    Ok(Vector3::new(
        eval(&v[0], unknowns)?,
        eval(&v[1], unknowns)?,
        eval(&v[2], unknowns)?,
    ))
}

fn constant(s: &Scalar, unknowns: &UnknownValues) -> Result<f64, EvalError> {
    eval(s, unknowns)
}

/// Builds the dynamic model: the tree of principal links, and the complementary links as
/// constraints.
pub fn build(mechanism: &Mechanism, kinematics: &KinematicModel) -> Result<Model, Vec<Diagnostic>> {
    build_with(mechanism, kinematics, true)
}

/// `build`, with `quaternions` false keeping every joint a plain chain in its declared
/// coordinates (velocities are the coordinates' rates): the form of the symbolic equations,
/// for comparing the two.
pub fn build_with(
    mechanism: &Mechanism,
    kinematics: &KinematicModel,
    quaternions: bool,
) -> Result<Model, Vec<Diagnostic>> {
    build_parts(mechanism, kinematics, quaternions, true)
}

/// The model of a study that asks only for kinematics (`lsdc kinematics`, `lsdc workspace`):
/// the joints, loops, stops, couplings, contacts and drives, without the dynamics. Every body
/// is massless and no effort, rotor, friction or state is built, so that neither a mass nor
/// an effort's value is needed and none is evaluated; `Model::dynamics` says so.
pub fn build_kinematic(
    mechanism: &Mechanism,
    kinematics: &KinematicModel,
) -> Result<Model, Vec<Diagnostic>> {
    build_parts(mechanism, kinematics, true, false)
}

/// `build_with`, with the bodies' inertias and the efforts only `with_dynamics`.
fn build_parts(
    mechanism: &Mechanism,
    kinematics: &KinematicModel,
    quaternions: bool,
    with_dynamics: bool,
) -> Result<Model, Vec<Diagnostic>> {
    let unknowns = &kinematics.unknowns;
    let topology = &kinematics.topology;
    let mut errors = Vec::new();
    let mut joints = Vec::new();
    let (mut nq, mut nv) = (0, 0);
    let mut declared_offsets = Vec::new();
    let mut declared = 0;
    for (link, chain) in topology.principal.iter().zip(kinematics.principal()) {
        let (on_parent, on_child) = if link.first_on_parent {
            (chain.first, chain.second)
        } else {
            (chain.second, chain.first)
        };
        let mut joint = Joint {
            chain: chain.clone(),
            kind: if quaternions {
                classify(chain)
            } else {
                JointType::Chain
            },
            parent: link.parent,
            child: link.child,
            first_on_parent: link.first_on_parent,
            on_parent,
            on_child,
            q_offset: nq,
            v_offset: nv,
            kernel: Kernel::General,
            dynamic_parent: link.parent,
        };
        joint.kernel = kernel(&joint);
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
        if !with_dynamics {
            bodies.push(BodyInertia::massless());
            body_names.push(name);
            continue;
        }
        match body_inertia(mechanism, id, unknowns) {
            Ok(b) => {
                let body = mechanism.body(id);
                let moments = constant_vector(body.inertia.value(), unknowns)
                    .ok()
                    .map(|v| [v.x, v.y, v.z]);
                if let Some(problem) = inertia_problem(Some(b.mass), moments) {
                    // Written values are checked where they are written: these came from
                    // `given` or `--set`.
                    errors.push(
                        Diagnostic::error(
                            "E0816",
                            format!(
                                "`{name}`: {} (a value given to an unknown)",
                                problem.message
                            ),
                        )
                        .primary(body.span, "the body")
                        .help(problem.help),
                    );
                }
                bodies.push(b);
            }
            Err(e) => errors.push(missing(
                mechanism,
                e,
                &format!("the inertia of `{name}`"),
                Some(mechanism.body(id).span),
            )),
        }
        body_names.push(name);
    }
    let applied = match with_dynamics {
        true => applied_efforts(mechanism, kinematics, &mut errors),
        false => Vec::new(),
    };
    let (gravity, applied) = gravity_field(applied, &bodies, unknowns);
    let loops = kinematics.complementary().to_vec();
    let loop_balls = loops
        .iter()
        .map(|l| match classify(l) {
            JointType::Spherical { axes } => Some(axes),
            _ => None,
        })
        .collect();
    let nc: usize = loops.iter().map(JointModel::coordinate_count).sum();
    let contacts = contact_models(mechanism, kinematics, &mut errors);
    let stops = stops::build(mechanism, &joints, &loops, unknowns, &mut errors);
    let mimics = mimics::build(mechanism, &joints, &loops, unknowns, &mut errors);
    // The dynamic elements of the links, the program's states and the frames the efforts
    // read: none in a kinematic model, whose values need not be known.
    let (link_efforts, rotors, mut frictions, states) = match with_dynamics {
        true => {
            let state_value = |e, what: &str, at| missing(mechanism, e, what, Some(at));
            (
                link_efforts(mechanism, &joints, &loops),
                rotors::build(mechanism, &joints, &loops, unknowns, &mut errors),
                friction::build(mechanism, &joints, &loops, unknowns, &mut errors),
                states::build(mechanism, unknowns, &state_value, &mut errors),
            )
        }
        false => (Vec::new(), Vec::new(), Vec::new(), Vec::new()),
    };
    let drives = drives::build(mechanism, kinematics, &joints, &mut errors);
    for friction in &mut frictions {
        friction.driven = drives.iter().any(|d| d.velocity == friction.velocity);
    }
    let position_drives = match position_drives::resolve(mechanism, kinematics) {
        Ok(resolved) => resolved,
        Err(refused) => {
            errors.extend(refused);
            Vec::new()
        }
    };
    let read = EffortsRead {
        applied: &applied,
        links: &link_efforts,
        states: &states,
    };
    let effort_frames = match with_dynamics {
        true => effort_frames(mechanism, kinematics, read, &mut errors),
        false => Vec::new(),
    };
    let link_potentials = joints
        .iter()
        .map(|j| &j.chain)
        .chain(&loops)
        .enumerate()
        .filter(|_| with_dynamics)
        .filter_map(|(k, chain)| {
            mechanism
                .link(mechanism.join(chain.join).link)
                .potential
                .clone()
                .map(|value| LinkPotential {
                    joint: k,
                    value,
                    root: 0,
                })
        })
        .collect();
    if !errors.is_empty() {
        return Err(errors);
    }
    let rotor_carriers: Vec<usize> = rotors.iter().map(|r| r.carrier).collect();
    let merged = welds::merge(
        &mut joints,
        &bodies,
        &applied,
        &link_efforts,
        &rotor_carriers,
        !loops.is_empty() || !contacts.is_empty(),
    );
    refuse_rotors_on_welds(mechanism, &joints, &merged.dynamic_joints, &rotors)?;
    let mut model = Model {
        branches: std::sync::OnceLock::new(),
        velocity_joints: std::sync::OnceLock::new(),
        dynamic_joints: merged.dynamic_joints,
        dynamic_bodies: merged.dynamic_bodies,
        anchor_offsets: merged.anchor_offsets,
        joints,
        bodies,
        body_names,
        body_numbers: topology.number_of.clone(),
        nq,
        nv,
        applied,
        gravity,
        link_efforts,
        link_potentials,
        effort_frames,
        unknowns: unknowns.clone(),
        declared_offsets,
        declared_count: declared + nc,
        loops,
        nc,
        loop_balls,
        contacts,
        stops,
        rotors,
        mimics,
        frictions,
        drives,
        position_drives,
        states,
        effort_inputs: match with_dynamics {
            true => mechanism.declared_inputs(),
            false => Vec::new(),
        },
        effort_tape: Err(EvalError::NotGeometric("efforts not compiled")),
        applied_groups: Vec::new(),
        declared_read: Vec::new(),
        actuation: None,
        dynamics: with_dynamics,
    };
    if with_dynamics {
        model.compile_efforts();
        model.compile_actuators(mechanism)?;
    }
    Ok(model)
}

/// A rotor carried by a body merged into another by welds (E0453): the algorithms see the merged
/// body only, and the rotor is not moved there.
fn refuse_rotors_on_welds(
    mechanism: &Mechanism,
    joints: &[Joint],
    dynamic_joints: &[usize],
    rotors: &[Rotor],
) -> Result<(), Vec<Diagnostic>> {
    let visited =
        |body: usize| body == 0 || dynamic_joints.iter().any(|&k| joints[k].child == body);
    let errors: Vec<Diagnostic> = rotors
        .iter()
        .filter(|r| !visited(r.carrier))
        .map(|r| {
            let join = mechanism.join(joints[r.joint].chain.join);
            Diagnostic::error(
                "E0453",
                format!(
                    "the rotor of `{}` is carried by a welded body",
                    joints[r.joint].chain.name
                ),
            )
            .primary(join.span, "its first frame's body is welded to another")
            .help("join the rotor's link to the body the weld attaches to")
        })
        .collect();
    match errors.is_empty() {
        true => Ok(()),
        false => Err(errors),
    }
}

impl Model {
    /// Compiles the actuators' laws and the states' rates that read the model (`actuators`),
    /// and marks the joints they read as read by the efforts.
    fn compile_actuators(&mut self, mechanism: &Mechanism) -> Result<(), Vec<Diagnostic>> {
        let mut errors = Vec::new();
        let compiling = self.actuators_compiling(mechanism);
        let actuation = actuators::build(&compiling, &mut errors);
        if !errors.is_empty() {
            return Err(errors);
        }
        if let Some(actuation) = &actuation {
            for &(state, root) in &actuation.state_roots {
                self.states[state].rate_root = root;
            }
            for (k, joint) in self.joints.iter().enumerate() {
                let offset = self.declared_offsets[k];
                let range = offset..offset + joint.chain.coordinate_count();
                if let Some(read) = self.declared_read.get_mut(k) {
                    *read |= actuation.tape.reads_declared(range);
                }
            }
        }
        self.actuation = actuation;
        Ok(())
    }

    /// What the actuators' laws, and outputs that read the model, are compiled from.
    pub fn actuators_compiling<'a>(&'a self, mechanism: &'a Mechanism) -> actuators::Compiling<'a> {
        actuators::Compiling {
            mechanism,
            joints: &self.joints,
            declared_offsets: &self.declared_offsets,
            drives: &self.drives,
            unknowns: &self.unknowns,
            frames: &self.effort_frames,
            states: &self.states,
            constrained: !self.contacts.is_empty() || !self.mimics.is_empty(),
        }
    }

    /// Lowers every effort into one tape and records where each effort's values lie in it
    /// (done when the model is built; again after changing its efforts or joints).
    pub fn compile_efforts(&mut self) {
        let declared_offset = |join| self.declared_offset(join);
        let mut builder = TapeBuilder::new(&self.unknowns, &self.effort_frames, &declared_offset);
        let mut lower = || -> Result<_, EvalError> {
            let mut potentials_applied = Vec::new();
            // (group, its value, its non-conservative part), both lowered but not yet roots.
            let mut groups: Vec<(AppliedGroup, [ExprId; 3], Option<[ExprId; 3]>)> = Vec::new();
            for effort in &self.applied {
                let lowered = builder.lower_vector(&effort.value, Link(None))?;
                let potential = match &effort.potential {
                    Some(p) => Some(builder.potential(p, Link(None))?),
                    None => None,
                };
                potentials_applied.push(potential);
                let alike = |g: &AppliedGroup| {
                    g.kind == effort.kind
                        && g.body == effort.body
                        && g.point == effort.point
                        && g.basis == effort.basis
                };
                let nonconservative = (!effort.conservative).then_some(lowered);
                match groups.iter_mut().find(|(g, _, _)| alike(g)) {
                    Some((_, sum, nc)) => {
                        *sum = builder.add_vectors(*sum, lowered);
                        *nc = match (*nc, nonconservative) {
                            (Some(a), Some(b)) => Some(builder.add_vectors(a, b)),
                            (a, b) => a.or(b),
                        };
                    }
                    None => groups.push((
                        AppliedGroup {
                            kind: effort.kind,
                            body: effort.body,
                            point: effort.point,
                            basis: effort.basis,
                            value_roots: [0; 3],
                            nonconservative_roots: None,
                        },
                        lowered,
                        nonconservative,
                    )),
                }
            }
            let groups: Vec<AppliedGroup> = groups
                .into_iter()
                .map(|(mut group, sum, nonconservative)| {
                    group.value_roots = builder.vector_root(sum);
                    group.nonconservative_roots = nonconservative.map(|nc| builder.vector_root(nc));
                    group
                })
                .collect();
            let mut links = Vec::new();
            for effort in &self.link_efforts {
                let offset = self.declared_offset(self.chain(effort.joint).join);
                links.push(builder.vector(&effort.value, Link(offset))?);
            }
            let mut potentials = Vec::new();
            for potential in &self.link_potentials {
                let offset = self.declared_offset(self.chain(potential.joint).join);
                potentials.push(builder.potential(&potential.value, Link(offset))?);
            }
            // A rate that reads the model is the actuators' (`actuators::build`).
            let rates = (self.states.iter())
                .map(|state| match state.reads_model {
                    true => Ok(None),
                    false => builder.scalar(&state.rate, Link(None)).map(Some),
                })
                .collect::<Result<Vec<_>, _>>()?;
            Ok((potentials_applied, groups, links, potentials, rates))
        };
        let lowered = lower();
        let tape = builder.build();
        let (potentials_applied, groups, links, potentials, rates) = match lowered {
            Ok(roots) => roots,
            Err(e) => {
                self.effort_tape = Err(e);
                return;
            }
        };
        for (effort, potential) in self.applied.iter_mut().zip(potentials_applied) {
            effort.potential_root = potential;
        }
        self.applied_groups = groups;
        for (effort, value) in self.link_efforts.iter_mut().zip(links) {
            effort.value_roots = value;
        }
        for (potential, root) in self.link_potentials.iter_mut().zip(potentials) {
            potential.root = root;
        }
        for (state, root) in self.states.iter_mut().zip(rates) {
            if let Some(root) = root {
                state.rate_root = root;
            }
        }
        self.declared_read = self.joints_read(&tape);
        self.effort_tape = Ok(tape);
    }

    /// Per tree joint, whether `tape` or a link effort or potential reads its declared state.
    fn joints_read(&self, tape: &EffortTape) -> Vec<bool> {
        let mut read: Vec<bool> = self
            .joints
            .iter()
            .zip(&self.declared_offsets)
            .map(|(joint, &offset)| {
                tape.reads_declared(offset..offset + joint.chain.coordinate_count())
            })
            .collect();
        let on_links = self.link_efforts.iter().map(|e| e.joint);
        for joint in on_links.chain(self.link_potentials.iter().map(|p| p.joint)) {
            if let Some(flag) = read.get_mut(joint) {
                *flag = true;
            }
        }
        read
    }

    /// The chain of a joint of the tree (`index < joints.len()`) or of a complementary link.
    pub fn chain(&self, index: usize) -> &JointModel {
        match self.joints.get(index) {
            Some(joint) => &joint.chain,
            None => &self.loops[index - self.joints.len()],
        }
    }
}

fn body_inertia(
    mechanism: &Mechanism,
    id: crate::elab::value::BodyId,
    unknowns: &UnknownValues,
) -> Result<BodyInertia, EvalError> {
    let body = mechanism.body(id);
    let mass = constant(body.mass.value(), unknowns)?;
    let moments = constant_vector(body.inertia.value(), unknowns)?;
    if mass == 0.0 && moments == Vector3::zeros() {
        return Ok(BodyInertia {
            mass,
            com: Vector3::zeros(),
            inertia: Inertia::zeros(),
            rigid: RigidInertia::zeros(),
            massless: true,
        });
    }
    let frame: Pose = constant_pose(body.iframe.value(), unknowns)?;
    let rotation = frame.rotation.to_rotation_matrix();
    let central =
        rotation.matrix() * Matrix3::from_diagonal(&moments) * rotation.matrix().transpose();
    let com = frame.translation.vector;
    let inertia = spatial::inertia(mass, &com, &central);
    Ok(BodyInertia {
        mass,
        com,
        inertia,
        rigid: RigidInertia::from_matrix(&inertia),
        massless: false,
    })
}

fn applied_efforts(
    mechanism: &Mechanism,
    kinematics: &KinematicModel,
    errors: &mut Vec<Diagnostic>,
) -> Vec<AppliedEffort> {
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
                errors.push(missing(
                    mechanism,
                    e,
                    "the point of application of an effort",
                    Some(application.span),
                ));
                continue;
            }
        };
        let point = if effort.kind == EffortKind::Torque {
            Vector3::zeros()
        } else {
            point
        };
        let basis = match effort.basis {
            BodyRef::Earth => 0,
            BodyRef::Body(id) => match topology.number_of.get(&id) {
                Some(&n) => n,
                None => {
                    errors.push(
                        Diagnostic::error(
                            "E0809",
                            "an effort is written in the basis of a body outside the mechanism",
                        )
                        .primary(effort.span, "this effort"),
                    );
                    continue;
                }
            },
        };
        let potential = effort.potential.clone();
        let mut applied_effort = AppliedEffort {
            kind: effort.kind,
            body,
            point,
            value: effort.value.value().clone(),
            basis,
            potential,
            span: application.span,
            conservative: false,
            potential_root: None,
        };
        applied_effort.conservative = applied_effort.potential.is_some()
            || constant_fixed_force(&applied_effort, &kinematics.unknowns).is_some();
        applied.push(applied_effort);
    }
    applied
}

/// The frames the efforts' values and potentials use, placed on their bodies.
/// What the efforts' tape evaluates besides the links' potentials: the applied efforts, the
/// link efforts and the states' rates.
#[derive(Clone, Copy)]
struct EffortsRead<'a> {
    applied: &'a [AppliedEffort],
    links: &'a [LinkEffort],
    states: &'a [StateModel],
}

fn effort_frames(
    mechanism: &Mechanism,
    kinematics: &KinematicModel,
    read: EffortsRead<'_>,
    errors: &mut Vec<Diagnostic>,
) -> Vec<EffortFrame> {
    let mut frames = Vec::new();
    let expressions = (read.applied.iter())
        .flat_map(|e| e.value.iter().chain(&e.potential))
        .chain(read.links.iter().flat_map(|e| e.value.iter()))
        .chain(mechanism.links.iter().flat_map(|l| &l.potential))
        .chain(read.states.iter().map(|s| &s.rate))
        .chain(mechanism.actuators.iter().map(|a| &a.law));
    for s in expressions {
        s.frames_used(&mut frames);
    }
    let mut placed = Vec::new();
    for frame in frames {
        let body = match frame.body {
            BodyRef::Earth => 0,
            BodyRef::Body(id) => match kinematics.topology.number_of.get(&id) {
                Some(&n) => n,
                None => {
                    errors.push(Diagnostic::error(
                        "E0809",
                        "an effort uses the state of a frame on a body outside the mechanism",
                    ));
                    continue;
                }
            },
        };
        match constant_pose(&frame.displacement, &kinematics.unknowns) {
            Ok(offset) => placed.push(EffortFrame {
                frame,
                body,
                offset,
            }),
            Err(e) => errors.push(missing(mechanism, e, "a frame an effort uses", None)),
        }
    }
    placed
}

/// The value of a constant force written in the fixed basis, or `None`.
pub fn constant_fixed_force(e: &AppliedEffort, unknowns: &UnknownValues) -> Option<Vector3<f64>> {
    (e.kind == EffortKind::Force && e.basis == 0)
        .then(|| constant_vector(&e.value, unknowns).ok())
        .flatten()
}

/// The velocities of each joint and its ancestors (through dynamic parents).
fn branch_velocities(joints: &[Joint]) -> Vec<Vec<usize>> {
    (0..joints.len())
        .map(|k| {
            let mut rows = Vec::new();
            let mut j = k;
            loop {
                rows.extend(joints[j].v_offset..joints[j].v_offset + joints[j].nv());
                match joints[j].dynamic_parent {
                    0 => break,
                    parent => j = parent - 1,
                }
            }
            rows
        })
        .collect()
}

/// Splits the weights off the applied efforts when every body with mass carries exactly one
/// constant force in the fixed basis, at its centre of mass, equal to its mass times one common
/// vector g: that is a uniform field g. Otherwise the efforts stay as they are (g = 0).
fn gravity_field(
    applied: Vec<AppliedEffort>,
    bodies: &[BodyInertia],
    unknowns: &UnknownValues,
) -> (Vector3<f64>, Vec<AppliedEffort>) {
    let constant_force = |e: &AppliedEffort| constant_fixed_force(e, unknowns);
    let mut field: Option<Vector3<f64>> = None;
    let mut is_weight = vec![false; applied.len()];
    for (k, body) in bodies
        .iter()
        .enumerate()
        .filter(|(_, b)| !b.massless && b.mass != 0.0)
    {
        let at_centre = |e: &AppliedEffort| {
            e.body == k + 1 && (e.point - body.com).norm() <= 1e-12 * (1.0 + body.com.norm())
        };
        let weights: Vec<usize> = (0..applied.len())
            .filter(|&i| at_centre(&applied[i]) && constant_force(&applied[i]).is_some())
            .collect();
        let [only] = weights.as_slice() else {
            return (Vector3::zeros(), applied);
        };
        let g = constant_force(&applied[*only]).unwrap_or_default() / body.mass;
        match field {
            Some(f) if (f - g).norm() > 1e-14 * f.norm().max(1e-300) => {
                return (Vector3::zeros(), applied)
            }
            _ => field = Some(g),
        }
        is_weight[*only] = true;
    }
    let Some(g) = field else {
        return (Vector3::zeros(), applied);
    };
    let rest = applied
        .into_iter()
        .zip(is_weight)
        .filter(|(_, w)| !w)
        .map(|(e, _)| e)
        .collect();
    (g, rest)
}

/// The efforts written in the links; `joint` indexes the tree's joints, then the loops'.
fn link_efforts(mechanism: &Mechanism, joints: &[Joint], loops: &[JointModel]) -> Vec<LinkEffort> {
    let mut efforts = Vec::new();
    let chains = joints.iter().map(|j| &j.chain).chain(loops);
    for (index, chain) in chains.enumerate() {
        let link = mechanism.link(mechanism.join(chain.join).link);
        for (kind, list) in [
            (EffortKind::Force, &link.forces),
            (EffortKind::Torque, &link.torques),
        ] {
            for (step, value) in list {
                let conservative = link.potential.is_some();
                efforts.push(LinkEffort {
                    joint: index,
                    kind,
                    step: *step,
                    value: value.clone(),
                    span: mechanism.join(chain.join).span,
                    conservative,
                    value_roots: [0; 3],
                });
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
        let mut q = Vec::new();
        let v = self.split_state_into(y, &mut q);
        (q, v)
    }

    /// `split_state` writing the positions into `q` (reusing its storage).
    pub fn split_state_into<'y>(&self, y: &'y [f64], q: &mut Vec<f64>) -> &'y [f64] {
        let (positions, v) = y.split_at(self.positions());
        q.clear();
        q.extend_from_slice(positions);
        // A quaternion joint has one position more than velocities: none when the counts agree.
        if self.nq != self.nv {
            for joint in &self.joints {
                joint.normalize(&mut q[joint.q_offset..joint.q_offset + joint.nq()]);
            }
        }
        v
    }

    /// dq/dt at positions `q` (quaternions of unit length: `split_state_into`) and velocities
    /// `v`, into `dq` (state lengths): each joint's `position_rate`, the complementary links'
    /// coordinates by their rates.
    pub fn position_rates(&self, q: &[f64], v: &[f64], dq: &mut [f64]) {
        // Without quaternion joints (as many positions as velocities) every coordinate's rate
        // is its velocity: one copy instead of one per joint (an RK4 step of UR5 spent 6 % of
        // its instructions in those).
        if self.nq == self.nv {
            dq.copy_from_slice(v);
            return;
        }
        for joint in &self.joints {
            let range = joint.q_offset..joint.q_offset + joint.nq();
            joint.position_rate(
                &q[range.clone()],
                &v[joint.v_offset..joint.v_offset + joint.nv()],
                &mut dq[range],
            );
        }
        dq[self.nq..].copy_from_slice(&v[self.nv..]);
    }

    /// The position of state velocity `velocity` when it is the rate of a coordinate (a chain's,
    /// or a complementary link's); `None` for a spherical or free joint's angular or linear
    /// velocity, whose positions are a quaternion and a point.
    pub fn position_of(&self, velocity: usize) -> Option<usize> {
        if velocity >= self.nv {
            return Some(self.nq + velocity - self.nv);
        }
        let joint = self.joint_of_velocity(velocity)?;
        (!joint.is_quaternion()).then(|| joint.q_offset + velocity - joint.v_offset)
    }

    /// Moves the positions `q` (state length) by the small velocity-space step `dv`: the joints'
    /// coordinates by their rates, quaternions along the rotation and back to unit length.
    pub fn retract(&self, q: &mut [f64], dv: &[f64]) {
        for joint in &self.joints {
            let (qs, vs) = (
                joint.q_offset..joint.q_offset + joint.nq(),
                joint.v_offset..joint.v_offset + joint.nv(),
            );
            // Seven positions at most but for long dof chains: on the stack then.
            let (mut stack, mut heap) = ([0.0; 7], Vec::new());
            let rate = if joint.nq() <= 7 {
                &mut stack[..joint.nq()]
            } else {
                heap.resize(joint.nq(), 0.0);
                &mut heap[..]
            };
            joint.position_rate(&q[qs.clone()], &dv[vs], rate);
            q[qs.clone()]
                .iter_mut()
                .zip(rate.iter())
                .for_each(|(x, r)| *x += r);
            joint.normalize(&mut q[qs]);
        }
        for i in 0..self.nc {
            q[self.nq + i] += dv[self.nv + i];
        }
    }

    /// Positions and velocities from the declared coordinates and rates of every join (in the
    /// joints' order).
    pub fn state_from_declared(
        &self,
        coordinates: &[f64],
        rates: &[f64],
    ) -> Result<(Vec<f64>, Vec<f64>), EvalError> {
        let mut q = vec![0.0; self.positions()];
        let mut v = vec![0.0; self.velocities()];
        let tree = self.declared_count - self.nc;
        q[self.nq..].copy_from_slice(&coordinates[tree..]);
        v[self.nv..].copy_from_slice(&rates[tree..]);
        for (joint, &offset) in self.joints.iter().zip(&self.declared_offsets) {
            let n = joint.chain.coordinate_count();
            let (jq, jv) = joint.state_from_declared(
                &coordinates[offset..offset + n],
                &rates[offset..offset + n],
            )?;
            q[joint.q_offset..joint.q_offset + joint.nq()].copy_from_slice(&jq);
            v[joint.v_offset..joint.v_offset + joint.nv()].copy_from_slice(&jv);
        }
        Ok((q, v))
    }

    /// Declared coordinates and rates at (q, v) at time t; `reference` keeps recovered angles
    /// continuous (see `dynamics::angles::AngleReference`, the library's own).
    pub fn declared(
        &self,
        (t, q, v): (f64, &[f64], &[f64]),
        reference: &AngleReference,
    ) -> Result<(Vec<f64>, Vec<f64>), EvalError> {
        let mut declared = DeclaredState::default();
        self.declared_into((t, q, v), reference, &mut declared, Recovered::Every)?;
        Ok((declared.coordinates, declared.rates))
    }

    /// `declared` writing into `declared` (reusing its storage: nothing is allocated once it
    /// has held this model's), for the joints `which` selects; the others' declared coordinates
    /// and rates are left as they were.
    pub fn declared_into(
        &self,
        (t, q, v): (f64, &[f64], &[f64]),
        reference: &AngleReference,
        declared: &mut DeclaredState,
        which: Recovered,
    ) -> Result<(), EvalError> {
        let wanted = |joint: usize| match which {
            Recovered::Every => true,
            Recovered::ReadByEfforts => self.declared_read.get(joint).copied().unwrap_or(true),
        };
        let DeclaredState {
            coordinates,
            rates,
            chain,
        } = declared;
        coordinates.resize(self.declared_count, 0.0);
        rates.resize(self.declared_count, 0.0);
        let joints = self.joints.iter().zip(&self.declared_offsets).enumerate();
        for (_, (joint, &offset)) in joints.filter(|(index, _)| wanted(*index)) {
            let n = joint.chain.coordinate_count();
            if joint.kind == JointType::Chain {
                // Its state is its declared coordinates and rates.
                coordinates[offset..offset + n].copy_from_slice(&q[joint.q_offset..][..n]);
                rates[offset..offset + n].copy_from_slice(&v[joint.v_offset..][..n]);
                continue;
            }
            let reference = JointReference {
                coordinates: &reference.coordinates[offset..offset + n],
                rates: &reference.rates[offset..offset + n],
                elapsed: t - reference.time,
            };
            joint.declared_into(
                &q[joint.q_offset..joint.q_offset + joint.nq()],
                &v[joint.v_offset..joint.v_offset + joint.nv()],
                reference,
                (
                    &mut coordinates[offset..offset + n],
                    &mut rates[offset..offset + n],
                ),
                chain,
            )?;
        }
        let tree = self.declared_count - self.nc;
        coordinates[tree..].copy_from_slice(&q[self.nq..self.nq + self.nc]);
        rates[tree..].copy_from_slice(&v[self.nv..self.nv + self.nc]);
        Ok(())
    }
}

/// Which joints' declared coordinates `Model::declared_into` recovers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Recovered {
    Every,
    /// Those the efforts read (`Model::declared_read`): recovering angles from quaternions is
    /// most of an evaluation's cost on mechanisms of ball joints that no effort reads.
    ReadByEfforts,
}

/// Declared coordinates and rates of every join at a state (`Model::declared_into`), with the
/// scratch their recovery from quaternions uses.
#[derive(Clone, Debug, Default)]
pub struct DeclaredState {
    pub coordinates: Vec<f64>,
    pub rates: Vec<f64>,
    chain: ChainMotion,
}
