//! The numeric kinematic model: for every join, its two frames as rigid transforms on their bodies
//! and its dof chain as steps to evaluate at given coordinates; the coordinates of the whole
//! mechanism in one vector, principal links first (by number), then complementary links.

use nalgebra::{DMatrix, Matrix6, Vector3};

use super::chain::{ChainScratch, CompiledChain};
use super::eval::{eval, EvalError, Geometric, UnknownValues};
use super::rheonomic::{self, PrescribedMotion};
use crate::diag::Diagnostic;
use crate::elab::mechanism::Mechanism;
use crate::elab::value::{Displacement, Elementary, JoinId, SExpr, Scalar};
use crate::source::Span;
use crate::spatial::{self, constant, Pose, Real, Twist};
use crate::symbolic::expr::{ExprId, Pool};
use crate::symbolic::program::Lower;
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
    /// The hidden coordinates of a rheonomic chain (`time` in it), after the declared ones,
    /// with their laws (`rheonomic`).
    pub prescribed: Vec<PrescribedMotion>,
    /// The steps' parameters compiled, or why they could not be (reported when evaluated).
    compiled: Result<CompiledChain, EvalError>,
}

impl JointModel {
    /// Its coordinates: the declared ones, then the hidden ones of a rheonomic chain.
    pub fn coordinate_count(&self) -> usize {
        self.coordinate_names.len()
    }

    /// The coordinates its link declares (the first ones).
    pub fn declared_count(&self) -> usize {
        self.coordinate_count() - self.prescribed.len()
    }

    /// Whether coordinate `index` is an angle that gives the same pose every full turn: the
    /// chain uses it only as the whole angle of its rotations (`q || axis`, as `revolute`).
    pub fn turns(&self, index: usize) -> bool {
        let index = index as u32;
        let whole =
            |s: &Scalar| matches!(**s, SExpr::Coordinate { index: i, order: 0 } if i == index);
        let mut as_angle = false;
        for step in &self.steps {
            match step {
                Step::Rotation { angle, .. } if whole(angle) => as_angle = true,
                Step::Rotation { angle, .. } if angle.uses_coordinate(index) => return false,
                Step::Translation(t) if t.iter().any(|s| s.uses_coordinate(index)) => return false,
                _ => {}
            }
        }
        as_angle
    }

