//! Contacts of a round body on a plane (`join plane and ball with rolling(r)` or
//! `sliding(r, f)`, `rolling_disc(r)` or `sliding_disc(r, f)` for a disc): constraints on the
//! tree's motion written on velocities, not joints.
//!
//! The plane passes through its frame's origin O, normal to the frame's z axis n (pointing
//! towards the round body); the round body is a sphere of radius r about its frame's origin C
//! (or a cylinder whose axis stays parallel to the plane), touching at p = C − r n, or a thin
//! disc touching at the lowest point of its rim (`ContactModel::touch`). Each contact has
//! three candidate rows, the relative velocity of the two bodies' material points at p along
//! the plane frame's axes x, y (tangential) and z (normal):
//!
//! - the normal row is the rate of the gap g (g = (C − O)·n − r for a sphere; for a disc,
//!   (C − O)·n − r s, which the rim's lowest point makes the normal velocity there too), a
//!   holonomic constraint: it is kept at the position level too (projected after every step);
//! - the tangential rows of a rolling contact say that the body rolls without slipping. They
//!   are non-holonomic (a ball on a plane can reach any position with any orientation): they
//!   hold on velocities and accelerations only, and nothing projects positions onto them;
//! - a sliding contact keeps its normal row only; the friction force −f|λₙ| s on the round body
//!   opposes the slip velocity w (Coulomb), with the regularised direction
//!   s = w / √(|w|² + ε²) (`SLIP_REGULARISATION`).
//!
//! With G the kept rows (solved with the mechanism's other rows, `rows`), the equations of
//! motion are M a = f + Hᵀλ, G a + γ = 0, where H = G
//! but on a sliding contact's normal row, whose force also carries the friction it causes:
//! H = Gₙ − f σ sᵀ Gₜ with σ the sign of λₙ. γ is the rows' velocity-product term: with V
//! the bodies' twists in fixed axes and A their accelerations at zero joint accelerations,
//! d/dt [e·(V_B − V_P)(p)] = (ω_P × e)·w + e·[(A_B − A_P)(p) + (ω_B − ω_P) × ṗ],
//! where ṗ, the rate of the contact point as it moves over both bodies, is v_C − r ω_P × n for
//! a sphere and v_C − r u̇ for a disc (`ContactModel::down_rate`).

use nalgebra::{DMatrix, DVector, DVectorView, Matrix3, Vector3};

use super::algorithms::{bias_accelerations, Data};
use super::model::Model;
use super::response::Response;
pub use crate::kinematics::contacts::{ContactModel, Touch, SLIP_REGULARISATION};
use crate::spatial::{self, Motion};

/// Names of a contact's three rows.
pub const CONTACT_ROW_NAMES: [&str; 3] = ["slip along x", "slip along y", "normal"];

/// The contacts' rows at a state: three per contact, every row computed (the kept ones are
/// chosen by the caller); empty by default.
#[derive(Clone, Debug, Default)]
pub struct ContactRows {
    /// 3 per contact × nv: the relative velocity at the contact point along the plane's axes.
    pub jacobian: DMatrix<f64>,
    /// γ, the rows' velocity-product term (zero unless asked for).
    pub bias: DVector<f64>,
    /// G v.
    pub velocity: DVector<f64>,
    /// Per contact, the gap g = (C − O)·n − r (a position row).
    pub gap: Vec<f64>,
    /// Per contact, the contact point and the plane's axes (columns x, y, n), fixed axes.
    pub points: Vec<Vector3<f64>>,
    pub axes: Vec<Matrix3<f64>>,
    /// Per contact, the direction from the centre to the contact point at the last state these
    /// rows were computed at (zero before the first).
    downs: Vec<Vector3<f64>>,
    /// The first contact whose disc lies flat at this state, or passed lying flat since the
    /// rows were last computed (`DISC_FLAT`): it has no contact point.
    pub flat_disc: Option<usize>,
}

/// A disc whose tilt from lying flat has a sine below this lies flat: its lowest point turns
/// by r/s per unit of tilt. A disc that passed lying flat between two states is caught by its
/// contact point's direction turning by more than 120° (the cosine below −1/2) between them:
/// the lowest point jumps across the rim there.
pub const DISC_FLAT: f64 = 1e-9;

/// The fixed-frame twist of a body (index 0: earth, at rest).
pub(super) fn world_twist(data: &Data, body: usize) -> Motion {
    if body == 0 {
        return Motion::zeros();
    }
    spatial::motion_to_parent(&data.world[body], &data.velocity[body])
}

