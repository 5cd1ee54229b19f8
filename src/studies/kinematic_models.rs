//! The kinematic models of a mechanism at a configuration (`lsdc kinematics`): the Jacobian
//! from the actuated coordinates to a frame's motion (the direct velocity model, MCD), its
//! inverse (MCI, the Delta seed's α̇ = J·Ṗ), the acceleration terms at given rates (MAD and MAI:
//! the frame's acceleration when the actuators do not accelerate, and the seed's H·α̇), their
//! conditioning and the singularity the configuration is at, classified.
//!
//! The method (Gosselin & Angeles, "Singularity analysis of closed-loop kinematic chains", IEEE
//! Trans. Robotics and Automation 6(3), 1990, generalised to any loop structure): the motions the
//! loops allow are the null space N of the constraint Jacobian G (for a tree, every motion).
//! Among them, the idle ones move neither an actuated coordinate nor the frame (a rod spinning
//! between two ball joints) and are set aside: on an orthonormal basis W of the others, the
//! actuated rates are A·ξ and the frame's motion B·ξ. Then
//! - type 2 (direct, parallel) singularity: A loses rank, some motion moves the frame with the
//!   actuators locked;
//! - type 1 (inverse, serial) singularity: B loses rank, some motion moves the actuators with the
//!   frame held (for a tree: the frame's Jacobian loses rank);
//! - elsewhere the direct model is B·A⁺ and the inverse one A·B⁺.
//!
//! Every decision is taken in the mechanism's units: velocities of sliding coordinates and the
//! frame's linear velocity are divided by the mechanism's characteristic length L (that of
//! `loops::structure`), so that the same mechanism in millimetres decides alike.
//! The acceleration terms come from the loops' exact velocity-product term γ = Ġ v and the
//! bodies' bias accelerations (no differences).

use nalgebra::{DMatrix, DVector, Vector3};
use serde::Serialize;

use crate::dynamics::algorithms::Data;
use crate::dynamics::loops::{self, structure, Constraints, Extent};
use crate::dynamics::model::Model;
use crate::kinematics::eval::{EvalError, NOT_FINITE};
use crate::kinematics::frames::FramePoint;
use crate::prepare::Prepared;
use crate::spatial::{self, Motion};
use crate::studies::statics::{velocity_index, StaticsError};

/// A measure below this is a singular configuration (both measures are singular values of
/// dimensionless matrices, at most about 1: see `Singularity`).
pub const SINGULAR_TOLERANCE: f64 = 1e-6;

/// Relative size of a singular value counted as zero when the idle motions are set aside.
const RANK_TOLERANCE: f64 = 1e-9;

/// What part of a frame's motion the models map to.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum OutputKind {
    /// The velocity of the frame's origin (3 rows).
    Point,
    /// The frame's twist: angular velocity, then the velocity of its origin (6 rows).
    Twist,
}

/// The frame the models map to, and which part of its motion.
#[derive(Clone, Debug)]
pub struct Output {
    pub frame: FramePoint,
    pub kind: OutputKind,
}

impl Output {
    /// `frame.vx`, … for each row of the models.
    pub fn names(&self) -> Vec<String> {
        let components: &[&str] = match self.kind {
            OutputKind::Point => &["vx", "vy", "vz"],
            OutputKind::Twist => &["wx", "wy", "wz", "vx", "vy", "vz"],
        };
        (components.iter())
            .map(|c| format!("{}.{c}", self.frame.name))
            .collect()
    }

    pub(crate) fn rows(&self) -> usize {
        match self.kind {
            OutputKind::Point => 3,
            OutputKind::Twist => 6,
        }
    }

    /// Whether row r is a linear velocity (in metres per second).
    pub(crate) fn linear(&self, r: usize) -> bool {
        self.kind == OutputKind::Point || r >= 3
    }
}

/// The actuated (or named) coordinates: their names and their indices among the state's
/// velocities.
#[derive(Clone, Debug)]
pub struct Actuation {
    pub names: Vec<String>,
    pub velocities: Vec<usize>,
}

