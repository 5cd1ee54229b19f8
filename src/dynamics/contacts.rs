//! Contacts of a round body on a plane (`join plane and ball with rolling(r)` or
//! `sliding(r, f)`): constraints on the tree's motion written on velocities, not joints.
//!
//! The plane passes through its frame's origin O, normal to the frame's z axis n (pointing
//! towards the round body); the round body is a sphere of radius r about its frame's origin C,
//! or a cylinder whose axis stays parallel to the plane. The contact point is p = C − r n. Each
//! contact has three candidate rows, the relative velocity of the two bodies' material points at
//! p along the plane frame's axes x, y (tangential) and z (normal):
//!
//! - the normal row is the rate of the gap g = (C − O)·n − r, a holonomic constraint: it is
//!   kept at the position level too (projected after every step);
//! - the tangential rows of a rolling contact say that the body rolls without slipping. They
//!   are non-holonomic (a ball on a plane can reach any position with any orientation): they
//!   hold on velocities and accelerations only, and nothing projects positions onto them;
//! - a sliding contact keeps its normal row only; the friction force −f|λₙ| s on the round body
//!   opposes the slip velocity w (Coulomb), with the regularised direction
//!   s = w / √(|w|² + ε²) (`SLIP_REGULARISATION`).
//!
//! With G the kept rows, the equations of motion are M a = f + Hᵀλ, G a + γ = 0, where H = G
//! but on a sliding contact's normal row, whose force also carries the friction it causes:
//! H = Gₙ − f σ sᵀ Gₜ with σ the sign of λₙ. γ is the rows' velocity-product term: with V
//! the bodies' twists in fixed axes and A their accelerations at zero joint accelerations,
//! d/dt [e·(V_B − V_P)(p)] = (ω_P × e)·w + e·[(A_B − A_P)(p) + (ω_B − ω_P) × ṗ],
//! ṗ = v_C − r ω_P × n (the contact point moves over both bodies).

use nalgebra::{DMatrix, DVector, DVectorView, DVectorViewMut, Matrix3, Vector3};

use super::algorithms::{bias_accelerations, Data};
use super::dense::{solve_in_place, Factor};
use super::model::Model;
pub use crate::kinematics::contacts::{ContactModel, SLIP_REGULARISATION};
use crate::spatial::{self, Motion};

/// Names of a contact's three rows.
pub const CONTACT_ROW_NAMES: [&str; 3] = ["slip along x", "slip along y", "normal"];

/// The contacts' rows at a state: three per contact, every row computed (the kept ones are
/// chosen by the caller).
#[derive(Clone, Debug)]
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
}

/// The fixed-frame twist of a body (index 0: earth, at rest).
fn world_twist(data: &Data, body: usize) -> Motion {
    if body == 0 {
        return Motion::zeros();
    }
    spatial::motion_to_parent(&data.world[body], &data.velocity[body])
}

/// The fixed-frame acceleration of a body at zero joint accelerations (after
/// `bias_accelerations`).
fn world_bias(data: &Data, body: usize) -> Motion {
    if body == 0 {
        return Motion::zeros();
    }
    spatial::motion_to_parent(&data.world[body], &data.acceleration[body])
}

