//! The constraint stack: every row a state's motion must keep, in blocks by kind, with one
//! solve, one projection and one reactions path for all of them (MuJoCo's rows of one Jacobian
//! by kind, Todorov, Erez & Tassa 2012; Pinocchio's `constraintDynamics`, Carpentier et al.
//! 2019). The blocks, in their order:
//!
//! 1. the tree's joints and the closed loops: the response X (`response`) eliminates them, a
//!    tree by its mass matrix, the tree's mimic couplings by their basis, the loops by their
//!    sparse factorisation (`loops`: the loops' block has its own specialised solve, whose
//!    allowed motions N give X = N (NᵀMN)⁻¹ Nᵀ, so that G X = 0 for its rows; the run solves
//!    it first in the same call as the others, `simulate::system::stack`, and the symplectic
//!    integrator's RATTLE steps solve the same block with their own right-hand sides);
//! 2. the contacts' kept rows (`contacts`), with their velocity-product terms γ;
//! 3. with closed loops, one row per mimic coupling, q̇_f − m q̇_l = 0 (a tree eliminates them
//!    in X instead);
//! 4. three rows per position drive (`driven_points`), the velocity of a frame's origin along
//!    the fixed axes, whose forces act on its body at the origin;
//! 5. one unit row eₖᵀ per coordinate held ([`HeldRow`]): driven by a law of time (`drive`),
//!    on a stop it rests on, or held by its dry friction (sticking).
//!
//! The blocks 2 to 5 are this stack's rows G, solved on X. With H the rows their forces act
//! along (G, but on a sliding contact's normal row, whose force carries the friction it
//! causes), the accelerations a₀ the base solve found without them become a = a₀ + X Hᵀλ with
//! (G X Hᵀ) λ = −(G a₀ + γ): the saddle-point system [M −Hᵀ; G 0] solved on the response
//! ([`RowStack::solve`]), at one call site of the run for every block
//! (`MechanicalSystem::solve_stack`, in `derivative_at`). The same rows bring a state's
//! velocities (their values G v − w, [`RowStack::velocity_values`]) or positions (their values
//! φ(q, t), [`RowStack::position_values`]) back onto them by the change of least kinetic
//! metric along X Gᵀ ([`RowStack::add_least_change`]: the steps of the one position corrector,
//! `corrector`, for every kind with a position, the drives' laws and the resting stops' bounds
//! among them); their forces join the generalised forces for the reactions, before the loops'
//! multipliers are found ([`RowStack::add_coordinate_forces`], the contacts' act on bodies
//! instead). The solve is rank-revealing (`Pivoted`): a follower held with its leader, or a
//! coordinate held by a stop and its friction, gives dependent rows, which leave the motion
//! determined though not their forces. Nothing is allocated once the storage is sized for the
//! rows ([`RowStack::arrange`]), which change only at events.
//!
//! Each row has a right-hand side at each level: its position value φ, its velocity target w
//! (G v = w) and its acceleration term γ (G a + γ = 0). A kind fixed in time has w = 0 and no
//! ∂/∂t terms. The rheonomic kind, a coordinate driven by a law of time q = d(t), is the held
//! row of [`Holder::Drive`], which carries the law evaluated at the row's time:
//! φ = q − d(t), w = ḋ(t), γ = −d̈(t), its force the drive's effort. To add a kind: give it
//! a block here (its rows in `gather`, its values in `position_values` and `velocity_values`,
//! its term in `gather`'s γ, its forces in `add_coordinate_forces`), and have the run arrange
//! it (`simulate::system::holding`), where the rows' forces are handed back to what holds
//! them.

use nalgebra::{DMatrix, DVector, Vector3};

use super::contacts::{self, ContactRows};
use super::dense::Pivoted;
use super::driven_points::PointRows;
use super::drives::DrivenCoordinate;
use super::mimics::Mimic;
use super::model::Model;
use super::response::Response;
use super::stops::Stop;
use crate::kinematics::drives::LawAt;

/// A coordinate held by a unit row eₖᵀ of the stack, and what holds it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HeldRow {
    /// The held coordinate's index among the state's velocities.
    pub velocity: usize,
    pub holder: Holder,
}

impl HeldRow {
    /// The row of a coordinate resting on the stop `index`, `stop`.
    pub fn on_stop(index: usize, stop: &Stop) -> HeldRow {
        HeldRow {
            velocity: stop.velocity,
            holder: Holder::Stop {
                index,
                position: stop.position,
                bound: stop.bound,
            },
        }
    }