/// The coordinates `names` (`join.coordinate`); without any, every velocity of a tree (a
/// mechanism with loops needs them named).
pub fn actuation(prepared: &Prepared, names: &[String]) -> Result<Actuation, KinematicsError> {
    let model = &prepared.model;
    if names.is_empty() {
        if model.has_loops() {
            return Err(KinematicsError::ActuatedNeeded);
        }
        return Ok(Actuation {
            names: (0..model.nv).map(|v| model.velocity_name(v)).collect(),
            velocities: (0..model.nv).collect(),
        });
    }
    let velocities = names
        .iter()
        .map(|name| velocity_index(prepared, name))
        .collect::<Result<Vec<usize>, StaticsError>>()
        .map_err(KinematicsError::Coordinate)?;
    for (k, v) in velocities.iter().enumerate() {
        if velocities[..k].contains(v) {
            return Err(KinematicsError::Repeated(names[k].clone()));
        }
    }
    Ok(Actuation {
        names: names.to_vec(),
        velocities,
    })
}

/// A matrix as rows, for JSON.
pub type Rows = Vec<Vec<f64>>;

fn rows_of(m: &DMatrix<f64>) -> Rows {
    m.row_iter().map(|r| r.iter().copied().collect()).collect()
}

/// The kind of a singular configuration.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SingularKind {
    /// The inverse model loses rank: a motion of the actuators leaves the frame still (for a
    /// tree, the frame's Jacobian loses rank).
    Type1,
    /// The direct model loses rank: a motion of the frame with the actuators locked.
    Type2,
    /// Both at once.
    Both,
}

impl SingularKind {
    pub fn describe(self) -> &'static str {
        match self {
            SingularKind::Type1 => {
                "type 1 (inverse model singular: the actuators move, the frame does not)"
            }
            SingularKind::Type2 => {
                "type 2 (direct model singular: the frame moves, the actuators are locked)"
            }
            SingularKind::Both => "types 1 and 2 at once",
        }
    }
}

/// The motion a singular configuration lets through: the coordinates it moves (largest first)
/// and the loops whose rows those coordinates enter.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SingularMotion {
    pub coordinates: Vec<String>,
    /// Each coordinate's rate in that motion (unit norm in the mechanism's units).
    pub rates: Vec<f64>,
    pub loops: Vec<String>,
}

/// How close a configuration is to each type of singularity, and which one it is at.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Singularity {
    /// `None` away from singular configurations.
    pub kind: Option<SingularKind>,
    /// The smallest singular value of B, the frame's motion (its lengths divided by L) on an
    /// orthonormal basis of the non-idle motions (sliding rates divided by L): 0 at a type 1.
    /// The frame's points lie in the box of diagonal L, so it is at most about 1.
    pub type1_measure: f64,
    /// The smallest singular value of A, the actuated rates on that basis: 0 at a type 2, at
    /// most 1 (A is a block of an orthonormal matrix).
    pub type2_measure: f64,
    pub tolerance: f64,
    /// The motion of the actuators that leaves the frame still (at a type 1).
    pub type1_motion: Option<SingularMotion>,
    /// The motion of the frame with the actuators locked (at a type 2).
    pub type2_motion: Option<SingularMotion>,
    /// The motions of the smallest singular values of B and A, singular or not: what a
    /// passage between samples lets through (`singularities`).
    #[serde(skip)]
    pub weakest_motions: [Option<SingularMotion>; 2],
}

/// The kinematic models at one configuration.
#[derive(Clone, Debug, Serialize)]
pub struct KinematicModels {
    pub actuated: Vec<String>,
    pub outputs: Vec<String>,
    /// The mechanism's characteristic length L (metres): the unit of the measures' lengths.
    pub characteristic_length: f64,
    /// The motions the loops allow, and how many of them are idle (move neither the actuated
    /// coordinates nor the frame).
    pub motions: usize,
    pub idle_motions: usize,
    /// MCD: the frame's motion per unit actuated rate (outputs × actuated).
    pub direct: Rows,
    /// MCI: the actuated rates per unit motion of the frame (actuated × outputs).
    pub inverse: Rows,
    /// Condition numbers of the direct and inverse models made dimensionless by L (`None`:
    /// infinite, at a singular configuration).
    pub direct_condition: Option<f64>,
    pub inverse_condition: Option<f64>,
    /// The actuated rates the acceleration terms are taken at, and the frame's motion then.
    pub actuated_rates: Vec<f64>,
    pub output_rates: Vec<f64>,
    /// MAD: the frame's acceleration is `direct · ä + direct_acceleration_term`.
    pub direct_acceleration_term: Vec<f64>,
    /// MAI: the actuated accelerations are `inverse · ẍ + inverse_acceleration_term` (the Delta
    /// seed's H·α̇).
    pub inverse_acceleration_term: Vec<f64>,
    pub singularity: Singularity,
}

