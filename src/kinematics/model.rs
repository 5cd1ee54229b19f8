//! The numeric kinematic model: for every join, its two frames as rigid transforms on their bodies
//! and its dof chain as steps to evaluate at given coordinates; the coordinates of the whole
//! mechanism in one vector, principal links first (by number), then complementary links.

use nalgebra::{DMatrix, Matrix6, Vector3};

use super::eval::{eval, eval_jet, Env, EvalError, UnknownValues};
use crate::diag::Diagnostic;
use crate::elab::mechanism::Mechanism;
use crate::elab::value::{Displacement, Elementary, JoinId, SExpr, Scalar};
use crate::source::Span;
use crate::spatial::{self, Pose, Twist};
use crate::topology::Topology;

#[derive(Clone, Debug)]
pub enum Step {
    Translation([Scalar; 3]),
    Rotation { angle: Scalar, axis: Vector3<f64> },
}

#[derive(Clone, Debug)]
pub struct JointModel {
    pub join: JoinId,
    pub name: String,
    /// Body numbers (0 = earth) of the first and second frames.
    pub first_body: usize,
    pub second_body: usize,
    /// The frames on their bodies.
    pub first: Pose,
    pub second: Pose,
    pub steps: Vec<Step>,
    pub coordinate_names: Vec<String>,
    /// Index of the joint's first coordinate in the mechanism's coordinate vector.
    pub offset: usize,
}

impl JointModel {
    pub fn coordinate_count(&self) -> usize {
        self.coordinate_names.len()
    }

    /// The chain when it is one rotation or translation along a fixed axis, linear in its one
    /// coordinate (structurally: no evaluation).
    fn single_motion(&self) -> Option<SingleMotion> {
        if self.coordinate_count() != 1 {
            return None;
        }
        match self.steps.as_slice() {
            [Step::Rotation { angle, axis }] => linear_in_first(angle)
                .filter(|&scale| scale != 0.0)
                .map(|scale| SingleMotion::Rotation { axis: *axis, scale }),
            [Step::Translation(t)] => {
                let [x, y, z] = [0, 1, 2].map(|i| linear_in_first(&t[i]));
                let direction = Vector3::new(x?, y?, z?);
                (direction != Vector3::zeros()).then_some(SingleMotion::Translation { direction })
            }
            _ => None,
        }
    }

    /// The dof chain's transform at coordinates `q`, and its motion subspace: column k is the
    /// twist, in the joint's first frame, produced by a unit rate of coordinate k.
    pub fn chain(
        &self,
        q: &[f64],
        unknowns: &UnknownValues,
    ) -> Result<(Pose, DMatrix<f64>), EvalError> {
        let motion = self.chain_motion(q, None, unknowns)?;
        Ok((motion.pose, motion.subspace))
    }

    /// The chain's transform, motion subspace and, when rates are given, the acceleration of the
    /// chain's end (in the first frame, as a twist derivative) when the coordinates move at those
    /// rates with no coordinate acceleration: the bias term of the joint.
    pub fn chain_motion(
        &self,
        q: &[f64],
        rates: Option<&[f64]>,
        unknowns: &UnknownValues,
    ) -> Result<ChainMotion, EvalError> {
        let mut motion = ChainMotion::default();
        self.chain_motion_into(q, rates, unknowns, &mut motion)?;
        Ok(motion)
    }