/// The fixed-frame acceleration of a body at zero joint accelerations (after
/// `bias_accelerations`).
pub(super) fn world_bias(data: &Data, body: usize) -> Motion {
    if body == 0 {
        return Motion::zeros();
    }
    spatial::motion_to_parent(&data.world[body], &data.acceleration[body])
}

/// Velocity at `point` of a fixed-frame twist.
pub(super) fn at_point(point: &Vector3<f64>, twist: &Motion) -> Vector3<f64> {
    spatial::linear(&spatial::shifted(point, twist))
}

impl ContactRows {
    /// Rows for the contacts of `model`, all zero.
    pub fn new(model: &Model) -> ContactRows {
        let count = model.contacts.len();
        ContactRows {
            jacobian: DMatrix::zeros(3 * count, model.velocities()),
            bias: DVector::zeros(3 * count),
            velocity: DVector::zeros(3 * count),
            gap: vec![0.0; count],
            points: vec![Vector3::zeros(); count],
            axes: vec![Matrix3::identity(); count],
            downs: vec![Vector3::zeros(); count],
            flat_disc: None,
        }
    }
}

/// The contacts' rows at the state whose forward kinematics `data` holds; γ when `with_bias`
/// (it overwrites `data.acceleration` with the bias accelerations).
pub fn contact_rows(model: &Model, data: &mut Data, v: &[f64], with_bias: bool) -> ContactRows {
    let mut rows = ContactRows::new(model);
    contact_rows_into(model, data, v, with_bias, &mut rows);
    rows
}

/// `contact_rows` written into `rows` (made by `ContactRows::new` for this model), without
/// allocating.
pub fn contact_rows_into(
    model: &Model,
    data: &mut Data,
    v: &[f64],
    with_bias: bool,
    rows: &mut ContactRows,
) {
    rows.jacobian.fill(0.0);
    rows.bias.fill(0.0);
    if with_bias {
        bias_accelerations(model, data);
    }
    rows.flat_disc = None;
    for (k, contact) in model.contacts.iter().enumerate() {
        let world = &data.world;
        let touch = contact.touch(&world[contact.plane_body], &world[contact.round_body]);
        let passed_flat = touch.disc.is_some() && rows.downs[k].dot(&touch.down) < -0.5;
        let lies_flat = touch
            .disc
            .is_some_and(|(_, sine)| sine.is_nan() || sine <= DISC_FLAT);
        if (passed_flat || lies_flat) && rows.flat_disc.is_none() {
            rows.flat_disc = Some(k);
        }
        rows.downs[k] = touch.down;
        rows.gap[k] = touch.gap;
        rows.points[k] = touch.point;
        rows.axes[k] = touch.axes;
        fill_jacobian(
            model,
            data,
            contact,
            &touch.point,
            &touch.axes,
            3 * k,
            &mut rows.jacobian,
        );
        if with_bias {
            let bias = contact_bias(data, contact, &touch);
            rows.bias.rows_mut(3 * k, 3).copy_from(&bias);
        }
    }
    let v = DVectorView::from_slice(v, v.len());
    rows.velocity.gemv(1.0, &rows.jacobian, &v, 0.0);
}

/// The three rows of a contact: the velocity at `point` that each state velocity gives the
/// round body, less the one it gives the plane's body, along the plane's axes.
fn fill_jacobian(
    model: &Model,
    data: &Data,
    contact: &ContactModel,
    point: &Vector3<f64>,
    axes: &Matrix3<f64>,
    row: usize,
    jacobian: &mut DMatrix<f64>,
) {
    for (body, sign) in [(contact.round_body, 1.0), (contact.plane_body, -1.0)] {
        add_point_jacobian(model, data, body, point, axes, sign, row, jacobian);
    }
}

/// Adds to the rows `row`, `row + 1`, `row + 2` of `jacobian` `sign` times the velocity that
/// each state velocity gives the material point of `body` at `point` (fixed axes), along the
/// columns of `axes`; `data` holds the forward kinematics.
#[allow(clippy::too_many_arguments)]
pub(super) fn add_point_jacobian(
    model: &Model,
    data: &Data,
    body: usize,
    point: &Vector3<f64>,
    axes: &Matrix3<f64>,
    sign: f64,
    row: usize,
    jacobian: &mut DMatrix<f64>,
) {
    for on_path in model.path_to_earth(body) {
        let joint = &model.joints[on_path - 1];
        let state = &data.states[on_path - 1];
        for column in 0..joint.nv() {
            let local = Motion::from_column_slice(state.subspace.column(column).as_slice());
            let twist = spatial::motion_to_parent(&data.world[joint.child], &local);
            let along = axes.transpose() * at_point(point, &twist);
            let mut entries = jacobian.view_mut((row, joint.v_offset + column), (3, 1));
            entries += sign * along;
        }
    }
}

