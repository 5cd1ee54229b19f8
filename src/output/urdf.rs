//! Writing a tree mechanism as URDF (`lsdc export-urdf`, described in docs/commands.md).
//!
//! Every body becomes a link named after it, and the earth the root link `earth`. URDF puts a
//! link's frame where the joint that carries it moves it, so a body's link frame is its join's
//! frame on the body, moved back by any constant displacement its dof chain ends with; the
//! body's inertia is re-expressed in that frame. A join whose dof chain moves one coordinate
//! becomes a `continuous` or `prismatic` joint, a weld a `fixed` joint, a free joint a
//! `floating` joint, and a chain of several coordinates one joint per coordinate through
//! massless links, all named `join.coordinate`.

use std::fmt::{self, Write};

use nalgebra::{Matrix3, Point3, UnitQuaternion, Vector3};
use urdf_rs::{
    Axis, Inertia, Inertial, Joint as UrdfJoint, JointLimit, JointType as UrdfType, Link, LinkName,
    Mass, Robot, Vec3,
};

use crate::diag::number::shortest as number;
use crate::dynamics::joint::{Joint, JointType};
use crate::dynamics::model::{BodyInertia, Model};
use crate::elab::value::SExpr;
use crate::kinematics::eval::{eval, EvalError, UnknownValues};
use crate::kinematics::model::{JointModel, Step};
use crate::output::xml::escape;
use crate::spatial::{self, Pose};
use crate::spatial::{rotation, translation};

/// URDF has no unlimited prismatic joint, and its readers require `<limit>` with an effort and
/// a velocity on one: this bound, SDFormat's own for "no limit", stands for none.
pub const NO_LIMIT: f64 = 1e16;

/// Why a mechanism cannot be written as URDF.
#[derive(Clone, Debug, PartialEq)]
pub enum ExportError {
    /// The mechanism has loops: the names of the joins of its complementary links.
    Loops(Vec<String>),
    /// A step of a join's dof chain that URDF joints cannot express; `step` counts the chain's
    /// elementary translations and rotations from 1.
    Step {
        join: String,
        step: usize,
        reason: String,
    },
    /// Two links, or two joints, would have the same name.
    DuplicateName { element: &'static str, name: String },
}

impl ExportError {
    /// The message, calling the mechanism `mechanism` (its file, in the command line).
    pub fn message(&self, mechanism: &str) -> String {
        match self {
            ExportError::Loops(links) => {
                let names = links.join(", ");
                match links.len() {
                    1 => format!("URDF describes trees: {mechanism} has complementary link {names} (it closes a loop)"),
                    _ => format!("URDF describes trees: {mechanism} has complementary links {names} (they close loops)"),
                }
            }
            ExportError::Step { join, step, reason } => {
                format!("join `{join}` cannot be written as URDF joints: step {step} of its dof chain {reason}")
            }
            ExportError::DuplicateName { element, name } => {
                format!("URDF names must be unique, and {mechanism} would have two {element}s named `{name}`")
            }
        }
    }
}

impl fmt::Display for ExportError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.message("the mechanism"))
    }
}

impl std::error::Error for ExportError {}

/// The URDF text of `model`'s tree, as a robot named `robot_name`.
pub fn export_urdf(model: &Model, robot_name: &str) -> Result<String, ExportError> {
    robot(model, robot_name).map(|robot| to_xml(&robot))
}

/// What a URDF cannot carry of `model`: its gravity, applied efforts and link efforts, named in
/// a sentence for a warning; `None` when it has none.
pub fn dropped_efforts(model: &Model) -> Option<String> {
    let plural = |n: usize| if n == 1 { "" } else { "s" };
    let counted = [
        (model.applied.len(), "applied effort"),
        (model.link_efforts.len(), "link effort"),
    ];
    let mut parts: Vec<String> = (model.gravity != nalgebra::Vector3::zeros())
        .then(|| "gravity".to_string())
        .into_iter()
        .collect();
    parts.extend(
        (counted.iter().filter(|(n, _)| *n > 0))
            .map(|(n, what)| format!("{n} {what}{}", plural(*n))),
    );
    if parts.is_empty() {
        return None;
    }
    Some(format!(
        "the URDF leaves out the mechanism's efforts ({}): URDF describes bodies and joints only",
        parts.join(", ")
    ))
}