    /// `chain_motion` into `out`, reusing its storage: nothing is allocated once it has held
    /// this chain's motion.
    pub fn chain_motion_into(
        &self,
        q: &[f64],
        rates: Option<&[f64]>,
        unknowns: &UnknownValues,
        out: &mut ChainMotion,
    ) -> Result<(), EvalError> {
        let n = self.coordinate_count();
        let env = Env { coordinates: q };
        let ChainMotion {
            pose,
            subspace,
            velocity,
            bias,
            unit,
            rest,
        } = out;
        rest.clear();
        rest.resize(n, 0.0);
        unit.clear();
        unit.resize(n, 0.0);
        let rates = rates.unwrap_or(rest);
        if subspace.ncols() == n {
            subspace.fill(0.0);
        } else {
            *subspace = DMatrix::zeros(6, n);
        }
        (*pose, *velocity, *bias) = (Pose::identity(), Twist::zeros(), Twist::zeros());
        if let Some(single) = self.single_motion() {
            // One rotation or translation along a fixed axis, proportional to the coordinate:
            // its subspace is that constant twist, its bias zero; nothing to evaluate.
            let column = match single {
                SingleMotion::Rotation { axis, scale } => {
                    *pose = spatial::rotation(&axis, scale * q[0]);
                    spatial::twist(axis * scale, Vector3::zeros())
                }
                SingleMotion::Translation { direction } => {
                    *pose = spatial::translation(direction * q[0]);
                    spatial::twist(Vector3::zeros(), direction)
                }
            };
            subspace.column_mut(0).copy_from(&column);
            *velocity = column * rates[0];
            return Ok(());
        }
        for step in &self.steps {
            // Value and derivatives of the step's parameters along the rates, then per
            // coordinate (a column of the subspace, moved to the first frame).
            let (transform, local_velocity, local_bias) = match step {
                Step::Translation(v) => {
                    let along = [0, 1, 2].map(|i| eval_jet(&v[i], unknowns, &env, rates));
                    let [x, y, z] = along;
                    let (x, y, z) = (x?, y?, z?);
                    for k in 0..n {
                        unit[k] = 1.0;
                        let d = |i: usize| eval_jet(&v[i], unknowns, &env, unit).map(|j| j.first);
                        let column =
                            spatial::twist(Vector3::zeros(), Vector3::new(d(0)?, d(1)?, d(2)?));
                        unit[k] = 0.0;
                        add_moved(subspace, k, pose, &column);
                    }
                    let value = Vector3::new(x.value, y.value, z.value);
                    let velocity =
                        spatial::twist(Vector3::zeros(), Vector3::new(x.first, y.first, z.first));
                    let bias = spatial::twist(
                        Vector3::zeros(),
                        Vector3::new(x.second, y.second, z.second),
                    );
                    (spatial::translation(value), velocity, bias)
                }
                Step::Rotation { angle, axis } => {
                    let jet = eval_jet(angle, unknowns, &env, rates)?;
                    for k in 0..n {
                        unit[k] = 1.0;
                        let rate = eval_jet(angle, unknowns, &env, unit)?.first;
                        unit[k] = 0.0;
                        add_moved(
                            subspace,
                            k,
                            pose,
                            &spatial::twist(axis * rate, Vector3::zeros()),
                        );
                    }
                    let velocity = spatial::twist(axis * jet.first, Vector3::zeros());
                    let bias = spatial::twist(axis * jet.second, Vector3::zeros());
                    (spatial::rotation(axis, jet.value), velocity, bias)
                }
            };
            // d/dt of Ad(P) ξ is V_P × Ad(P) ξ + Ad(P) ξ̇ (spatial twists in the first frame).
            let step_velocity = spatial::motion_to_parent(pose, &local_velocity);
            *bias += cross(velocity, &step_velocity) + spatial::motion_to_parent(pose, &local_bias);
            *velocity += step_velocity;
            *pose *= transform;
        }
        Ok(())
    }
}

/// Adds `column`, a twist in the frame `pose` places, to column k of the subspace (in the first
/// frame).
fn add_moved(subspace: &mut DMatrix<f64>, k: usize, pose: &Pose, column: &Twist) {
    let moved = spatial::motion_to_parent(pose, column);
    for r in 0..6 {
        subspace[(r, k)] += moved[r];
    }
}

/// A one-coordinate chain of one step: a rotation by `scale` · q about `axis`, or a translation
/// by q · `direction`.
enum SingleMotion {
    Rotation { axis: Vector3<f64>, scale: f64 },
    Translation { direction: Vector3<f64> },
}

/// A dof chain at given coordinates and rates, in the joint's first frame.
#[derive(Clone, Debug)]
pub struct ChainMotion {
    pub pose: Pose,
    pub subspace: DMatrix<f64>,
    /// Twist of the chain's end: `subspace · rates`.
    pub velocity: Twist,
    /// Its derivative when the coordinates have no acceleration.
    pub bias: Twist,
    /// Scratch: unit rates, one coordinate at a time, and zero rates.
    unit: Vec<f64>,
    rest: Vec<f64>,
}