/// The models at the state positions `q`, the actuated coordinates moving at `actuated_rates`
/// (the other coordinates as the loops and the idle motions at rest make them).
pub fn models_at(
    model: &Model,
    actuation: &Actuation,
    output: &Output,
    q: &[f64],
    actuated_rates: &[f64],
    tolerance: f64,
) -> Result<KinematicModels, KinematicsError> {
    let MotionBasis {
        length,
        scales,
        allowed,
        basis,
        unit_rows,
        at_rest,
        a,
        b,
        a_svd,
        b_svd,
    } = motion_basis(model, actuation, output, q)?;
    let rows = output.rows();
    let n = model.velocities();
    let motions = basis.ncols();
    let type2_measure = kth(&a_svd.values, motions);
    let type1_measure = kth(&b_svd.values, motions.min(rows));
    let a_plus = pseudo_inverse(&a, &a_svd);
    let b_plus = pseudo_inverse(&b, &b_svd);
    let direct_scaled = &b * &a_plus;
    let inverse_scaled = &a * &b_plus;
    let actuated_scales: Vec<f64> = actuation.velocities.iter().map(|&v| scales[v]).collect();
    let direct = DMatrix::from_fn(rows, actuated_scales.len(), |r, c| {
        direct_scaled[(r, c)] * unit_rows[(r, 0)] / actuated_scales[c]
    });
    let inverse = DMatrix::from_fn(actuated_scales.len(), rows, |r, c| {
        inverse_scaled[(r, c)] * actuated_scales[r] / unit_rows[(c, 0)]
    });
    let singular_types = (type1_measure < tolerance, type2_measure < tolerance);
    let kind = match singular_types {
        (false, false) => None,
        (true, false) => Some(SingularKind::Type1),
        (false, true) => Some(SingularKind::Type2),
        (true, true) => Some(SingularKind::Both),
    };
    let name_motion = |xi: DVector<f64>| {
        let scaled = &basis * xi;
        singular_motion(model, &at_rest, &scaled)
    };
    let weakest_motions = [
        (motions > 0).then(|| name_motion(weakest(&b, &b_svd, motions))),
        (motions > 0).then(|| name_motion(weakest(&a, &a_svd, motions))),
    ];
    let type1_motion = weakest_motions[0].clone().filter(|_| singular_types.0);
    let type2_motion = weakest_motions[1].clone().filter(|_| singular_types.1);
    // The rates: the actuated ones given, the others as the allowed motions carry them.
    let actuated_scaled = DVector::from_iterator(
        actuated_rates.len(),
        (actuated_rates.iter().zip(&actuated_scales)).map(|(r, s)| r / s),
    );
    let v_scaled = &basis * (&a_plus * &actuated_scaled);
    let v: Vec<f64> = (0..n).map(|c| v_scaled[c] * scales[c]).collect();
    let (direct_term, inverse_term, output_rates) = acceleration_terms(
        model,
        output,
        q,
        &v,
        (&scales, length),
        (&direct, &inverse),
        actuation,
    )?;
    Ok(KinematicModels {
        actuated: actuation.names.clone(),
        outputs: output.names(),
        characteristic_length: length,
        motions: allowed.ncols(),
        idle_motions: allowed.ncols() - motions,
        direct: rows_of(&direct),
        inverse: rows_of(&inverse),
        direct_condition: condition(&direct_scaled),
        inverse_condition: condition(&inverse_scaled),
        actuated_rates: actuated_rates.to_vec(),
        output_rates,
        direct_acceleration_term: direct_term,
        inverse_acceleration_term: inverse_term,
        singularity: Singularity {
            kind,
            type1_measure,
            type2_measure,
            tolerance,
            type1_motion,
            type2_motion,
            weakest_motions,
        },
    })
}