/// The URDF robot of `model`'s tree: links in body order after `earth`, the intermediate links
/// of each join after its body; joints in join order.
pub fn robot(model: &Model, robot_name: &str) -> Result<Robot, ExportError> {
    let layouts = layouts(model)?;
    let frames = frames_of(model, &layouts);
    let mut links = vec![bare_link("earth".to_string())];
    let mut joints = Vec::new();
    for ((joint, layout), body) in model.joints.iter().zip(&layouts).zip(&model.bodies) {
        let name = &model.body_names[joint.child - 1];
        let parent = if joint.parent == 0 {
            "earth"
        } else {
            &model.body_names[joint.parent - 1]
        };
        let lead = frames[joint.parent].inverse() * joint.on_parent;
        let (chain, intermediate) = urdf_joints(joint, layout, &lead, parent, name);
        links.push(Link {
            inertial: inertial(body, &frames[joint.child]),
            ..bare_link(name.clone())
        });
        links.extend(intermediate.into_iter().map(bare_link));
        joints.extend(chain);
    }
    couple_and_damp(model, &mut joints);
    unique(links.iter().map(|l| &l.name), "link")?;
    unique(joints.iter().map(|j| &j.name), "joint")?;
    Ok(Robot {
        name: robot_name.to_string(),
        links,
        joints,
        materials: Vec::new(),
    })
}

/// Where each body's URDF link frame is in the body's frame, by body number (0 is the earth).
#[cfg(lsdc_internals)]
pub fn link_frames(model: &Model) -> Result<Vec<Pose>, ExportError> {
    Ok(frames_of(model, &layouts(model)?))
}

/// What a join becomes: a floating joint, or a chain of motions with constant displacements
/// between them.
enum Layout {
    /// A free joint: any rigid motion, whatever its coordinates.
    Floating,
    /// M = lead · J1(q) · C1 · J2(q) · C2 ⋯ (M of dynamics::joint: from the join's frame on the
    /// parent to its frame on the child); no motion is a weld, `lead` alone.
    Chain {
        lead: Pose,
        motions: Vec<(Motion, Pose)>,
    },
}

/// A rotation about, or a translation along, a unit axis, by one coordinate.
#[derive(Clone, Copy, Debug)]
struct Motion {
    coordinate: usize,
    rotation: bool,
    axis: Vector3<f64>,
}

/// A step of the chain as URDF sees it.
enum Piece {
    Constant(Pose),
    Moving(Motion),
}

fn layouts(model: &Model) -> Result<Vec<Layout>, ExportError> {
    if model.has_loops() {
        return Err(ExportError::Loops(
            model.loops.iter().map(|l| l.name.clone()).collect(),
        ));
    }
    model
        .joints
        .iter()
        .map(|joint| layout(joint, &model.unknowns))
        .collect()
}

fn layout(joint: &Joint, unknowns: &UnknownValues) -> Result<Layout, ExportError> {
    if let JointType::Free { .. } = joint.kind {
        return Ok(Layout::Floating);
    }
    let mut pieces = pieces(&joint.chain, unknowns)?;
    if !joint.first_on_parent {
        // The child moves with D⁻¹: the steps in reverse order, each undone.
        pieces.reverse();
        for piece in &mut pieces {
            match piece {
                Piece::Constant(pose) => *pose = pose.inverse(),
                Piece::Moving(motion) => motion.axis = -motion.axis,
            }
        }
    }
    let mut lead = Pose::identity();
    let mut motions: Vec<(Motion, Pose)> = Vec::new();
    for piece in pieces {
        match (piece, motions.last_mut()) {
            (Piece::Constant(pose), Some((_, after))) => *after *= pose,
            (Piece::Constant(pose), None) => lead *= pose,
            (Piece::Moving(motion), _) => motions.push((motion, Pose::identity())),
        }
    }
    Ok(Layout::Chain { lead, motions })
}