impl ChainMotion {
    /// The subspace padded with zero columns to 6 × 6 (for chains of at most six coordinates:
    /// a quaternion joint's declared angles), for fixed-size solves that allocate nothing. The
    /// padding changes neither a Householder QR factorisation of the first columns (it takes
    /// the columns in order) nor a pseudo-inverse (padded with zero rows).
    pub fn padded_subspace(&self) -> Matrix6<f64> {
        let mut padded = Matrix6::zeros();
        for (k, column) in self.subspace.column_iter().enumerate() {
            padded.set_column(k, &column);
        }
        padded
    }
}

impl Default for ChainMotion {
    fn default() -> ChainMotion {
        ChainMotion {
            pose: Pose::identity(),
            subspace: DMatrix::zeros(6, 0),
            velocity: Twist::zeros(),
            bias: Twist::zeros(),
            unit: Vec::new(),
            rest: Vec::new(),
        }
    }
}

/// `a × b` for two twists `[ω; v]`.
fn cross(a: &Twist, b: &Twist) -> Twist {
    let (wa, va) = (spatial::angular(a), spatial::linear(a));
    let (wb, vb) = (spatial::angular(b), spatial::linear(b));
    spatial::twist(wa.cross(&wb), wa.cross(&vb) + va.cross(&wb))
}

#[derive(Clone, Debug)]
pub struct KinematicModel {
    pub topology: Topology,
    /// Principal joints (index j - 1 for body j), then complementary ones.
    pub joints: Vec<JointModel>,
    pub unknowns: UnknownValues,
    pub coordinate_count: usize,
}

impl KinematicModel {
    pub fn principal(&self) -> &[JointModel] {
        &self.joints[..self.topology.body_count()]
    }

    pub fn complementary(&self) -> &[JointModel] {
        &self.joints[self.topology.body_count()..]
    }

    /// Coordinates of the tree (principal links).
    pub fn tree_coordinate_count(&self) -> usize {
        self.principal()
            .iter()
            .map(JointModel::coordinate_count)
            .sum()
    }

    /// `crank.q`, … for every coordinate, in vector order.
    pub fn coordinate_names(&self) -> Vec<String> {
        self.joints
            .iter()
            .flat_map(|j| {
                j.coordinate_names
                    .iter()
                    .map(move |c| format!("{}.{c}", j.name))
            })
            .collect()
    }

    pub fn joint_of_join(&self, join: JoinId) -> Option<&JointModel> {
        self.joints.iter().find(|j| j.join == join)
    }
}

/// Builds the numeric model. Every quantity the geometry uses must have a value.
pub fn build(
    mechanism: &Mechanism,
    topology: Topology,
    unknowns: UnknownValues,
) -> Result<KinematicModel, Vec<Diagnostic>> {
    let mut joints = Vec::new();
    let mut errors = Vec::new();
    let mut offset = 0;
    let order = topology
        .principal
        .iter()
        .map(|l| l.join)
        .chain(topology.complementary.iter().map(|l| l.join));
    for join_id in order {
        match joint_model(mechanism, &topology, join_id, &unknowns, offset) {
            Ok(joint) => {
                offset += joint.coordinate_count();
                joints.push(joint);
            }
            Err(e) => errors.push(e),
        }
    }
    if !errors.is_empty() {
        return Err(errors);
    }
    Ok(KinematicModel {
        topology,
        joints,
        unknowns,
        coordinate_count: offset,
    })
}

fn joint_model(
    mechanism: &Mechanism,
    topology: &Topology,
    id: JoinId,
    unknowns: &UnknownValues,
    offset: usize,
) -> Result<JointModel, Diagnostic> {
    let join = mechanism.join(id);
    let link = mechanism.link(join.link);
    let name = mechanism.join_name(id);
    let frame = |d: &Displacement| {
        constant_pose(d, unknowns).map_err(|e| geometry_error(mechanism, e, join.span, &name))
    };
    let first = frame(&join.first.displacement)?;
    let second = frame(&join.second.displacement)?;
    let steps = link_steps(mechanism, id, unknowns)?;
    Ok(JointModel {
        join: id,
        name,
        first_body: topology.number(join.first.body),
        second_body: topology.number(join.second.body),
        first,
        second,
        steps,
        coordinate_names: link.coordinates.iter().map(|c| c.to_string()).collect(),
        offset,
    })
}