/// The motions the loops allow at a configuration, in the mechanism's units (see the module's
/// comment): an orthonormal basis of the non-idle ones, and on it the actuated rates (A) and
/// the frame's motion (B), each with its singular value decomposition.
pub(crate) struct MotionBasis {
    /// The characteristic length L.
    pub length: f64,
    /// Per state velocity, what makes it dimensionless (L for a sliding one, 1 otherwise).
    pub scales: Vec<f64>,
    /// Every allowed motion, idle ones included (columns, dimensionless state velocities).
    pub allowed: DMatrix<f64>,
    /// The non-idle ones (columns, dimensionless state velocities).
    pub basis: DMatrix<f64>,
    /// Per row of the frame's motion, its unit (L for a linear velocity, 1 otherwise).
    pub unit_rows: DMatrix<f64>,
    pub at_rest: Constraints,
    pub a: DMatrix<f64>,
    pub b: DMatrix<f64>,
    pub a_svd: Singular,
    pub b_svd: Singular,
}

pub(crate) fn motion_basis(
    model: &Model,
    actuation: &Actuation,
    output: &Output,
    q: &[f64],
) -> Result<MotionBasis, KinematicsError> {
    let mut data = Data::new(model);
    let rest = vec![0.0; model.velocities()];
    let at_rest = loops::constraints(model, &mut data, q, &rest, Extent::Rows)?;
    let length = structure::characteristic_length(model, &data, &at_rest);
    let scales = velocity_scales(model, &data, &at_rest, length);
    let rows = output.rows();
    let point = frame_origin(&data, &output.frame);
    let g = dimensionless_rows(&at_rest.jacobian.dense(), length, &scales);
    let allowed = allowed_motions(model, &g);
    let n = model.velocities();
    let select = DMatrix::from_fn(actuation.velocities.len(), n, |r, c| {
        f64::from(u8::from(actuation.velocities[r] == c))
    });
    let frame_jacobian = frame_jacobian(model, &data, output, &point);
    let unit_rows = DMatrix::from_fn(rows, 1, |r, _| if output.linear(r) { length } else { 1.0 });
    let frame_scaled = DMatrix::from_fn(rows, n, |r, c| {
        frame_jacobian[(r, c)] * scales[c] / unit_rows[(r, 0)]
    });
    // Set the idle motions aside: keep the row space of [A; B] on the allowed motions.
    let on_allowed = {
        let mut stacked = DMatrix::zeros(select.nrows() + rows, allowed.ncols());
        stacked
            .rows_mut(0, select.nrows())
            .copy_from(&(&select * &allowed));
        stacked
            .rows_mut(select.nrows(), rows)
            .copy_from(&(&frame_scaled * &allowed));
        stacked
    };
    let kept = row_space(&on_allowed);
    let basis = &allowed * &kept;
    let a = &select * &basis;
    let b = &frame_scaled * &basis;
    let (a_svd, b_svd) = (singular(&a), singular(&b));
    Ok(MotionBasis {
        length,
        scales,
        allowed,
        basis,
        unit_rows,
        at_rest,
        a,
        b,
        a_svd,
        b_svd,
    })
}

/// The direct model's acceleration term, the inverse model's, and the frame's motion.
type AccelerationTerms = (Vec<f64>, Vec<f64>, Vec<f64>);

/// The acceleration terms of the direct and inverse models at rates `v` (state velocities on
/// the loops' allowed motions), and the frame's motion at those rates: they are what the
/// accelerations of [`SecondOrder`] make them when the actuated (direct) or the frame's
/// (inverse) accelerations vanish.
fn acceleration_terms(
    model: &Model,
    output: &Output,
    q: &[f64],
    v: &[f64],
    (scales, length): (&[f64], f64),
    (direct, inverse): (&DMatrix<f64>, &DMatrix<f64>),
    actuation: &Actuation,
) -> Result<AccelerationTerms, KinematicsError> {
    let second = second_order(model, output, q, v, scales, length)?;
    let actuated_part = DVector::from_iterator(
        actuation.velocities.len(),
        actuation.velocities.iter().map(|&c| second.particular[c]),
    );
    let direct_term = &second.frame - direct * &actuated_part;
    let inverse_term = &actuated_part - inverse * &second.frame;
    Ok((
        direct_term.iter().copied().collect(),
        inverse_term.iter().copied().collect(),
        second.output_rates,
    ))
}