/// Velocity at `point` of a fixed-frame twist.
fn at_point(point: &Vector3<f64>, twist: &Motion) -> Vector3<f64> {
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
    for (k, contact) in model.contacts.iter().enumerate() {
        let plane = data.world[contact.plane_body] * contact.plane;
        let centre = (data.world[contact.round_body] * contact.centre)
            .translation
            .vector;
        let axes = plane.rotation.to_rotation_matrix().into_inner();
        let normal = axes.column(2).into_owned();
        let point = centre - contact.radius * normal;
        rows.gap[k] = (centre - plane.translation.vector).dot(&normal) - contact.radius;
        rows.points[k] = point;
        rows.axes[k] = axes;
        fill_jacobian(
            model,
            data,
            contact,
            &point,
            &axes,
            3 * k,
            &mut rows.jacobian,
        );
        if with_bias {
            let bias = contact_bias(data, contact, &centre, &point, &axes);
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
}

/// γ of a contact's three rows (see the module's documentation).
fn contact_bias(
    data: &Data,
    contact: &ContactModel,
    centre: &Vector3<f64>,
    point: &Vector3<f64>,
    axes: &Matrix3<f64>,
) -> Vector3<f64> {
    let (round, plane) = (
        world_twist(data, contact.round_body),
        world_twist(data, contact.plane_body),
    );
    let (spin_round, spin_plane) = (spatial::angular(&round), spatial::angular(&plane));
    let normal = axes.column(2).into_owned();
    let relative = at_point(point, &(round - plane));
    let point_rate = at_point(centre, &round) - contact.radius * spin_plane.cross(&normal);
    let accelerations = world_bias(data, contact.round_body) - world_bias(data, contact.plane_body);
    let material = at_point(point, &accelerations) + (spin_round - spin_plane).cross(&point_rate);
    Vector3::from_fn(|i, _| {
        let axis = axes.column(i).into_owned();
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
/// order: a Cholesky factorisation of G M⁻¹ Gᵀ pivoted on its diagonal, whose entries all have
/// the units of an inverse mass, stops where the largest pivot left falls below
/// `CONTACT_RANK_TOLERANCE` times the largest diagonal entry. A cylinder rolling in a plane
/// motion has a tangential row along its axis that is zero at every state: it is left out.
pub fn independent_rows(model: &Model, mass: &DMatrix<f64>, rows: &ContactRows) -> Vec<usize> {
    let candidates = candidate_rows(model);
    let Some(cholesky) = mass.clone().cholesky() else {
        return candidates;
    };
    let g = rows.jacobian.select_rows(&candidates);
    let normal = &g * cholesky.solve(&g.transpose());
    choose_independent(&candidates, normal)
}

/// [`independent_rows`] on a mechanism with loops, whose accelerations respond to forces
/// through `response` (P, `loops::constrained_response`) rather than M⁻¹: a contact row the
/// loops already keep is left out.
pub fn independent_rows_on(
    model: &Model,
    response: &DMatrix<f64>,
    rows: &ContactRows,
) -> Vec<usize> {
    let candidates = candidate_rows(model);
    let g = rows.jacobian.select_rows(&candidates);
    let normal = &g * response * g.transpose();
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

/// The holonomic rows among `kept`: the normal rows, which positions are projected onto.
pub fn holonomic_rows(kept: &[usize]) -> Vec<usize> {
    kept.iter().copied().filter(|r| r % 3 == 2).collect()
}

/// The solution of the constrained equations of motion at a state.
#[derive(Clone, Debug)]
pub struct ContactSolution {
    pub accelerations: DVector<f64>,
    /// Per contact, the force on the round body at the contact point along the plane's axes
    /// (x, y tangential, z normal): the reaction of the plane, friction included.
    pub forces: Vec<Vector3<f64>>,
}

/// Why the constrained equations have no solution.
#[derive(Clone, Debug, PartialEq)]
pub enum ContactError {
    /// The mass matrix is not positive definite.
    SingularMass,
    /// The kept rows stopped being independent (the contact `row` names).
    Singular { row: usize },
}

/// What a solve on some of the contacts' rows forms: G (those rows), the rows H their forces act
/// along, M⁻¹Hᵀ, G M⁻¹Hᵀ, and the right-hand side (the multipliers once solved), sized once for
/// the rows.
#[derive(Clone, Debug)]
struct RowSystem {
    rows: Vec<usize>,
    g: DMatrix<f64>,
    h: DMatrix<f64>,
    moved: DMatrix<f64>,
    coupling: DMatrix<f64>,
    right: DVector<f64>,
}

impl RowSystem {
    fn new(rows: Vec<usize>, velocities: usize) -> RowSystem {
        let n = rows.len();
        RowSystem {
            rows,
            g: DMatrix::zeros(n, velocities),
            h: DMatrix::zeros(n, velocities),
            moved: DMatrix::zeros(velocities, n),
            coupling: DMatrix::zeros(n, n),
            right: DVector::zeros(n),
        }
    }

    /// G, and H = G (the forces of ideal contacts), from every contact row.
    fn gather(&mut self, all: &ContactRows) {
        for (i, &row) in self.rows.iter().enumerate() {
            self.g.row_mut(i).copy_from(&all.jacobian.row(row));
        }
        self.h.copy_from(&self.g);
    }

    /// M⁻¹Hᵀ and G M⁻¹Hᵀ, `factor` holding M's factorisation; with loops, P Hᵀ and G P Hᵀ
    /// for their `response` P in place of M⁻¹.
    fn couple(&mut self, factor: &Factor, response: Option<&DMatrix<f64>>) {
        match response {
            Some(response) => self.moved.gemm(1.0, response, &self.h.transpose(), 0.0),
            None => {
                self.moved.tr_copy_from(&self.h);
                factor.solve_mut(&mut self.moved);
            }
        }
        self.coupling.gemm(1.0, &self.g, &self.moved, 0.0);
    }

    /// The multipliers (G M⁻¹Hᵀ)⁻¹ r of the right-hand side r, left in its place; Err names a
    /// row that depends on the others.
    fn multipliers(&mut self) -> Result<(), usize> {
        solve_in_place(&mut self.coupling, &mut self.right).map_err(|k| self.rows[k])
    }
}

/// Everything the contacts' equations and projections use at each evaluation, kept so that
/// they allocate nothing once the run's rows are chosen (`ContactScratch::keep`): the rows,
/// the mass matrix (for `crba_after_kinematics` to fill) and its factor, the solves on the
/// kept rows and on their normal rows, and the last solution.
#[derive(Clone, Debug)]
pub struct ContactScratch {
    pub rows: ContactRows,
    pub mass: DMatrix<f64>,
    factor: Factor,
    kept: RowSystem,
    normal: RowSystem,
    /// M⁻¹f, and the assumed sign of each contact's normal force.
    free: DVector<f64>,
    pressing: Vec<f64>,
    pub solution: ContactSolution,
    /// The step of the velocities that closes the gaps (`gap_step`).
    pub step: DVector<f64>,
    /// On a mechanism with loops, the response P of its accelerations to generalised forces
    /// (`loops::constrained_response`), which the solves and projections use in place of M⁻¹.
    pub response: Option<DMatrix<f64>>,
}

impl ContactScratch {
    /// Scratch for the contacts of `model`, with no row kept yet.
    pub fn new(model: &Model) -> ContactScratch {
        let n = model.velocities();
        ContactScratch {
            rows: ContactRows::new(model),
            mass: DMatrix::zeros(n, n),
            factor: Factor::new(n),
            kept: RowSystem::new(Vec::new(), n),
            normal: RowSystem::new(Vec::new(), n),
            free: DVector::zeros(n),
            pressing: vec![1.0; model.contacts.len()],
            solution: ContactSolution {
                accelerations: DVector::zeros(n),
                forces: vec![Vector3::zeros(); model.contacts.len()],
            },
            step: DVector::zeros(n),
            response: None,
        }
    }

    /// Sizes the solves for the rows `kept` (see `independent_rows`); nothing is done when they
    /// are the rows already kept.
    pub fn keep(&mut self, kept: &[usize]) {
        if self.kept.rows != kept {
            let n = self.mass.nrows();
            self.kept = RowSystem::new(kept.to_vec(), n);
            self.normal = RowSystem::new(holonomic_rows(kept), n);
        }
    }

    /// The rows kept.
    pub fn kept(&self) -> &[usize] {
        &self.kept.rows
    }

    /// The kept rows G of the last solve and the rows H their forces act along (G but on a
    /// sliding contact's normal row, which carries its friction), over the velocities.
    pub fn kept_system(&self) -> (&DMatrix<f64>, &DMatrix<f64>) {
        (&self.kept.g, &self.kept.h)
    }

    /// Factors `mass`: false when it is not positive definite.
    pub fn factor_mass(&mut self) -> bool {
        self.factor.factor(&self.mass)
    }
}

/// Solves M a = f + Hᵀλ, G a + γ = 0 on the kept rows (see the module's documentation), with
/// M and the rows in `scratch` and f the efforts less the velocity-product forces; the solution
/// is left in `scratch.solution`. A sliding contact's friction follows the sign of its normal
/// force: assumed pressing first, and solved again where it pulls.
pub fn solve(
    model: &Model,
    scratch: &mut ContactScratch,
    free_force: &DVector<f64>,
) -> Result<(), ContactError> {
    if !scratch.factor_mass() {
        return Err(ContactError::SingularMass);
    }
    scratch.free.copy_from(free_force);
    scratch.factor.solve_vector_mut(&mut scratch.free);
    solve_rows(model, scratch)
}

/// [`solve`] on a mechanism with loops: `free` the accelerations the loops' solve found without
/// the contacts, and the contacts' forces acting through the loops' response
/// (`ContactScratch::response`, which must be set).
pub fn solve_on_loops(
    model: &Model,
    scratch: &mut ContactScratch,
    free: &DVector<f64>,
) -> Result<(), ContactError> {
    scratch.free.copy_from(free);
    solve_rows(model, scratch)
}

/// The contacts' multipliers and the accelerations a = a_free + X Hᵀλ from the accelerations
/// without them in `scratch.free`, X = M⁻¹ (factored) or the loops' response.
fn solve_rows(model: &Model, scratch: &mut ContactScratch) -> Result<(), ContactError> {
    let ContactScratch {
        rows,
        factor,
        kept: system,
        free,
        pressing,
        solution,
        response,
        ..
    } = scratch;
    system.gather(rows);
    pressing.fill(1.0);
    for _ in 0..=model.contacts.len() {
        force_rows(model, rows, system, pressing);
        system.couple(factor, response.as_ref());
        for (i, &row) in system.rows.iter().enumerate() {
            system.right[i] = -rows.bias[row];
        }
        system.right.gemv(-1.0, &system.g, free, 1.0);
        system
            .multipliers()
            .map_err(|row| ContactError::Singular { row })?;
        contact_forces(model, rows, system, &mut solution.forces);
        if !flip_pulling(model, &solution.forces, pressing) {
            solution.accelerations.copy_from(free);
            (solution.accelerations).gemv(1.0, &system.moved, &system.right, 1.0);
            return Ok(());
        }
    }
    Err(ContactError::Singular {
        row: system.rows[0],
    })
}

/// H: the kept rows, where a sliding contact's normal row also carries the friction its normal
/// force causes, −f σ (sₓ Gₓ + s_y G_y), with σ = `pressing` (±1) the normal force's sign.
fn force_rows(model: &Model, rows: &ContactRows, system: &mut RowSystem, pressing: &[f64]) {
    system.h.copy_from(&system.g);
    for (i, &row) in system.rows.iter().enumerate() {
        let k = row / 3;
        let Some(friction) = model.contacts[k].friction else {
            continue;
        };
        let [sx, sy] = friction_direction(rows, k);
        let scale = friction * pressing[k];
        for j in 0..system.h.ncols() {
            let tangential = rows.jacobian[(3 * k, j)] * sx + rows.jacobian[(3 * k + 1, j)] * sy;
            system.h[(i, j)] -= scale * tangential;
        }
    }
}

/// Each contact's force on its round body, in the plane's axes, from the multipliers of the
/// kept rows (solved in `system`).
fn contact_forces(
    model: &Model,
    rows: &ContactRows,
    system: &RowSystem,
    forces: &mut [Vector3<f64>],
) {
    forces.fill(Vector3::zeros());
    for (&row, &lambda) in system.rows.iter().zip(system.right.iter()) {
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
fn flip_pulling(model: &Model, forces: &[Vector3<f64>], pressing: &mut [f64]) -> bool {
    let mut flipped = false;
    for (k, contact) in model.contacts.iter().enumerate() {
        if contact.friction.is_some() && forces[k].z * pressing[k] < 0.0 {
            pressing[k] = -pressing[k];
            flipped = true;
        }
    }
    flipped
}

/// The smallest change of the velocities in the metric of M that zeroes the kept rows:
/// v − M⁻¹Gᵀ(G M⁻¹ Gᵀ)⁻¹ G v, with the rows of `scratch` taken at v and its mass matrix
/// factored (`ContactScratch::factor_mass`), or with loops their response P in place of M⁻¹
/// (the change then keeps the loops' velocity rows). Nothing moves where the rows are
/// dependent.
pub fn project_velocities(scratch: &mut ContactScratch, v: &mut [f64]) {
    let system = &mut scratch.kept;
    system.gather(&scratch.rows);
    system.couple(&scratch.factor, scratch.response.as_ref());
    for (i, &row) in system.rows.iter().enumerate() {
        system.right[i] = scratch.rows.velocity[row];
    }
    if system.multipliers().is_ok() {
        let n = v.len();
        let mut v = DVectorViewMut::from_slice(v, n);
        v.gemv(-1.0, &system.moved, &system.right, 1.0);
    }
}

/// The minimum-M-norm step of the velocities that closes the gaps of the kept normal rows to
/// first order, −M⁻¹Gₙᵀ(Gₙ M⁻¹ Gₙᵀ)⁻¹ g, into `scratch.step`, with `scratch` as for
/// `project_velocities`; false where the rows are dependent.
pub fn gap_step(scratch: &mut ContactScratch) -> bool {
    let system = &mut scratch.normal;
    system.gather(&scratch.rows);
    system.couple(&scratch.factor, scratch.response.as_ref());
    for (i, &row) in system.rows.iter().enumerate() {
        system.right[i] = scratch.rows.gap[row / 3];
    }
    if system.multipliers().is_err() {
        return false;
    }
    (scratch.step).gemv(-1.0, &system.moved, &system.right, 0.0);
    true
}

/// The largest gap of the kept normal rows.
pub fn largest_gap(scratch: &ContactScratch) -> f64 {
    (scratch.normal.rows.iter())
        .map(|r| scratch.rows.gap[r / 3].abs())
        .fold(0.0, f64::max)
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