/// γ of a contact's three rows (see the module's documentation).
fn contact_bias(data: &Data, contact: &ContactModel, touch: &Touch) -> Vector3<f64> {
    let (round, plane) = (
        world_twist(data, contact.round_body),
        world_twist(data, contact.plane_body),
    );
    let (spin_round, spin_plane) = (spatial::angular(&round), spatial::angular(&plane));
    let point = &touch.point;
    let relative = at_point(point, &(round - plane));
    let down_rate = contact.down_rate(touch, &spin_round, &spin_plane);
    let point_rate = at_point(&touch.centre, &round) + contact.radius * down_rate;
    let accelerations = world_bias(data, contact.round_body) - world_bias(data, contact.plane_body);
    let material = at_point(point, &accelerations) + (spin_round - spin_plane).cross(&point_rate);
    Vector3::from_fn(|i, _| {
        let axis = touch.axes.column(i).into_owned();
        spin_plane.cross(&axis).dot(&relative) + axis.dot(&material)
    })
}

/// The regularised direction of Coulomb friction for a slip velocity (see
/// `SLIP_REGULARISATION`), in the plane's axes x, y.
pub fn friction_direction(rows: &ContactRows, k: usize) -> [f64; 2] {
    let (x, y) = (rows.velocity[3 * k], rows.velocity[3 * k + 1]);
    let scale = (x * x + y * y + SLIP_REGULARISATION * SLIP_REGULARISATION).sqrt();
    [x / scale, y / scale]
}

/// The relative size below which a row is taken as dependent on the rows chosen before it.
pub const CONTACT_RANK_TOLERANCE: f64 = 1e-10;

/// The independent rows among the contacts' candidate rows (`ContactModel::rows`), in contact
/// order, for accelerations that respond to forces through `response` (X, formed at the state:
/// M⁻¹ on a tree, with the couplings or the loops' allowed motions otherwise): a Cholesky
/// factorisation of G X Gᵀ pivoted on its diagonal, whose entries all have the units of an
/// inverse mass, stops where the largest pivot left falls below `CONTACT_RANK_TOLERANCE` times
/// the largest diagonal entry. A cylinder rolling in a plane motion has a tangential row along
/// its axis that is zero at every state, and a row the loops already keep is zero on X: they
/// are left out.
pub fn independent_rows(model: &Model, response: &mut Response, rows: &ContactRows) -> Vec<usize> {
    let candidates = candidate_rows(model);
    let gt = rows.jacobian.select_rows(&candidates).transpose();
    let mut moved = gt.clone();
    response.apply(&gt, &mut moved);
    let normal = gt.transpose() * moved;
    choose_independent(&candidates, normal)
}

/// The candidate rows a Cholesky factorisation of their normal matrix `normal` pivoted on its
/// diagonal takes before its largest pivot left falls below `CONTACT_RANK_TOLERANCE` times
/// the largest diagonal entry.
fn choose_independent(candidates: &[usize], mut normal: DMatrix<f64>) -> Vec<usize> {
    let scale = normal.diagonal().max();
    let mut chosen = Vec::new();
    let mut left: Vec<usize> = (0..candidates.len()).collect();
    while let Some((position, &pivot)) = (left.iter().enumerate())
        .max_by(|a, b| normal[(*a.1, *a.1)].total_cmp(&normal[(*b.1, *b.1)]))
    {
        let size = normal[(pivot, pivot)];
        // A NaN pivot stops the choice too.
        if size.is_nan() || size <= CONTACT_RANK_TOLERANCE * scale {
            break;
        }
        left.remove(position);
        chosen.push(pivot);
        let column = normal.column(pivot).into_owned();
        for &i in &left {
            for &j in &left {
                normal[(i, j)] -= column[i] * column[j] / size;
            }
        }
    }
    chosen.sort_unstable();
    chosen.into_iter().map(|i| candidates[i]).collect()
}