/// The accelerations a motion at rates `v` needs to stay on the loops, at least: the loops'
/// acceleration rows G v̇ + γ = 0 give the least-norm v̇ₚ = −G⁺γ (any other differs by an
/// allowed motion), and the frame's acceleration is then J v̇ₚ + β (β from the bodies' bias
/// accelerations).
pub(crate) struct SecondOrder {
    /// v̇ₚ (state accelerations).
    pub particular: DVector<f64>,
    /// The frame's acceleration with v̇ₚ (classical: the acceleration of its origin).
    pub frame: DVector<f64>,
    /// The frame's motion at `v`.
    pub output_rates: Vec<f64>,
}

pub(crate) fn second_order(
    model: &Model,
    output: &Output,
    q: &[f64],
    v: &[f64],
    scales: &[f64],
    length: f64,
) -> Result<SecondOrder, KinematicsError> {
    let mut data = Data::new(model);
    let moving = loops::constraints(model, &mut data, q, v, Extent::WithBias)?;
    if !model.has_loops() {
        // Without loops `constraints` leaves the bodies' bias accelerations uncomputed.
        crate::dynamics::algorithms::bias_accelerations(model, &mut data);
    }
    let point = frame_origin(&data, &output.frame);
    let g = dimensionless_rows(&moving.jacobian.dense(), length, scales);
    let gamma = DVector::from_iterator(
        moving.bias.len(),
        (moving.bias.iter().enumerate()).map(|(r, x)| x * row_scale(r, length)),
    );
    let particular_scaled = -(loops::decompose(&g).pseudo_inverse * gamma);
    let particular = DVector::from_iterator(
        v.len(),
        (0..v.len()).map(|c| particular_scaled[c] * scales[c]),
    );
    let frame_jacobian = frame_jacobian(model, &data, output, &point);
    let body = output.frame.body;
    let world = |m: &Motion| spatial::motion_to_parent(&data.world[body], m);
    let velocity = spatial::shifted(&point, &world(&data.velocity[body]));
    let acceleration = spatial::shifted(&point, &world(&data.acceleration[body]));
    // The classical acceleration of the frame's origin: the spatial one at that point plus
    // ω × v (Featherstone, Rigid Body Dynamics Algorithms, 2008, §2.11).
    let omega = spatial::angular(&velocity);
    let classical = spatial::twist(
        spatial::angular(&acceleration),
        spatial::linear(&acceleration) + omega.cross(&spatial::linear(&velocity)),
    );
    let offset = 6 - output.rows();
    let bias_output = DVector::from_fn(output.rows(), |r, _| classical[offset + r]);
    let output_rates: Vec<f64> = (0..output.rows()).map(|r| velocity[offset + r]).collect();
    let frame = &frame_jacobian * &particular + bias_output;
    Ok(SecondOrder {
        particular,
        frame,
        output_rates,
    })
}

/// An orthonormal basis of the motions the loops allow (the null space of the dimensionless
/// G), without the complementary ball joints' own angles: they move nothing (the rows leave
/// them out, `loops::rows`) and are no motions of the mechanism.
fn allowed_motions(model: &Model, g: &DMatrix<f64>) -> DMatrix<f64> {
    let ball_angles = |c: usize| {
        (c >= model.nv)
            && (0..model.loops.len()).any(|k| {
                let start = model.nv + model.loop_offset(k);
                model.loop_balls[k].is_some() && (start..start + 3).contains(&c)
            })
    };
    let columns: Vec<usize> = (0..g.ncols()).filter(|&c| !ball_angles(c)).collect();
    let null = loops::decompose(&g.select_columns(&columns)).null_space;
    let mut allowed = DMatrix::zeros(g.ncols(), null.ncols());
    for (local, &c) in columns.iter().enumerate() {
        allowed.row_mut(c).copy_from(&null.row(local));
    }
    allowed
}