/// The steps of a join's dof chain, with rotation axes evaluated and normalised.
pub fn link_steps(
    mechanism: &Mechanism,
    id: JoinId,
    unknowns: &UnknownValues,
) -> Result<Vec<Step>, Diagnostic> {
    let join = mechanism.join(id);
    let link = mechanism.link(join.link);
    let name = mechanism.join_name(id);
    let mut steps = Vec::new();
    let uses_frame_state = |s: &Scalar| s.uses_frame_state();
    for step in link.dofs.iter().flat_map(|d| d.0.iter()) {
        let parameters: Vec<&Scalar> = match step {
            Elementary::Translation(v) => v.iter().collect(),
            Elementary::Rotation { angle, axis } => {
                std::iter::once(angle).chain(axis.iter()).collect()
            }
        };
        if parameters.into_iter().any(uses_frame_state) {
            return Err(geometry_error(
                mechanism,
                EvalError::NotGeometric("the state of a frame (position, velocity, …)"),
                link.span,
                &name,
            ));
        }
        steps.push(match step {
            Elementary::Translation(v) => Step::Translation(v.clone()),
            Elementary::Rotation { angle, axis } => {
                let axis = constant_vector(axis, unknowns)
                    .map_err(|e| geometry_error(mechanism, e, link.span, &name))?;
                let norm = axis.norm();
                if norm == 0.0 || !norm.is_finite() {
                    return Err(Diagnostic::error(
                        "E0704",
                        format!("a rotation of join `{name}` has a zero axis"),
                    )
                    .primary(link.span, "in this link's dof chain"));
                }
                Step::Rotation {
                    angle: angle.clone(),
                    axis: axis / norm,
                }
            }
        });
    }
    Ok(steps)
}

/// A joint model of the link alone (frames at identity): enough to analyse the joint.
pub fn link_only(
    mechanism: &Mechanism,
    id: JoinId,
    unknowns: &UnknownValues,
) -> Result<JointModel, Diagnostic> {
    let join = mechanism.join(id);
    Ok(JointModel {
        join: id,
        name: mechanism.join_name(id),
        first_body: 0,
        second_body: 0,
        first: Pose::identity(),
        second: Pose::identity(),
        steps: link_steps(mechanism, id, unknowns)?,
        coordinate_names: mechanism
            .link(join.link)
            .coordinates
            .iter()
            .map(|c| c.to_string())
            .collect(),
        offset: 0,
    })
}

fn constant_vector(v: &[Scalar; 3], unknowns: &UnknownValues) -> Result<Vector3<f64>, EvalError> {
    let value = |s: &Scalar| {
        eval(s, unknowns, &[]).map_err(|e| match e {
            EvalError::NotGeometric("a coordinate of another link") => {
                EvalError::NotGeometric("a coordinate (rotation axes and frames are constant)")
            }
            other => other,
        })
    };
    Ok(Vector3::new(value(&v[0])?, value(&v[1])?, value(&v[2])?))
}

/// A displacement without coordinates, as a rigid transform.
pub fn constant_pose(d: &Displacement, unknowns: &UnknownValues) -> Result<Pose, EvalError> {
    let mut pose = Pose::identity();
    for step in &d.0 {
        pose *= match step {
            Elementary::Translation(v) => spatial::translation(constant_vector(v, unknowns)?),
            Elementary::Rotation { angle, axis } => {
                let axis = constant_vector(axis, unknowns)?;
                let angle = eval(angle, unknowns, &[])?;
                let norm = axis.norm();
                if norm == 0.0 {
                    Pose::identity()
                } else {
                    spatial::rotation(&(axis / norm), angle)
                }
            }
        };
    }
    Ok(pose)
}

