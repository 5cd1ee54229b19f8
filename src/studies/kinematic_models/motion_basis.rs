//! The motions the loops allow at a configuration, in the mechanism's units: an orthonormal
//! basis of the non-idle ones (the idle ones, a rod spinning between two ball joints, set
//! aside), and on it the actuated rates (A) and the frame's motion (B) with their singular
//! value decompositions; the scalings that make velocities and loop rows dimensionless.

use nalgebra::{DMatrix, Vector3};

use super::error::KinematicsError;
use super::output::{Actuation, Output};
use super::singular_values::{singular, Singular, RANK_TOLERANCE};
use crate::dynamics::algorithms::Data;
use crate::dynamics::loops::{self, structure, Constraints, Extent};
use crate::dynamics::model::Model;
use crate::kinematics::frames::FramePoint;
use crate::spatial::{self, Motion};

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
pub(super) fn frame_jacobian(
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
pub(super) fn row_scale(r: usize, length: f64) -> f64 {
    if r % 6 < 3 {
        1.0
    } else {
        1.0 / length
    }
}

/// G with dimensionless rows and columns.
pub(super) fn dimensionless_rows(g: &DMatrix<f64>, length: f64, scales: &[f64]) -> DMatrix<f64> {
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
pub(super) fn frame_origin(data: &Data, frame: &FramePoint) -> Vector3<f64> {
    (data.world[frame.body] * frame.offset).translation.vector
}