/// The frame's motion (point velocity or twist, in fixed axes, about its origin `point`) per
/// unit rate of each state velocity.
fn frame_jacobian(
    model: &Model,
    data: &Data,
    output: &Output,
    point: &Vector3<f64>,
) -> DMatrix<f64> {
    let rows = output.rows();
    let offset = 6 - rows;
    let mut jacobian = DMatrix::zeros(rows, model.velocities());
    for body in model.path_to_earth(output.frame.body) {
        let joint = &model.joints[body - 1];
        let state = &data.states[body - 1];
        for column in 0..joint.nv() {
            let local = Motion::from_column_slice(state.subspace.column(column).as_slice());
            let world = spatial::motion_to_parent(&data.world[joint.child], &local);
            let moved = spatial::shifted(point, &world);
            for r in 0..rows {
                jacobian[(r, joint.v_offset + column)] = moved[offset + r];
            }
        }
    }
    jacobian
}

/// Per state velocity, the factor that makes it dimensionless: L for a sliding motion (it turns
/// no body and no loop's rotation rows), 1 otherwise.
fn velocity_scales(model: &Model, data: &Data, c: &Constraints, length: f64) -> Vec<f64> {
    let mut turns = vec![false; model.velocities()];
    for (k, joint) in model.joints.iter().enumerate() {
        let state = &data.states[k];
        for column in 0..joint.nv() {
            let local = Motion::from_column_slice(state.subspace.column(column).as_slice());
            turns[joint.v_offset + column] = spatial::angular(&local) != Vector3::zeros();
        }
    }
    for block in &c.jacobian.blocks {
        for (local, &column) in block.columns.iter().enumerate() {
            if column >= model.nv && (0..3).any(|r| block.values[(r, local)] != 0.0) {
                turns[column] = true;
            }
        }
    }
    turns
        .iter()
        .map(|&t| if t { 1.0 } else { length })
        .collect()
}

/// The factor of a loop's row r: 1 for a rotation row, 1/L for a translation row.
fn row_scale(r: usize, length: f64) -> f64 {
    if r % 6 < 3 {
        1.0
    } else {
        1.0 / length
    }
}

/// G with dimensionless rows and columns.
fn dimensionless_rows(g: &DMatrix<f64>, length: f64, scales: &[f64]) -> DMatrix<f64> {
    DMatrix::from_fn(g.nrows(), g.ncols(), |r, c| {
        g[(r, c)] * row_scale(r, length) * scales[c]
    })
}

/// An orthonormal basis (columns) of the row space of `m`: its right singular vectors of the
/// singular values above the rank tolerance.
fn row_space(m: &DMatrix<f64>) -> DMatrix<f64> {
    let svd = singular(m);
    let largest = svd.values.first().copied().unwrap_or(0.0);
    let rank = (svd.values.iter())
        .take_while(|&&s| s > RANK_TOLERANCE * largest && s > 0.0)
        .count();
    svd.right.columns(0, rank).into_owned()
}

/// The origin of `frame` in the fixed frame, from the bodies' poses in `data`.
fn frame_origin(data: &Data, frame: &FramePoint) -> Vector3<f64> {
    (data.world[frame.body] * frame.offset).translation.vector
}

/// Singular values (largest first) and right singular vectors (columns, same order).
pub(crate) struct Singular {
    pub values: Vec<f64>,
    pub right: DMatrix<f64>,
    pub left: DMatrix<f64>,
}

pub(crate) fn singular(m: &DMatrix<f64>) -> Singular {
    let (rows, columns) = m.shape();
    let mut values = Vec::new();
    let (mut left, mut right) = (DMatrix::zeros(rows, 0), DMatrix::zeros(columns, 0));
    if rows > 0 && columns > 0 {
        if let Some(svd) = crate::linalg::svd(m.clone(), true, true) {
            let (u, v_t) = (svd.u.expect("asked for"), svd.v_t.expect("asked for"));
            let mut order: Vec<usize> = (0..svd.singular_values.len()).collect();
            order.sort_by(|&a, &b| svd.singular_values[b].total_cmp(&svd.singular_values[a]));
            values = order.iter().map(|&k| svd.singular_values[k]).collect();
            right = DMatrix::from_fn(columns, order.len(), |r, c| v_t[(order[c], r)]);
            left = DMatrix::from_fn(rows, order.len(), |r, c| u[(r, order[c])]);
        } else {
            values = vec![f64::NAN; rows.min(columns)];
        }
    }
    Singular {
        values,
        right,
        left,
    }
}

/// The k-th singular value (largest first; 0 when there are fewer than k, 1 for k = 0: a
/// mechanism without motions is singular in no way).
pub(crate) fn kth(values: &[f64], k: usize) -> f64 {
    match k {
        0 => 1.0,
        _ => values.get(k - 1).copied().unwrap_or(0.0),
    }
}