/// The link frames of the bodies in their frames: the join's frame on the child, moved back by
/// the constant displacement after the last motion, so that the last joint moves the link.
fn frames_of(model: &Model, layouts: &[Layout]) -> Vec<Pose> {
    let mut frames = vec![Pose::identity(); model.body_count() + 1];
    for (joint, layout) in model.joints.iter().zip(layouts) {
        let trailing = match layout {
            Layout::Chain { motions, .. } => motions
                .last()
                .map_or_else(Pose::identity, |(_, after)| *after),
            Layout::Floating => Pose::identity(),
        };
        frames[joint.child] = joint.on_child * trailing.inverse();
    }
    frames
}

/// The URDF joints of a join, and the intermediate links between them; `lead` is the join's
/// frame on the parent in the parent's link frame.
fn urdf_joints(
    joint: &Joint,
    layout: &Layout,
    lead: &Pose,
    parent: &str,
    child: &str,
) -> (Vec<UrdfJoint>, Vec<String>) {
    let chain = &joint.chain;
    let (origin, motions) = match layout {
        Layout::Floating => {
            return (
                vec![urdf_joint(
                    chain.name.clone(),
                    UrdfType::Floating,
                    lead,
                    parent,
                    child,
                )],
                Vec::new(),
            )
        }
        Layout::Chain {
            lead: first,
            motions,
        } => (lead * first, motions),
    };
    if motions.is_empty() {
        return (
            vec![urdf_joint(
                chain.name.clone(),
                UrdfType::Fixed,
                &origin,
                parent,
                child,
            )],
            Vec::new(),
        );
    }
    let names: Vec<String> = match motions.len() {
        1 => vec![chain.name.clone()],
        _ => motions
            .iter()
            .map(|(m, _)| format!("{}.{}", chain.name, chain.coordinate_names[m.coordinate]))
            .collect(),
    };
    let mut joints = Vec::new();
    let mut origin = origin;
    for (k, (motion, after)) in motions.iter().enumerate() {
        let from = if k == 0 { parent } else { &names[k - 1] };
        let to = if k + 1 == motions.len() {
            child
        } else {
            &names[k]
        };
        joints.push(motion_joint(names[k].clone(), motion, &origin, from, to));
        origin = *after;
    }
    let intermediate = names[..names.len() - 1].to_vec();
    (joints, intermediate)
}

fn urdf_joint(
    name: String,
    joint_type: UrdfType,
    origin: &Pose,
    parent: &str,
    child: &str,
) -> UrdfJoint {
    UrdfJoint {
        name,
        joint_type,
        origin: urdf_pose(origin),
        parent: LinkName {
            link: parent.to_string(),
        },
        child: LinkName {
            link: child.to_string(),
        },
        axis: Axis::default(),
        limit: JointLimit::default(),
        calibration: None,
        dynamics: None,
        mimic: None,
        safety_controller: None,
    }
}

fn motion_joint(
    name: String,
    motion: &Motion,
    origin: &Pose,
    parent: &str,
    child: &str,
) -> UrdfJoint {
    let axis = Axis {
        xyz: Vec3(motion.axis.into()),
    };
    if motion.rotation {
        UrdfJoint {
            axis,
            ..urdf_joint(name, UrdfType::Continuous, origin, parent, child)
        }
    } else {
        let limit = JointLimit {
            lower: -NO_LIMIT,
            upper: NO_LIMIT,
            effort: NO_LIMIT,
            velocity: NO_LIMIT,
        };
        UrdfJoint {
            axis,
            limit,
            ..urdf_joint(name, UrdfType::Prismatic, origin, parent, child)
        }
    }
}

fn bare_link(name: String) -> Link {
    Link {
        name,
        inertial: Inertial::default(),
        visual: Vec::new(),
        collision: Vec::new(),
    }
}

