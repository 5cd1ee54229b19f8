//! The position drives of the dynamic model (`drive position(nacelle) = [x, y, z]`, resolved
//! and differentiated in `kinematics::position_drives`): each one three rows of the constraint
//! stack (`rows`), the velocity of the frame's origin along the fixed axes x, y, z, whose
//! right-hand sides follow the path p(t): φ = o(q) − p(t) (position), J v − ṗ(t) (velocity) and,
//! with J̇ v the acceleration of the origin at zero joint accelerations, γ = J̇ v − p̈(t), so that
//! J a + γ = 0 gives the origin the path's acceleration. The rows' multipliers λ are the force
//! applied at the origin, in the fixed axes, that imposes the path (J a = p̈ − J̇ v under
//! M a = f + Jᵀ λ): the drive's efforts `nacelle.drive_force.x`, `.y`, `.z`. The origin's
//! acceleration at zero joint accelerations is that of the material point of the body,
//! A(o) + ω × v(o) with A the body's spatial acceleration in the fixed axes (Featherstone,
//! *Rigid Body Dynamics Algorithms*, 2008, §2.11: the classical acceleration from the spatial
//! one).

use nalgebra::{DMatrix, DVector, Matrix3, Vector3};

use super::algorithms::{bias_accelerations, Data};
use super::contacts::{add_point_jacobian, at_point, world_bias, world_twist};
use super::model::Model;
use crate::kinematics::drives::LawAt;
use crate::kinematics::position_drives::{ResolvedPositionDrive, AXES};
use crate::spatial;

/// The names of a position drive's efforts among the outputs: `nacelle.drive_force.x`, …
pub fn force_names(drive: &ResolvedPositionDrive) -> [String; 3] {
    AXES.map(|axis| format!("{}.drive_force.{axis}", drive.frame.name))
}

/// The position drives' rows at a state: three per drive, along x, y, z.
#[derive(Clone, Debug, Default)]
pub struct PointRows {
    /// 3 per drive × nv: the velocity of the frame's origin.
    pub jacobian: DMatrix<f64>,
    /// γ = J̇ v − p̈(t) (zero unless asked for).
    pub bias: DVector<f64>,
    /// J v − ṗ(t).
    pub velocity: DVector<f64>,
    /// o(q) − p(t).
    pub position: DVector<f64>,
    /// Per drive, the path at the rows' time (the size of its position, for the round-off).
    pub laws: Vec<[LawAt; 3]>,
}

impl PointRows {
    /// Rows for the position drives of `model`, all zero.
    pub fn new(model: &Model) -> PointRows {
        let rows = 3 * model.position_drives.len();
        PointRows {
            jacobian: DMatrix::zeros(rows, model.velocities()),
            bias: DVector::zeros(rows),
            velocity: DVector::zeros(rows),
            position: DVector::zeros(rows),
            laws: Vec::with_capacity(model.position_drives.len()),
        }
    }

    /// The number of rows.
    pub fn len(&self) -> usize {
        self.bias.len()
    }

    // Asked of a public `len` (clippy's `len_without_is_empty`), used by no caller yet.
    #[cfg_attr(not(lsdc_internals), allow(dead_code))]
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// The position drives' rows at time `t` and the state whose forward kinematics `data` holds
/// (velocities `v`), into `rows` (made by `PointRows::new` for this model); γ when `with_bias`
/// (it overwrites `data.acceleration` with the bias accelerations). `values` is the laws'
/// evaluation storage.
pub fn point_rows_into(
    model: &Model,
    data: &mut Data,
    t: f64,
    v: &[f64],
    with_bias: bool,
    values: &mut Vec<f64>,
    rows: &mut PointRows,
) {
    rows.jacobian.fill(0.0);
    rows.bias.fill(0.0);
    rows.laws.clear();
    if model.position_drives.is_empty() {
        return;
    }
    if with_bias {
        bias_accelerations(model, data);
    }
    let identity = Matrix3::identity();
    for (k, drive) in model.position_drives.iter().enumerate() {
        let body = drive.frame.body;
        let origin = (data.world[body] * drive.frame.offset).translation.vector;
        let laws = [0, 1, 2].map(|axis| drive.laws[axis].evaluate(t, values));
        add_point_jacobian(
            model,
            data,
            body,
            &origin,
            &identity,
            1.0,
            3 * k,
            &mut rows.jacobian,
        );
        if with_bias {
            let twist = world_twist(data, body);
            let rate = at_point(&origin, &twist);
            let material =
                at_point(&origin, &world_bias(data, body)) + spatial::angular(&twist).cross(&rate);
            for axis in 0..3 {
                rows.bias[3 * k + axis] = material[axis] - laws[axis].acceleration;
            }
        }
        for (axis, law) in laws.iter().enumerate() {
            rows.position[3 * k + axis] = origin[axis] - law.position;
        }
        rows.laws.push(laws);
    }
    let v = nalgebra::DVectorView::from_slice(v, v.len());
    rows.velocity.gemv(1.0, &rows.jacobian, &v, 0.0);
    let rates = rows.laws.iter().flatten().map(|law| law.rate);
    for (velocity, rate) in rows.velocity.iter_mut().zip(rates) {
        *velocity -= rate;
    }
}

/// Adds the position drives' forces `forces` (three per drive, along x, y, z, as
/// `RowStack::point_forces` gives them) to the forces on the bodies `on_bodies` (in each body's
/// frame, as the efforts' external forces are): each force acts on its frame's body at the
/// frame's origin; `data` holds the forward kinematics.
pub fn add_body_forces(
    model: &Model,
    data: &Data,
    forces: &[f64],
    on_bodies: &mut [spatial::Force],
) {
    for (k, drive) in model.position_drives.iter().enumerate() {
        let body = drive.frame.body;
        if body == 0 {
            continue;
        }
        let origin = (data.world[body] * drive.frame.offset).translation.vector;
        let force = Vector3::new(forces[3 * k], forces[3 * k + 1], forces[3 * k + 2]);
        let at_point = spatial::twist(Vector3::zeros(), force);
        let about_origin = spatial::force_to_parent(&spatial::translation(origin), &at_point);
        on_bodies[body] += spatial::force_to_child(&data.world[body], &about_origin);
    }
}