fn geometry_error(mechanism: &Mechanism, error: EvalError, span: Span, join: &str) -> Diagnostic {
    match error {
        EvalError::Missing(id) => {
            let what = super::eval::unknown_label(mechanism, id);
            Diagnostic::error(
                "E0801",
                format!("the geometry of join `{join}` needs a value for {what}"),
            )
            .primary(mechanism.unknowns[id.0 as usize].span, "no value given")
            .secondary(span, "used by this join")
            .help("give it a value: `let L = 0.5;` and use `L` instead of `?s`")
        }
        EvalError::NotGeometric(what) => Diagnostic::error(
            "E0802",
            format!("the geometry of join `{join}` depends on {what}"),
        )
        .primary(span, "here")
        .help("frames and rotation axes are constant; only the link's own coordinates vary"),
    }
}

impl JointModel {
    /// ∂/∂q along `direction` of the chain's twist `S(q)·rates` (in the first frame): how the
    /// joint's velocity changes when its coordinates move while the rates stay put. With
    /// `direction = rates` this is the bias of `chain_motion`.
    pub fn velocity_derivative(
        &self,
        q: &[f64],
        rates: &[f64],
        direction: &[f64],
        unknowns: &UnknownValues,
    ) -> Result<Twist, EvalError> {
        let env = Env { coordinates: q };
        let sum: Vec<f64> = rates.iter().zip(direction).map(|(a, b)| a + b).collect();
        // Mixed second derivative by polarisation: D²f[u, w] = (D²f[u + w] − D²f[u] − D²f[w]) / 2.
        let mixed = |s: &Scalar| -> Result<(f64, f64, f64), EvalError> {
            let along_rates = eval_jet(s, unknowns, &env, rates)?;
            let along_direction = eval_jet(s, unknowns, &env, direction)?;
            let along_sum = eval_jet(s, unknowns, &env, &sum)?;
            let second = 0.5 * (along_sum.second - along_rates.second - along_direction.second);
            Ok((along_rates.first, along_direction.first, second))
        };
        let mut pose = Pose::identity();
        let mut moved_frame = Twist::zeros();
        let mut derivative = Twist::zeros();
        for step in &self.steps {
            let (transform, local_rates, local_direction, local_mixed) = match step {
                Step::Translation(v) => {
                    let (x, y, z) = (mixed(&v[0])?, mixed(&v[1])?, mixed(&v[2])?);
                    let value = Vector3::new(
                        eval(&v[0], unknowns, q)?,
                        eval(&v[1], unknowns, q)?,
                        eval(&v[2], unknowns, q)?,
                    );
                    let zero = Vector3::zeros();
                    (
                        spatial::translation(value),
                        spatial::twist(zero, Vector3::new(x.0, y.0, z.0)),
                        spatial::twist(zero, Vector3::new(x.1, y.1, z.1)),
                        spatial::twist(zero, Vector3::new(x.2, y.2, z.2)),
                    )
                }
                Step::Rotation { angle, axis } => {
                    let (rate, along, second) = mixed(angle)?;
                    let zero = Vector3::zeros();
                    (
                        spatial::rotation(axis, eval(angle, unknowns, q)?),
                        spatial::twist(axis * rate, zero),
                        spatial::twist(axis * along, zero),
                        spatial::twist(axis * second, zero),
                    )
                }
            };
            let step_velocity = spatial::motion_to_parent(&pose, &local_rates);
            derivative += cross(&moved_frame, &step_velocity)
                + spatial::motion_to_parent(&pose, &local_mixed);
            moved_frame += spatial::motion_to_parent(&pose, &local_direction);
            pose *= transform;
        }
        Ok(derivative)
    }
}

/// The coefficient c when `s` is c · (coordinate 0), structurally (no evaluation).
pub fn linear_in_first(s: &SExpr) -> Option<f64> {
    match s {
        SExpr::Num(x) if *x == 0.0 => Some(0.0),
        SExpr::Coordinate { index: 0, order: 0 } => Some(1.0),
        SExpr::Neg(a) => linear_in_first(a).map(|c| -c),
        SExpr::Mul(a, b) => match (&**a, &**b) {
            (SExpr::Num(x), other) | (other, SExpr::Num(x)) => {
                linear_in_first(other).map(|c| c * x)
            }
            _ => None,
        },
        SExpr::Div(a, b) => match &**b {
            SExpr::Num(x) if *x != 0.0 => linear_in_first(a).map(|c| c / x),
            _ => None,
        },
        _ => None,
    }
}