fn unique<'a>(
    names: impl Iterator<Item = &'a String>,
    element: &'static str,
) -> Result<(), ExportError> {
    let mut seen = std::collections::HashSet::new();
    for name in names {
        if !seen.insert(name) {
            return Err(ExportError::DuplicateName {
                element,
                name: name.clone(),
            });
        }
    }
    Ok(())
}

/// The inertia of a body about its centre of mass, in the axes of its link frame `frame` (given
/// in the body's frame); a massless body has none (the default, all zero, is not written).
fn inertial(body: &BodyInertia, frame: &Pose) -> Inertial {
    if body.massless {
        return Inertial::default();
    }
    let m = body.mass;
    let c = spatial::skew(&body.com);
    // The spatial inertia's top-left block is I_c − m ĉĉ about the body frame's origin.
    let central: Matrix3<f64> = body.inertia.fixed_view::<3, 3>(0, 0) + m * c * c;
    let r = frame.rotation.to_rotation_matrix().into_inner();
    let i = r.transpose() * central * r;
    let com = frame.inverse_transform_point(&Point3::from(body.com));
    Inertial {
        origin: urdf_rs::Pose {
            xyz: Vec3(com.coords.into()),
            rpy: Vec3([0.0; 3]),
        },
        mass: Mass { value: m },
        inertia: Inertia {
            ixx: i[(0, 0)],
            ixy: i[(0, 1)],
            ixz: i[(0, 2)],
            iyy: i[(1, 1)],
            iyz: i[(1, 2)],
            izz: i[(2, 2)],
        },
    }
}

fn urdf_pose(pose: &Pose) -> urdf_rs::Pose {
    urdf_rs::Pose {
        xyz: Vec3(pose.translation.vector.into()),
        rpy: Vec3(rpy(&pose.rotation)),
    }
}

/// Roll, pitch and yaw with R = Rz(yaw)·Ry(pitch)·Rx(roll), URDF's convention. The pitch comes
/// from atan2 (asin loses half the digits near ±π/2) and the roll from what the yaw and pitch
/// leave, so that the three angles give back R to round-off even near gimbal lock.
pub fn rpy(rotation: &UnitQuaternion<f64>) -> [f64; 3] {
    let r = rotation.to_rotation_matrix().into_inner();
    let pitch = (-r[(2, 0)]).atan2(r[(0, 0)].hypot(r[(1, 0)]));
    let yaw = r[(1, 0)].atan2(r[(0, 0)]);
    let turned = UnitQuaternion::from_euler_angles(0.0, pitch, yaw)
        .to_rotation_matrix()
        .into_inner();
    let rest = turned.transpose() * r;
    let roll = rest[(2, 1)].atan2(rest[(2, 2)]);
    [roll, pitch, yaw]
}

// ---------------------------------------------------------------------------------------------
// Dof chains as pieces: constant displacements and single-coordinate motions.

fn pieces(chain: &JointModel, unknowns: &UnknownValues) -> Result<Vec<Piece>, ExportError> {
    let mut pieces = Vec::new();
    let mut moved_by: Vec<Option<usize>> = vec![None; chain.coordinate_count()];
    for (index, step) in chain.steps.iter().enumerate() {
        let refuse = |reason: String| ExportError::Step {
            join: chain.name.clone(),
            step: index + 1,
            reason,
        };
        let before = pieces.len();
        step_pieces(step, unknowns, &mut pieces).map_err(|r| refuse(r.describe(chain)))?;
        for piece in &pieces[before..] {
            let Piece::Moving(motion) = piece else {
                continue;
            };
            if let Some(earlier) = moved_by[motion.coordinate].replace(index + 1) {
                let name = &chain.coordinate_names[motion.coordinate];
                return Err(refuse(format!("moves `{name}`, which step {earlier} moves too: a URDF joint has a coordinate of its own")));
            }
        }
    }
    Ok(pieces)
}