/// Every contact's candidate rows (`ContactModel::rows`), in contact order.
pub fn candidate_rows(model: &Model) -> Vec<usize> {
    (model.contacts.iter().enumerate())
        .flat_map(|(k, c)| c.rows().iter().map(move |r| 3 * k + r))
        .collect()
}

/// Hᵀ for the stacked contact rows `stacked` (the first columns of `directions`, which holds
/// Gᵀ): a sliding contact's normal row also carries the friction its normal force causes,
/// −f σ (sₓ Gₓ + s_y G_y), with σ = `pressing` (±1) the normal force's sign.
pub fn sliding_directions(
    model: &Model,
    rows: &ContactRows,
    stacked: &[usize],
    directions: &mut DMatrix<f64>,
    pressing: &[f64],
) {
    for (i, &row) in stacked.iter().enumerate() {
        let k = row / 3;
        let Some(friction) = model.contacts[k].friction else {
            continue;
        };
        let [sx, sy] = friction_direction(rows, k);
        let scale = friction * pressing[k];
        for j in 0..directions.nrows() {
            let tangential = rows.jacobian[(3 * k, j)] * sx + rows.jacobian[(3 * k + 1, j)] * sy;
            directions[(j, i)] -= scale * tangential;
        }
    }
}

/// Each contact's force on its round body, in the plane's axes, from the multipliers of the
/// stacked contact rows `stacked`.
pub fn contact_forces(
    model: &Model,
    rows: &ContactRows,
    stacked: &[usize],
    multipliers: &[f64],
    forces: &mut [Vector3<f64>],
) {
    forces.fill(Vector3::zeros());
    for (&row, &lambda) in stacked.iter().zip(multipliers) {
        forces[row / 3][row % 3] = lambda;
    }
    for (k, contact) in model.contacts.iter().enumerate() {
        if let Some(friction) = contact.friction {
            let [sx, sy] = friction_direction(rows, k);
            let normal = forces[k].z.abs();
            forces[k].x = -friction * normal * sx;
            forces[k].y = -friction * normal * sy;
        }
    }
}

/// Flips the assumed sign of every sliding contact's normal force that came out the other
/// way; whether any did.
pub fn flip_pulling(model: &Model, forces: &[Vector3<f64>], pressing: &mut [f64]) -> bool {
    let mut flipped = false;
    for (k, contact) in model.contacts.iter().enumerate() {
        if contact.friction.is_some() && forces[k].z * pressing[k] < 0.0 {
            pressing[k] = -pressing[k];
            flipped = true;
        }
    }
    flipped
}

/// The contact forces as forces on the bodies (in their frames, about their origins): each
/// contact's force on its round body at the contact point, its opposite on the plane's body.
pub fn contact_body_forces(
    model: &Model,
    data: &Data,
    rows: &ContactRows,
    forces: &[Vector3<f64>],
) -> Vec<spatial::Force> {
    let mut on_bodies = vec![spatial::Force::zeros(); model.body_count() + 1];
    for (k, contact) in model.contacts.iter().enumerate() {
        let force = rows.axes[k] * forces[k];
        let at_point = spatial::twist(Vector3::zeros(), force);
        let about_origin =
            spatial::force_to_parent(&spatial::translation(rows.points[k]), &at_point);
        for (body, sign) in [(contact.round_body, 1.0), (contact.plane_body, -1.0)] {
            if body != 0 {
                on_bodies[body] += sign * spatial::force_to_child(&data.world[body], &about_origin);
            }
        }
    }
    on_bodies
}

/// The contacts' reactions as the outputs give them, six per contact: a contact transmits no
/// moment about its point, then its force along the plane's axes.
pub fn contact_reactions(forces: &[Vector3<f64>]) -> DVector<f64> {
    let flat = forces.iter().flat_map(|f| [0.0, 0.0, 0.0, f.x, f.y, f.z]);
    DVector::from_iterator(6 * forces.len(), flat)
}

/// The power of the sliding contacts' friction forces on the slip velocities (≤ 0): the rate
/// of the work the energy balance counts.
pub fn friction_power(model: &Model, rows: &ContactRows, forces: &[Vector3<f64>]) -> f64 {
    (model.contacts.iter().enumerate())
        .filter(|(_, c)| c.friction.is_some())
        .map(|(k, _)| forces[k].x * rows.velocity[3 * k] + forces[k].y * rows.velocity[3 * k + 1])
        .sum()
}