    /// The row of the drive `index`, `drive`, its law evaluated at the row's time (`law`).
    pub fn driven(index: usize, drive: &DrivenCoordinate, law: LawAt) -> HeldRow {
        HeldRow {
            velocity: drive.velocity,
            holder: Holder::Drive {
                index,
                position: drive.position,
                law,
            },
        }
    }
}

/// What holds a coordinate, which decides its row's right-hand sides and where its force goes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Holder {
    /// The drive `index` (`Model::drives`), its law d at the row's time: φ = q − d(t),
    /// w = ḋ(t), γ = −d̈(t); its force is the drive's effort.
    Drive {
        index: usize,
        position: usize,
        law: LawAt,
    },
    /// The stop `index` it rests on: at rest, its position row q − bound.
    Stop {
        index: usize,
        position: usize,
        bound: f64,
    },
    /// The joint friction `index`, sticking: at rest, no position row (the friction holds the
    /// rate, not the place).
    Friction { index: usize },
    /// The stop `index` at an impact: its rate brought to `rate_after` (−e times the rate
    /// before), the other rows to rest; a velocity row only.
    Impact { index: usize, rate_after: f64 },
}

/// Relative size of a coupling's violation below which it is not corrected.
const COUPLING_ROUND_OFF: f64 = 1e-13;

/// Relative size of a driven coordinate's distance to its law (to 1 + |d(t)|) below which it
/// is not corrected.
pub const LAW_ROUND_OFF: f64 = 1e-13;

/// Relative size of a contact's gap (to the largest radius) below which it is not corrected.
const GAP_ROUND_OFF: f64 = 1e-15;

/// A held coordinate's distance to its bound below this (relative to max(1, |bound|)) is at
/// round-off: it is set on the bound alone (`simulate::system::stacked`).
pub const BOUND_ROUND_OFF: f64 = 1e-14;

/// A held coordinate's distance to its bound above this (relative to max(1, |bound|)) is
/// corrected with the other rows: a stop's row is linear in the positions, so one step closes
/// it to a few units in the last place, and a coordinate then set on its bound alone leaves the
/// other rows closed. At `BOUND_ROUND_OFF` instead, the crank of `limited_four_bar` (dop853),
/// found 7.9e-15 below its bound at an impact and set on it alone, was 8e-13 below it when the
/// integration restarted: its next crossing, from below, was missed.
const BOUND_CLOSED: f64 = 4.0 * f64::EPSILON;

/// Entries of G X Hᵀ below this fraction of its largest are taken as zero: the rows left are
/// dependent on the others.
pub const DEPENDENT_ROWS: f64 = 1e-12;

/// The stacked rows of one use (the accelerations' solve, or a projection) and their solve.
#[derive(Clone, Debug)]
pub struct RowStack {
    /// The contacts' rows stacked (indices among the three per contact of `ContactRows`).
    contacts: Vec<usize>,
    /// How many coupling rows follow them, then how many position drives' rows (three per
    /// drive), then the coordinates held.
    couplings: usize,
    points: usize,
    held: Vec<HeldRow>,
    /// G (rows × velocities), Hᵀ (velocities × rows), γ, X Hᵀ, G X Hᵀ.
    g: DMatrix<f64>,
    directions: DMatrix<f64>,
    bias: DVector<f64>,
    moved: DMatrix<f64>,
    coupling: DMatrix<f64>,
    /// The right-hand side, then the multipliers λ.
    right: DVector<f64>,
    pivoted: Pivoted,
    /// Per contact, the assumed sign of its normal force (sliding contacts), and its force on
    /// the round body along the plane's axes at the last solve.
    pressing: Vec<f64>,
    pub contact_forces: Vec<Vector3<f64>>,
    /// The accelerations of the last solve.
    pub accelerations: DVector<f64>,
}