/// Why a step cannot be expressed.
enum Refusal {
    Evaluation(EvalError),
    /// One expression of two coordinates.
    Several(usize, usize),
    Nonlinear(usize),
    /// A coordinate that moves its step at a rate other than 1.
    Rate(usize, f64),
}

impl Refusal {
    fn describe(&self, chain: &JointModel) -> String {
        let name = |k: &usize| chain.coordinate_names.get(*k).map_or("?", String::as_str);
        match self {
            Refusal::Evaluation(EvalError::NotGeometric(what)) => format!("depends on {what}"),
            Refusal::Evaluation(EvalError::NotFinite) => "is not a finite number".to_string(),
            Refusal::Evaluation(EvalError::Missing(_)) => {
                "needs the value of an unknown".to_string()
            }
            Refusal::Several(a, b) => format!(
                "has an expression of two coordinates, `{}` and `{}`",
                name(a),
                name(b)
            ),
            Refusal::Nonlinear(k) => format!(
                "uses the coordinate `{}` in a nonlinear expression",
                name(k)
            ),
            Refusal::Rate(k, rate) => format!(
                "moves {} per unit of `{}`: a URDF joint moves 1 per unit of its coordinate",
                number(*rate),
                name(k)
            ),
        }
    }
}

fn step_pieces(
    step: &Step,
    unknowns: &UnknownValues,
    pieces: &mut Vec<Piece>,
) -> Result<(), Refusal> {
    match step {
        Step::Rotation { angle, axis } => {
            let angle = affine(angle, unknowns)?;
            pieces.push(Piece::Constant(rotation(axis, angle.constant)));
            if let Some((coordinate, rate)) = angle.term {
                // Rot(a, c + s·q) = Rot(a, c)·Rot(s·a, q) for s = ±1.
                unit_rate(coordinate, rate)?;
                pieces.push(Piece::Moving(Motion {
                    coordinate,
                    rotation: true,
                    axis: axis * rate.signum(),
                }));
            }
        }
        Step::Translation(components) => {
            let mut offset = Vector3::zeros();
            let mut directions: Vec<(usize, Vector3<f64>)> = Vec::new();
            for (i, component) in components.iter().enumerate() {
                let value = affine(component, unknowns)?;
                offset[i] = value.constant;
                let Some((coordinate, rate)) = value.term else {
                    continue;
                };
                match directions.iter_mut().find(|(k, _)| *k == coordinate) {
                    Some((_, direction)) => direction[i] = rate,
                    None => directions.push((coordinate, Vector3::ith(i, rate))),
                }
            }
            // Translations commute: the constant part, then one prismatic joint per coordinate.
            pieces.push(Piece::Constant(translation(offset)));
            for (coordinate, direction) in directions {
                unit_rate(coordinate, direction.norm())?;
                pieces.push(Piece::Moving(Motion {
                    coordinate,
                    rotation: false,
                    axis: direction,
                }));
            }
        }
    }
    Ok(())
}

fn unit_rate(coordinate: usize, rate: f64) -> Result<(), Refusal> {
    if (rate.abs() - 1.0).abs() > 1e-12 {
        return Err(Refusal::Rate(coordinate, rate.abs()));
    }
    Ok(())
}

/// `constant + rate · q[coordinate]`.
#[derive(Clone, Copy)]
struct Affine {
    constant: f64,
    term: Option<(usize, f64)>,
}

impl Affine {
    fn scaled(self, factor: f64) -> Affine {
        let term = self
            .term
            .map(|(k, rate)| (k, rate * factor))
            .filter(|(_, rate)| *rate != 0.0);
        Affine {
            constant: self.constant * factor,
            term,
        }
    }

    fn plus(self, other: Affine, sign: f64) -> Result<Affine, Refusal> {
        let other = other.scaled(sign);
        let term = match (self.term, other.term) {
            (Some((a, x)), Some((b, y))) if a == b => {
                Some((a, x + y)).filter(|(_, rate)| *rate != 0.0)
            }
            (Some((a, _)), Some((b, _))) => return Err(Refusal::Several(a, b)),
            (term, None) | (None, term) => term,
        };
        Ok(Affine {
            constant: self.constant + other.constant,
            term,
        })
    }
}