    /// The chain when it is one rotation or translation along a fixed axis, linear in its one
    /// coordinate (structurally: no evaluation).
    pub(crate) fn single_motion(&self) -> Option<SingleMotion> {
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
    pub fn chain(&self, q: &[f64]) -> Result<(Pose, DMatrix<f64>), EvalError> {
        let motion = self.chain_motion(q, None)?;
        Ok((motion.pose, motion.subspace))
    }

    /// The chain's transform, motion subspace and, when rates are given, the acceleration of the
    /// chain's end (in the first frame, as a twist derivative) when the coordinates move at those
    /// rates with no coordinate acceleration: the bias term of the joint.
    pub fn chain_motion(&self, q: &[f64], rates: Option<&[f64]>) -> Result<ChainMotion, EvalError> {
        let mut motion = ChainMotion::default();
        self.chain_motion_into(q, rates, &mut motion)?;
        Ok(motion)
    }

    /// `chain_motion` into `out`, reusing its storage: nothing is allocated once it has held
    /// this chain's motion.
    pub fn chain_motion_into(
        &self,
        q: &[f64],
        rates: Option<&[f64]>,
        out: &mut ChainMotion,
    ) -> Result<(), EvalError> {
        if self.single_motion_into(q, rates, spatial::rotation, out) {
            return Ok(());
        }
        let n = self.coordinate_count();
        out.reset(n);
        let chain = self.compiled()?;
        chain.eval(q, rates, &mut out.scratch);
        let ChainMotion {
            pose,
            subspace,
            velocity,
            bias,
            scratch,
        } = out;
        let mut first = 0;
        for step in &self.steps {
            let parameter = |i: usize| first + i;
            for k in 0..n {
                let column = local_twist(step, |i| chain.partial(scratch, parameter(i), k));
                add_moved(subspace, k, pose, &column);
            }
            if let Some(rates) = rates {
                let along = |f: &dyn Fn(usize) -> f64| (0..n).map(|k| f(k) * rates[k]).sum::<f64>();
                let local_velocity = local_twist(step, |i| {
                    along(&|k| chain.partial(scratch, parameter(i), k))
                });
                let local_bias =
                    local_twist(step, |i| along(&|l| chain.mixed(scratch, parameter(i), l)));
                // d/dt of Ad(P) ξ is V_P × Ad(P) ξ + Ad(P) ξ̇ (spatial twists in the first frame).
                let step_velocity = spatial::motion_to_parent(pose, &local_velocity);
                *bias +=
                    cross(velocity, &step_velocity) + spatial::motion_to_parent(pose, &local_bias);
                *velocity += step_velocity;
            }
            *pose *= step_transform(step, |i| chain.value(scratch, parameter(i)));
            first += parameter_count(step);
        }
        Ok(())
    }

    /// `chain_motion_into` for a chain of one rotation or translation along a fixed axis,
    /// proportional to its coordinate (`single_motion`), in any scalar, its rotation by
    /// `rotation` (axis, angle): its subspace is that constant twist, its bias zero; nothing
    /// to evaluate. False, `out` untouched, for any other chain, whose expressions are
    /// evaluated in `f64` only.
    pub fn single_motion_into<T: Real>(
        &self,
        q: &[T],
        rates: Option<&[T]>,
        rotation: fn(&Vector3<T>, T) -> Pose<T>,
        out: &mut ChainMotion<T>,
    ) -> bool {
        let Some(single) = self.single_motion() else {
            return false;
        };
        single.motion_into(q, rates, rotation, out);
        true
    }

    /// The twists of step `index` of the chain per unit rate of each coordinate, in the step's
    /// own frame, into `columns` (6 × coordinates); `scratch` holds the evaluated chain.
    pub fn step_columns_into(
        &self,
        q: &[f64],
        index: usize,
        scratch: &mut ChainMotion,
        columns: &mut DMatrix<f64>,
    ) -> Result<(), EvalError> {
        let chain = self.compiled()?;
        chain.eval(q, None, &mut scratch.scratch);
        let n = self.coordinate_count();
        if columns.ncols() != n {
            *columns = DMatrix::zeros(6, n);
        }
        let first: usize = self.steps[..index].iter().map(parameter_count).sum();
        let step = &self.steps[index];
        for k in 0..n {
            let column = local_twist(step, |i| chain.partial(&scratch.scratch, first + i, k));
            columns.column_mut(k).copy_from(&column);
        }
        Ok(())
    }

    /// The compiled chain, or why it could not be compiled (an unknown without a value, …).
    fn compiled(&self) -> Result<&CompiledChain, EvalError> {
        self.compiled.as_ref().map_err(Clone::clone)
    }
}

/// A step's twist whose parameters' components are `component(i)` (the rate or partial of the
/// step's parameter i): along the axis for a rotation, the vector itself for a translation.
fn local_twist(step: &Step, component: impl Fn(usize) -> f64) -> Twist {
    match step {
        Step::Translation(_) => spatial::twist(
            Vector3::zeros(),
            Vector3::new(component(0), component(1), component(2)),
        ),
        Step::Rotation { axis, .. } => spatial::twist(axis * component(0), Vector3::zeros()),
    }
}

/// The chain of `steps` compiled: their parameters in order (a translation's three components,
/// a rotation's angle).
fn compile(
    steps: &[Step],
    coordinates: usize,
    unknowns: &UnknownValues,
) -> Result<CompiledChain, EvalError> {
    let parameters: Vec<&SExpr> = steps
        .iter()
        .flat_map(|step| match step {
            Step::Translation(v) => v.iter().map(|s| &**s).collect(),
            Step::Rotation { angle, .. } => vec![&**angle],
        })
        .collect();
    CompiledChain::new(&parameters, coordinates, unknowns)
}

/// Number of parameters of a step: three for a translation, one for a rotation.
fn parameter_count(step: &Step) -> usize {
    match step {
        Step::Translation(_) => 3,
        Step::Rotation { .. } => 1,
    }
}

/// A step's transform when its parameters have the values `value(i)`.
fn step_transform(step: &Step, value: impl Fn(usize) -> f64) -> Pose {
    match step {
        Step::Translation(_) => spatial::translation(Vector3::new(value(0), value(1), value(2))),
        Step::Rotation { axis, .. } => spatial::rotation(axis, value(0)),
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
#[derive(Clone, Copy, Debug)]
pub(crate) enum SingleMotion {
    Rotation { axis: Vector3<f64>, scale: f64 },
    Translation { direction: Vector3<f64> },
}

impl SingleMotion {
    /// The chain's motion at its coordinate `q[0]` (and rate, when given) into `out`, its
    /// rotation by `rotation` (axis, angle): its subspace is the constant twist, its bias zero.
    /// Callers that evaluate one chain many times find it once (`JointModel::single_motion`
    /// reads the chain's expressions) and call this.
    pub(crate) fn motion_into<T: Real>(
        self,
        q: &[T],
        rates: Option<&[T]>,
        rotation: fn(&Vector3<T>, T) -> Pose<T>,
        out: &mut ChainMotion<T>,
    ) {
        out.reset(1);
        let column = match self {
            SingleMotion::Rotation { axis, scale } => {
                let axis: Vector3<T> = axis.cast();
                out.pose = rotation(&axis, constant::<T>(scale) * q[0]);
                spatial::twist(axis * constant::<T>(scale), Vector3::zeros())
            }
            SingleMotion::Translation { direction } => {
                let direction: Vector3<T> = direction.cast();
                out.pose = spatial::translation(direction * q[0]);
                spatial::twist(Vector3::zeros(), direction)
            }
        };
        out.subspace.column_mut(0).copy_from(&column);
        out.velocity = column * rates.map_or(T::zero(), |r| r[0]);
    }
}

/// A dof chain at given coordinates and rates, in the joint's first frame, in the scalar `T`
/// (`f64`, or dual numbers for a chain of one rotation or translation: `single_motion_into`).
#[derive(Clone, Debug)]
pub struct ChainMotion<T: Real = f64> {
    pub pose: Pose<T>,
    pub subspace: DMatrix<T>,
    /// Twist of the chain's end: `subspace · rates`.
    pub velocity: Twist<T>,
    /// Its derivative when the coordinates have no acceleration.
    pub bias: Twist<T>,
    /// Where the compiled chain is evaluated.
    scratch: ChainScratch,
}

impl<T: Real> ChainMotion<T> {
    /// The motion of a chain of `n` coordinates that does not move: identity, zero subspace.
    fn reset(&mut self, n: usize) {
        if self.subspace.ncols() == n {
            // As a slice: nalgebra's `fill` steps a strided iterator element by element.
            self.subspace.as_mut_slice().fill(T::zero());
        } else {
            self.subspace = DMatrix::zeros(6, n);
        }
        (self.pose, self.velocity, self.bias) = (Pose::identity(), Twist::zeros(), Twist::zeros());
    }
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

impl<T: Real> Default for ChainMotion<T> {
    fn default() -> ChainMotion<T> {
        ChainMotion {
            pose: Pose::identity(),
            subspace: DMatrix::zeros(6, 0),
            velocity: Twist::zeros(),
            bias: Twist::zeros(),
            scratch: ChainScratch::default(),
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

    /// For every coordinate, in vector order, whether it turns (`JointModel::turns`).
    pub fn turning(&self) -> Vec<bool> {
        self.joints
            .iter()
            .flat_map(|j| (0..j.coordinate_count()).map(move |k| j.turns(k)))
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
    let name = mechanism.join_name(id);
    let frame = |d: &Displacement| {
        constant_pose(d, unknowns).map_err(|e| geometry_error(mechanism, e, join.span, &name))
    };
    let first = frame(&join.first.displacement)?;
    let second = frame(&join.second.displacement)?;
    let mut joint = link_only(mechanism, id, unknowns)?;
    joint.first_body = topology.number(join.first.body);
    joint.second_body = topology.number(join.second.body);
    (joint.first, joint.second, joint.offset) = (first, second, offset);
    Ok(joint)
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
                let axis_expr = axis;
                let axis = constant_vector(axis, unknowns)
                    .map_err(|e| geometry_error(mechanism, e, link.span, &name))?;
                let norm = axis.norm();
                if norm == 0.0 || !norm.is_finite() {
                    return Err(zero_axis(
                        mechanism,
                        axis_expr,
                        (link.span, join.span),
                        &name,
                    ));
                }
                Step::Rotation {
                    angle: angle.clone(),
                    axis: axis / norm,
                }
            }
        });
    }
    coordinates_move(mechanism, id, unknowns)?;
    Ok(steps)
}

/// E0829: a coordinate of a join's dof chain that moves nothing with the values of its
/// unknowns: `prismatic([a, 0, 0])` with `given a = 0` or `--set a=0` is `q * [0, 0, 0]`, and
/// `k * q || axis` with k = 0 turns by nothing. As written the chain depends on the coordinate
/// (E0610 refuses one that does not), so these values came from `given` or `--set`; the joint
/// would be a weld with a singular mass matrix. The translations and angles are lowered with
/// the unknowns' values, where products by zero fold, and differentiated by each coordinate.
fn coordinates_move(
    mechanism: &Mechanism,
    id: JoinId,
    unknowns: &UnknownValues,
) -> Result<(), Diagnostic> {
    let join = mechanism.join(id);
    let link = mechanism.link(join.link);
    let moving: Vec<&Scalar> = link
        .dofs
        .iter()
        .flat_map(|d| d.0.iter())
        .flat_map(|step| match step {
            Elementary::Translation(v) => v.iter().collect::<Vec<_>>(),
            Elementary::Rotation { angle, .. } => vec![angle],
        })
        .collect();
    let mut named = std::collections::BTreeSet::new();
    moving.iter().for_each(|s| s.collect_unknowns(&mut named));
    if named.is_empty() {
        return Ok(()); // Numbers alone: checked as written (E0610).
    }
    let mut lowering = Geometric {
        pool: Pool::new(),
        unknowns,
        coordinates: Vec::new(),
    };
    for coordinate in &link.coordinates {
        let symbol = lowering.pool.symbol(coordinate);
        lowering.coordinates.push(symbol);
    }
    // What cannot be lowered here (a missing value, a time derivative) is reported elsewhere.
    let Ok(values) = moving
        .iter()
        .map(|s| lowering.lower(s))
        .collect::<Result<Vec<_>, _>>()
    else {
        return Ok(());
    };
    for (index, &symbol) in lowering.coordinates.iter().enumerate() {
        let written = moving.iter().any(|s| s.uses_coordinate(index as u32));
        if written && !depends_on(&mut lowering.pool, &values, symbol) {
            return Err(motionless(mechanism, id, index, &named));
        }
    }
    Ok(())
}

/// E0704: a rotation axis of a dof chain that is zero with the values of its unknowns. A
/// written zero axis is refused where it is written (E0609), so these values came from
/// `given` or `--set`: the message names them.
fn zero_axis(
    mechanism: &Mechanism,
    axis: &[Scalar; 3],
    (link, join_span): (Span, Span),
    join: &str,
) -> Diagnostic {
    let mut ids = std::collections::BTreeSet::new();
    axis.iter().for_each(|s| s.collect_unknowns(&mut ids));
    let names: Vec<String> = ids
        .iter()
        .map(|&id| super::eval::unknown_label(mechanism, id))
        .collect();
    let mut diagnostic = Diagnostic::error(
        "E0704",
        format!("a rotation of join `{join}` has a zero axis"),
    )
    .primary(link, "in this link's dof chain")
    .secondary(join_span, "the join");
    if !names.is_empty() {
        diagnostic = diagnostic
            .note(format!(
                "the axis is zero with the values given to {}",
                names.join(", ")
            ))
            .help("give values that make the axis non-zero, with `given` or `--set NAME=VALUE`");
    }
    diagnostic
}

/// Whether any of `values` depends on `symbol`: a derivative that does not fold to zero.
fn depends_on(pool: &mut Pool, values: &[ExprId], symbol: ExprId) -> bool {
    let mut memo = std::collections::HashMap::new();
    values.iter().any(|&e| {
        let derivative = pool.derivative(e, symbol, &mut memo);
        !pool.is_zero(derivative)
    })
}

/// E0829 for coordinate `index` of join `id`, whose dof chain mentions the unknowns `named`.
fn motionless(
    mechanism: &Mechanism,
    id: JoinId,
    index: usize,
    named: &std::collections::BTreeSet<crate::elab::value::UnknownId>,
) -> Diagnostic {
    let join = mechanism.join(id);
    let link = mechanism.link(join.link);
    let names: Vec<String> = named
        .iter()
        .map(|&u| super::eval::unknown_label(mechanism, u))
        .collect();
    Diagnostic::error(
        "E0829",
        format!(
            "coordinate `{}` of join `{}` moves nothing",
            link.coordinates[index],
            mechanism.join_name(id)
        ),
    )
    .primary(link.span, "in this link's dof chain")
    .secondary(join.span, "the join")
    .note(format!(
        "its motion is zero with the values given to {}",
        names.join(", ")
    ))
    .help(
        "give values that make it move (a translation `q * axis` needs a non-zero axis), with \
         `given` or `--set NAME=VALUE`",
    )
}

/// A joint model of the link alone (frames at identity): enough to analyse the joint; a
/// rheonomic chain's parameters rewritten on their hidden coordinates (`rheonomic`).
pub fn link_only(
    mechanism: &Mechanism,
    id: JoinId,
    unknowns: &UnknownValues,
) -> Result<JointModel, Diagnostic> {
    let join = mechanism.join(id);
    let mut steps = link_steps(mechanism, id, unknowns)?;
    let mut coordinate_names: Vec<String> = mechanism
        .link(join.link)
        .coordinates
        .iter()
        .map(|c| c.to_string())
        .collect();
    let parameters = steps.iter_mut().flat_map(|step| match step {
        Step::Translation(v) => v.iter_mut().collect::<Vec<_>>(),
        Step::Rotation { angle, .. } => vec![angle],
    });
    let prescribed = rheonomic::rewrite(parameters, coordinate_names.len());
    for k in 1..=prescribed.len() {
        coordinate_names.push(rheonomic::hidden_name(&coordinate_names, k));
    }
    Ok(JointModel {
        join: id,
        name: mechanism.join_name(id),
        first_body: 0,
        second_body: 0,
        first: Pose::identity(),
        second: Pose::identity(),
        compiled: compile(&steps, coordinate_names.len(), unknowns),
        steps,
        coordinate_names,
        prescribed,
        offset: 0,
    })
}

pub fn constant_vector(
    v: &[Scalar; 3],
    unknowns: &UnknownValues,
) -> Result<Vector3<f64>, EvalError> {
    let value = |s: &Scalar| {
        eval(s, unknowns).map_err(|e| match e {
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
                let angle = eval(angle, unknowns)?;
                let norm = axis.norm();
                // A written zero axis is refused while evaluating (E0609); this one is zero by
                // the values of its unknowns, and a rotation about nothing has no value.
                if norm == 0.0 {
                    return Err(EvalError::NotFinite);
                }
                spatial::rotation(&(axis / norm), angle)
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
        EvalError::NotFinite => Diagnostic::error(
            "E0802",
            format!("the geometry of join `{join}` is not a finite number"),
        )
        .primary(span, "here")
        .help("check the join's frames and axes, and the `initial` values of its coordinates"),
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
    ) -> Result<Twist, EvalError> {
        let chain = self.compiled()?;
        let mut scratch = ChainScratch::default();
        chain.eval(q, Some(rates), &mut scratch);
        let n = self.coordinate_count();
        let mut pose = Pose::identity();
        let mut moved_frame = Twist::zeros();
        let mut derivative = Twist::zeros();
        let mut first = 0;
        for step in &self.steps {
            let along = |weights: &[f64], f: &dyn Fn(usize) -> f64| -> f64 {
                (0..n).map(|k| f(k) * weights[k]).sum()
            };
            let twist = |weights: &[f64], mixed: bool| {
                local_twist(step, |i| {
                    along(weights, &|k| match mixed {
                        false => chain.partial(&scratch, first + i, k),
                        true => chain.mixed(&scratch, first + i, k),
                    })
                })
            };
            let step_velocity = spatial::motion_to_parent(&pose, &twist(rates, false));
            derivative += cross(&moved_frame, &step_velocity)
                + spatial::motion_to_parent(&pose, &twist(direction, true));
            moved_frame += spatial::motion_to_parent(&pose, &twist(direction, false));
            pose *= step_transform(step, |i| chain.value(&scratch, first + i));
            first += parameter_count(step);
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