/// The velocities just after an impact, from `v` (before it) into `after`: the change of least
/// kinetic metric along X that brings the stop's row (`impact`, a held row with
/// [`Holder::Impact`]) to its rate after and every other row of `stack` to rest, the impulse
/// P = (G X Gᵀ)⁺ (G v − w) acting through the response as the forces do
/// (Pfeiffer & Glocker, *Multibody Dynamics with Unilateral Contacts*, 1996, §7: Newton's
/// impact law on one contact, the bilateral rows kept). `stack` arranged with `impact` last
/// among its held rows, G gathered, X formed at the state. False when the result is not
/// finite (no inertia along the stopped coordinate).
pub fn impact_velocities(
    stack: &mut RowStack,
    response: &mut Response,
    all: &ContactRows,
    mimics: &[Mimic],
    points: &PointRows,
    v: &[f64],
    after: &mut [f64],
) -> bool {
    after.copy_from_slice(v);
    stack.velocity_values(all, mimics, points, v);
    stack.add_least_change(response, after);
    // The law holds exactly on the stop's row: the solve leaves its rate within round-off of
    // the target, and after a dead stop (e = 0) a rate of −1e-17 into the stop would be a
    // second impact at once. The other rows move by that round-off at most.
    for held in &stack.held {
        if let Holder::Impact { rate_after, .. } = held.holder {
            after[held.velocity] = rate_after;
        }
    }
    after.iter().all(|x| x.is_finite())
}

/// Why the rows' solve failed: a sliding contact's normal force changes sign at every solve
/// (the contact named).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Unsettled {
    pub contact: usize,
}

impl RowStack {
    /// An empty stack for the velocities of `model`.
    pub fn new(model: &Model) -> RowStack {
        let mut stack = RowStack::over(model.velocities(), model.contacts.len());
        stack
            .held
            .reserve(model.drives.len() + model.stops.len() + model.frictions.len());
        stack
    }

    /// An empty stack for `n` velocities and `contacts` contacts.
    pub fn over(n: usize, contacts: usize) -> RowStack {
        RowStack {
            contacts: Vec::new(),
            couplings: 0,
            points: 0,
            held: Vec::new(),
            g: DMatrix::zeros(0, n),
            directions: DMatrix::zeros(n, 0),
            bias: DVector::zeros(0),
            moved: DMatrix::zeros(n, 0),
            coupling: DMatrix::zeros(0, 0),
            right: DVector::zeros(0),
            pivoted: Pivoted::default(),
            pressing: vec![1.0; contacts],
            contact_forces: vec![Vector3::zeros(); contacts],
            accelerations: DVector::zeros(n),
        }
    }

    /// Stacks the contact rows `contacts`, `couplings` coupling rows, the position drives' rows
    /// of `points` and the unit rows of the coordinates `held`; the storage is sized anew only
    /// when the number of rows changes.
    pub fn arrange(
        &mut self,
        contacts: &[usize],
        couplings: usize,
        points: &PointRows,
        held: &[HeldRow],
    ) {
        if self.contacts != contacts {
            self.contacts.clear();
            self.contacts.extend_from_slice(contacts);
        }
        self.couplings = couplings;
        self.points = points.len();
        self.held.clear();
        self.held.extend_from_slice(held);
        let (rows, n) = (self.len(), self.g.ncols());
        if self.g.nrows() != rows {
            self.g = DMatrix::zeros(rows, n);
            self.directions = DMatrix::zeros(n, rows);
            self.bias = DVector::zeros(rows);
            self.moved = DMatrix::zeros(n, rows);
            self.coupling = DMatrix::zeros(rows, rows);
            self.right = DVector::zeros(rows);
        }
    }

    /// The number of rows stacked.
    pub fn len(&self) -> usize {
        self.contacts.len() + self.couplings + self.points + self.held.len()
    }

    #[cfg(lsdc_internals)]
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Fills G and γ from the contacts' rows `all` (γ as they hold it), the couplings
    /// `mimics` (the first `couplings` of them) and the position drives' rows `points` (γ as
    /// they hold it), the unit rows after them (γ = −d̈(t) on a driven row, 0 on the others).
    pub fn gather(&mut self, all: &ContactRows, mimics: &[Mimic], points: &PointRows) {
        self.g.fill(0.0);
        self.bias.fill(0.0);
        for (i, &row) in self.contacts.iter().enumerate() {
            self.g.row_mut(i).copy_from(&all.jacobian.row(row));
            self.bias[i] = all.bias[row];
        }
        let first = self.contacts.len();
        for (i, mimic) in mimics.iter().take(self.couplings).enumerate() {
            self.g[(first + i, mimic.velocity)] = 1.0;
            self.g[(first + i, mimic.leader_velocity)] -= mimic.multiplier;
        }
        let first = first + self.couplings;
        for i in 0..self.points {
            self.g.row_mut(first + i).copy_from(&points.jacobian.row(i));
            self.bias[first + i] = points.bias[i];
        }
        let first = first + self.points;
        for (i, held) in self.held.iter().enumerate() {
            self.g[(first + i, held.velocity)] = 1.0;
            if let Holder::Drive { law, .. } = held.holder {
                self.bias[first + i] = -law.acceleration;
            }
        }
    }