/// A scalar of a dof chain as an affine function of one of the link's coordinates.
fn affine(s: &SExpr, unknowns: &UnknownValues) -> Result<Affine, Refusal> {
    let Some(coordinate) = first_coordinate(s) else {
        let constant = eval(s, unknowns).map_err(Refusal::Evaluation)?;
        return Ok(Affine {
            constant,
            term: None,
        });
    };
    match s {
        SExpr::Coordinate { index, .. } => Ok(Affine {
            constant: 0.0,
            term: Some((*index as usize, 1.0)),
        }),
        SExpr::Neg(a) => Ok(affine(a, unknowns)?.scaled(-1.0)),
        SExpr::Add(a, b) => affine(a, unknowns)?.plus(affine(b, unknowns)?, 1.0),
        SExpr::Sub(a, b) => affine(a, unknowns)?.plus(affine(b, unknowns)?, -1.0),
        SExpr::Mul(a, b) => match (affine(a, unknowns)?, affine(b, unknowns)?) {
            (
                x,
                Affine {
                    constant,
                    term: None,
                },
            )
            | (
                Affine {
                    constant,
                    term: None,
                },
                x,
            ) => Ok(x.scaled(constant)),
            _ => Err(Refusal::Nonlinear(coordinate)),
        },
        SExpr::Div(a, b) => match (affine(a, unknowns)?, affine(b, unknowns)?) {
            (
                x,
                Affine {
                    constant,
                    term: None,
                },
            ) => Ok(x.scaled(1.0 / constant)),
            _ => Err(Refusal::Nonlinear(coordinate)),
        },
        _ => Err(Refusal::Nonlinear(coordinate)),
    }
}

/// The first of the link's coordinates (not their rates) that `s` uses.
fn first_coordinate(s: &SExpr) -> Option<usize> {
    match s {
        SExpr::Coordinate { index, order: 0 } => Some(*index as usize),
        SExpr::Neg(a) => first_coordinate(a),
        SExpr::Add(a, b)
        | SExpr::Sub(a, b)
        | SExpr::Mul(a, b)
        | SExpr::Div(a, b)
        | SExpr::Pow(a, b) => first_coordinate(a).or_else(|| first_coordinate(b)),
        SExpr::Call(_) | SExpr::UnknownFunction(_) => {
            s.arguments().iter().find_map(|a| first_coordinate(a))
        }
        _ => None,
    }
}

/// The mimic couplings (`<mimic>`) and the joint friction (`<dynamics>`) of the model on the
/// URDF joints of their joins, which have one coordinate and so the join's name.
fn couple_and_damp(model: &Model, joints: &mut [UrdfJoint]) {
    let name = |k: usize| &model.joints[k].chain.name;
    let position = |joints: &[UrdfJoint], k: usize| joints.iter().position(|j| &j.name == name(k));
    for mimic in &model.mimics {
        if let Some(joint) = position(joints, mimic.joint).map(|i| &mut joints[i]) {
            joint.mimic = Some(urdf_rs::Mimic {
                joint: name(mimic.leader_joint).clone(),
                multiplier: Some(mimic.multiplier),
                offset: Some(mimic.offset),
            });
        }
    }
    for friction in &model.frictions {
        if let Some(joint) = position(joints, friction.joint).map(|i| &mut joints[i]) {
            joint.dynamics = Some(urdf_rs::Dynamics {
                damping: friction.viscous,
                friction: friction.dry,
            });
        }
    }
}

// ---------------------------------------------------------------------------------------------
// XML. urdf-rs's writer always writes `<inertial>` and `<limit>`, so a massless link would get a
// zero mass and a continuous joint zero effort and velocity limits: the text is written here.