/// The right singular vector of `m`'s `motions`-th singular value, or, when `m` has fewer
/// singular values (fewer rows than motions), a vector of its null space.
fn weakest(m: &DMatrix<f64>, svd: &Singular, motions: usize) -> DVector<f64> {
    let k = motions.saturating_sub(1);
    if k < svd.values.len() {
        return svd.right.column(k).into_owned();
    }
    loops::decompose(m).null_space.column(0).into_owned()
}

/// The pseudo-inverse from the decomposition, singular values below the rank tolerance dropped.
fn pseudo_inverse(m: &DMatrix<f64>, svd: &Singular) -> DMatrix<f64> {
    let mut inverse = DMatrix::zeros(m.ncols(), m.nrows());
    let largest = svd.values.first().copied().unwrap_or(0.0);
    for (k, &s) in svd.values.iter().enumerate() {
        if s > RANK_TOLERANCE * largest && s > 0.0 {
            inverse += svd.right.column(k) * svd.left.column(k).transpose() / s;
        }
    }
    inverse
}

/// σ_max/σ_min over the smaller dimension; `None` when infinite.
fn condition(m: &DMatrix<f64>) -> Option<f64> {
    let svd = singular(m);
    let smallest = svd.values.get(m.nrows().min(m.ncols()).checked_sub(1)?)?;
    let value = svd.values[0] / smallest;
    (value.is_finite() && *smallest > RANK_TOLERANCE * svd.values[0]).then_some(value)
}

/// A singular motion (dimensionless state velocities) named: the coordinates it moves beyond a
/// hundredth of the largest, largest first, and the loops whose rows they enter.
pub(crate) fn singular_motion(
    model: &Model,
    c: &Constraints,
    scaled: &DVector<f64>,
) -> SingularMotion {
    let norm = scaled.norm();
    let largest = scaled.amax();
    let mut moved: Vec<usize> = (0..scaled.len())
        .filter(|&i| scaled[i].abs() > 1e-2 * largest)
        .collect();
    moved.sort_by(|&a, &b| scaled[b].abs().total_cmp(&scaled[a].abs()));
    let loops = (c.jacobian.blocks.iter().enumerate())
        .filter(|(_, block)| {
            moved.iter().any(|&i| {
                block
                    .columns
                    .binary_search(&i)
                    .is_ok_and(|local| (0..6).any(|r| block.values[(r, local)] != 0.0))
            })
        })
        .map(|(k, _)| model.loops[k].name.clone())
        .collect();
    SingularMotion {
        coordinates: moved.iter().map(|&i| model.velocity_name(i)).collect(),
        rates: moved.iter().map(|&i| scaled[i] / norm).collect(),
        loops,
    }
}

/// Why the models cannot be computed.
#[derive(Debug)]
pub enum KinematicsError {
    /// A mechanism with loops needs its actuated coordinates named.
    ActuatedNeeded,
    /// A coordinate named twice.
    Repeated(String),
    Coordinate(StaticsError),
    Evaluation(EvalError),
    /// A state of `--at` cannot be closed or read.
    State {
        index: usize,
        message: String,
    },
}

impl From<EvalError> for KinematicsError {
    fn from(error: EvalError) -> Self {
        KinematicsError::Evaluation(error)
    }
}

impl std::fmt::Display for KinematicsError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            KinematicsError::ActuatedNeeded => write!(
                f,
                "the mechanism has closed loops: name its actuated coordinates with `--actuate JOIN.COORDINATE`"
            ),
            KinematicsError::Repeated(name) => write!(f, "`{name}` is named twice"),
            KinematicsError::Coordinate(error) => write!(f, "{error}"),
            KinematicsError::Evaluation(EvalError::NotFinite) => {
                write!(f, "cannot evaluate the kinematics here: {NOT_FINITE}")
            }
            // A prepared program has a value for every unknown and a geometry of numbers.
            KinematicsError::Evaluation(error) => {
                write!(f, "cannot evaluate the kinematics here: {error:?}")
            }
            KinematicsError::State { index, message } => write!(f, "state {index}: {message}"),
        }
    }
}

impl std::error::Error for KinematicsError {}