    /// X Hᵀ and G X Hᵀ, with Hᵀ in `directions`.
    fn couple(&mut self, response: &mut Response) {
        response.apply(&self.directions, &mut self.moved);
        self.coupling.gemm(1.0, &self.g, &self.moved, 0.0);
    }

    /// The accelerations a = a₀ + X Hᵀλ that keep every row, from the accelerations `free`
    /// (a₀) found without them, into `accelerations`, with the contacts' forces and the
    /// multipliers (`multipliers`); G and γ gathered at the state, X formed there. A sliding
    /// contact's friction follows the sign of its normal force: assumed pressing first, and
    /// solved again where it pulls.
    pub fn solve(
        &mut self,
        model: &Model,
        all: &ContactRows,
        response: &mut Response,
        free: &DVector<f64>,
    ) -> Result<(), Unsettled> {
        self.pressing.fill(1.0);
        for _ in 0..=model.contacts.len() {
            self.directions.tr_copy_from(&self.g);
            contacts::sliding_directions(
                model,
                all,
                &self.contacts,
                &mut self.directions,
                &self.pressing,
            );
            self.couple(response);
            self.right.copy_from(&self.bias);
            self.right.gemv(-1.0, &self.g, free, -1.0);
            self.pivoted
                .solve(&mut self.coupling, &mut self.right, DEPENDENT_ROWS);
            let multipliers = &self.right.as_slice()[..self.contacts.len()];
            contacts::contact_forces(
                model,
                all,
                &self.contacts,
                multipliers,
                &mut self.contact_forces,
            );
            if !contacts::flip_pulling(model, &self.contact_forces, &mut self.pressing) {
                self.accelerations.copy_from(free);
                self.accelerations.gemv(1.0, &self.moved, &self.right, 1.0);
                return Ok(());
            }
        }
        let sliding = model.contacts.iter().position(|c| c.friction.is_some());
        Err(Unsettled {
            contact: sliding.unwrap_or_default(),
        })
    }

    /// The coordinates held, each with the force that held it at the last solve.
    pub fn held_forces(&self) -> impl Iterator<Item = (&HeldRow, f64)> {
        let first = self.contacts.len() + self.couplings + self.points;
        let forces = &self.right.as_slice()[first..];
        self.held.iter().zip(forces.iter().copied())
    }

    /// The position drives' forces of the last solve: per drive, the force along x, y, z at
    /// its frame's origin that imposes the path.
    pub fn point_forces(&self) -> &[f64] {
        let first = self.contacts.len() + self.couplings;
        &self.right.as_slice()[first..first + self.points]
    }

    /// The rows G, gathered (`gather`).
    #[cfg(lsdc_internals)]
    pub fn rows(&self) -> &DMatrix<f64> {
        &self.g
    }

    /// Sets the rows' values to their velocities' distance from their targets at the
    /// velocities `v`, G v − w (`values_mut`, for `add_least_change`): the contacts' rates as
    /// `all` holds them, the couplings' q̇_f − m q̇_l, the position drives' J v − ṗ(t) as
    /// `points` holds them, the held rates (a driven one from its law's, q̇ − ḋ(t)). Whether
    /// any is non-zero.
    pub fn velocity_values(
        &mut self,
        all: &ContactRows,
        mimics: &[Mimic],
        points: &PointRows,
        v: &[f64],
    ) -> bool {
        let contacts = self.contacts.len();
        for (i, &row) in self.contacts.iter().enumerate() {
            self.right[i] = all.velocity[row];
        }
        for (i, mimic) in mimics.iter().take(self.couplings).enumerate() {
            self.right[contacts + i] =
                v[mimic.velocity] - mimic.multiplier * v[mimic.leader_velocity];
        }
        let first = contacts + self.couplings;
        for i in 0..self.points {
            self.right[first + i] = points.velocity[i];
        }
        let first = first + self.points;
        for (i, held) in self.held.iter().enumerate() {
            let target = match held.holder {
                Holder::Impact { rate_after, .. } => rate_after,
                Holder::Drive { law, .. } => law.rate,
                Holder::Stop { .. } | Holder::Friction { .. } => 0.0,
            };
            self.right[first + i] = v[held.velocity] - target;
        }
        self.right.amax() > 0.0
    }