/// The URDF document of `robot`: `<inertial>` only for links with mass or inertia, `<axis>`
/// only for joints that move along one, `<limit>` only for revolute and prismatic joints.
pub fn to_xml(robot: &Robot) -> String {
    let mut out = String::from("<?xml version=\"1.0\"?>\n");
    let _ = writeln!(out, "<robot name=\"{}\">", escape(&robot.name));
    for link in &robot.links {
        write_link(&mut out, link);
    }
    for joint in &robot.joints {
        write_joint(&mut out, joint);
    }
    out.push_str("</robot>\n");
    out
}

fn write_link(out: &mut String, link: &Link) {
    let name = escape(&link.name);
    let Inertial {
        origin,
        mass,
        inertia: i,
    } = &link.inertial;
    let moments = [i.ixx, i.ixy, i.ixz, i.iyy, i.iyz, i.izz];
    if mass.value == 0.0 && moments.iter().all(|m| *m == 0.0) {
        let _ = writeln!(out, "  <link name=\"{name}\"/>");
        return;
    }
    let _ = writeln!(out, "  <link name=\"{name}\">\n    <inertial>");
    let _ = writeln!(
        out,
        "      <origin xyz=\"{}\" rpy=\"{}\"/>",
        triple(&origin.xyz),
        triple(&origin.rpy)
    );
    let _ = writeln!(out, "      <mass value=\"{}\"/>", number(mass.value));
    let names = ["ixx", "ixy", "ixz", "iyy", "iyz", "izz"];
    let attributes: Vec<String> = names
        .iter()
        .zip(moments)
        .map(|(n, v)| format!("{n}=\"{}\"", number(v)))
        .collect();
    let _ = writeln!(out, "      <inertia {}/>", attributes.join(" "));
    let _ = writeln!(out, "    </inertial>\n  </link>");
}

fn write_joint(out: &mut String, joint: &UrdfJoint) {
    let kind = match joint.joint_type {
        UrdfType::Revolute => "revolute",
        UrdfType::Continuous => "continuous",
        UrdfType::Prismatic => "prismatic",
        UrdfType::Fixed => "fixed",
        UrdfType::Floating => "floating",
        UrdfType::Planar => "planar",
        UrdfType::Spherical => "spherical",
    };
    let _ = writeln!(
        out,
        "  <joint name=\"{}\" type=\"{kind}\">",
        escape(&joint.name)
    );
    let _ = writeln!(
        out,
        "    <origin xyz=\"{}\" rpy=\"{}\"/>",
        triple(&joint.origin.xyz),
        triple(&joint.origin.rpy)
    );
    let _ = writeln!(out, "    <parent link=\"{}\"/>", escape(&joint.parent.link));
    let _ = writeln!(out, "    <child link=\"{}\"/>", escape(&joint.child.link));
    if matches!(
        joint.joint_type,
        UrdfType::Revolute | UrdfType::Continuous | UrdfType::Prismatic | UrdfType::Planar
    ) {
        let _ = writeln!(out, "    <axis xyz=\"{}\"/>", triple(&joint.axis.xyz));
    }
    if matches!(joint.joint_type, UrdfType::Revolute | UrdfType::Prismatic) {
        let l = &joint.limit;
        let _ = writeln!(
            out,
            "    <limit lower=\"{}\" upper=\"{}\" effort=\"{}\" velocity=\"{}\"/>",
            number(l.lower),
            number(l.upper),
            number(l.effort),
            number(l.velocity)
        );
    }
    if let Some(d) = &joint.dynamics {
        let (damping, friction) = (number(d.damping), number(d.friction));
        let _ = writeln!(
            out,
            "    <dynamics damping=\"{damping}\" friction=\"{friction}\"/>"
        );
    }
    if let Some(m) = &joint.mimic {
        let _ = writeln!(
            out,
            "    <mimic joint=\"{}\" multiplier=\"{}\" offset=\"{}\"/>",
            escape(&m.joint),
            number(m.multiplier.unwrap_or(1.0)),
            number(m.offset.unwrap_or(0.0))
        );
    }
    out.push_str("  </joint>\n");
}

fn triple(v: &Vec3) -> String {
    v.iter().map(|x| number(*x)).collect::<Vec<_>>().join(" ")
}