    /// Sets the rows' values to their position values at q, φ(q, t) (`values_mut`, for
    /// `add_least_change`): the gaps of the contacts' rows (normal rows only: the others are
    /// not integrable), the couplings' violations, the held coordinates' distances to their
    /// bounds or their laws, q − d(t) (none for a row of velocities only), the position
    /// drives' o(q) − p(t) as `points` holds them. Whether any is above its round-off (a gap's
    /// relative to the largest radius, a coupling's to its follower's coordinate, a bound's to
    /// the bound (a few units in the last place), a law's distance to 1 + |d(t)|, a path's to
    /// 1 + |p(t)|).
    pub fn position_values(
        &mut self,
        model: &Model,
        all: &ContactRows,
        points: &PointRows,
        q: &[f64],
    ) -> bool {
        let radius = model.contacts.iter().map(|c| c.radius).fold(0.0, f64::max);
        let mut open = false;
        for (i, &row) in self.contacts.iter().enumerate() {
            debug_assert_eq!(row % 3, 2, "a contact's position row is its normal row");
            self.right[i] = all.gap[row / 3];
            open |= self.right[i].abs() > GAP_ROUND_OFF * radius;
        }
        let first = self.contacts.len();
        let couplings = &model.mimics[..self.couplings];
        let scale = 1.0
            + couplings
                .iter()
                .map(|m| q[m.position].abs())
                .fold(0.0, f64::max);
        for (i, mimic) in couplings.iter().enumerate() {
            self.right[first + i] = mimic.violation(q);
            open |= self.right[first + i].abs() > COUPLING_ROUND_OFF * scale;
        }
        let first = first + self.couplings;
        for i in 0..self.points {
            let path = points.laws[i / 3][i % 3].position;
            self.right[first + i] = points.position[i];
            open |= points.position[i].abs() > LAW_ROUND_OFF * (1.0 + path.abs());
        }
        let first = first + self.points;
        for (i, held) in self.held.iter().enumerate() {
            // A row of velocities only has no position to correct.
            let (value, round_off) = match held.holder {
                Holder::Stop {
                    position, bound, ..
                } => (q[position] - bound, BOUND_CLOSED * bound.abs().max(1.0)),
                Holder::Drive { position, law, .. } => (
                    q[position] - law.position,
                    LAW_ROUND_OFF * (1.0 + law.position.abs()),
                ),
                Holder::Friction { .. } | Holder::Impact { .. } => (0.0, 0.0),
            };
            self.right[first + i] = value;
            open |= value.abs() > round_off;
        }
        open
    }

    /// Adds the forces of the last solve's coupling and held rows to the generalised forces
    /// `tau` (over the state's velocities): they act along coordinates, as link efforts do
    /// (the contacts' and the position drives' act on bodies instead, `contact_forces`,
    /// `point_forces`).
    pub fn add_coordinate_forces(&self, mimics: &[Mimic], tau: &mut DVector<f64>) {
        let multipliers = &self.right.as_slice()[self.contacts.len()..];
        let (couplings, rest) = multipliers.split_at(self.couplings);
        let held = &rest[self.points..];
        for (mimic, force) in mimics.iter().zip(couplings) {
            tau[mimic.velocity] += force;
            tau[mimic.leader_velocity] -= mimic.multiplier * force;
        }
        for (row, force) in self.held.iter().zip(held) {
            tau[row.velocity] += force;
        }
    }

    /// The values the rows must be brought from, for `add_least_change` (one per row).
    pub fn values_mut(&mut self) -> &mut DVector<f64> {
        &mut self.right
    }

    /// Adds to `out` (over the velocities) the change of least kinetic metric along X Gᵀ that
    /// brings the rows from the values set by `values_mut` to zero, −X Gᵀ (G X Gᵀ)⁺ e; G
    /// gathered, X formed at the state.
    pub fn add_least_change(&mut self, response: &mut Response, out: &mut [f64]) {
        self.directions.tr_copy_from(&self.g);
        self.couple(response);
        self.pivoted
            .solve(&mut self.coupling, &mut self.right, DEPENDENT_ROWS);
        for (i, x) in out.iter_mut().enumerate() {
            let change: f64 = (0..self.right.len())
                .map(|j| self.moved[(i, j)] * self.right[j])
                .sum();
            *x -= change;
        }
    }
}
