//! One set of constraint rows for everything a state's motion must keep beyond what the response
//! X keeps (`response`: the tree's joints, the mimic couplings of a tree, the closed loops), in
//! this order:
//!
//! - the contacts' kept rows (`contacts`), with their velocity-product terms γ;
//! - with closed loops, one row per mimic coupling, q̇_f − m q̇_l = 0 (a tree eliminates them
//!   in X instead);
//! - one unit row eₖᵀ per driven coordinate (`drives`), its right-hand side the law's
//!   acceleration: eₖᵀ a = law''(t), set by [`RowStack::prescribe`];
//! - one unit row eₖᵀ per coordinate held at rest: on a stop it rests on, or held by its dry
//!   friction (sticking).
//!
//! With G the rows and H the rows their forces act along (G, but on a sliding contact's normal
//! row, whose force carries the friction it causes), the accelerations a₀ the base solve found
//! without them become a = a₀ + X Hᵀλ with (G X Hᵀ) λ = −(G a₀ + γ): the saddle-point system
//! [M −Hᵀ; G 0] solved on the response. The same rows, without γ, bring a state's velocities
//! (or positions, on their position rows) back onto them by the change of least kinetic metric
//! along X Gᵀ ([`RowStack::add_least_change`]). The solve is rank-revealing (`Pivoted`): a
//! follower held with its leader, or a coordinate held by a stop and its friction, gives
//! dependent rows, which leave the motion determined though not their forces. Nothing is
//! allocated once the storage is sized for the rows (`RowStack::arrange`), which change only at
//! events.

use nalgebra::{DMatrix, DVector, Vector3};

use super::contacts::{self, ContactRows};
use super::dense::Pivoted;
use super::mimics::Mimic;
use super::model::Model;
use super::response::Response;

/// Entries of G X Hᵀ below this fraction of its largest are taken as zero: the rows left are
/// dependent on the others.
pub const DEPENDENT_ROWS: f64 = 1e-12;

/// The stacked rows of one use (the accelerations' solve, or a projection) and their solve.
#[derive(Clone, Debug)]
pub struct RowStack {
    /// The contacts' rows stacked (indices among the three per contact of `ContactRows`).
    contacts: Vec<usize>,
    /// How many coupling rows follow them, then the driven velocities, then the velocities
    /// held at rest.
    couplings: usize,
    drives: Vec<usize>,
    held: Vec<usize>,
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

/// Why the rows' solve failed: a sliding contact's normal force changes sign at every solve
/// (the contact named).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Unsettled {
    pub contact: usize,
}

impl RowStack {
    /// An empty stack for the velocities of `model`.
    pub fn new(model: &Model) -> RowStack {
        let n = model.velocities();
        RowStack {
            contacts: Vec::new(),
            couplings: 0,
            drives: Vec::with_capacity(model.drives.len()),
            held: Vec::with_capacity(model.stops.len() + model.frictions.len()),
            g: DMatrix::zeros(0, n),
            directions: DMatrix::zeros(n, 0),
            bias: DVector::zeros(0),
            moved: DMatrix::zeros(n, 0),
            coupling: DMatrix::zeros(0, 0),
            right: DVector::zeros(0),
            pivoted: Pivoted::default(),
            pressing: vec![1.0; model.contacts.len()],
            contact_forces: vec![Vector3::zeros(); model.contacts.len()],
            accelerations: DVector::zeros(n),
        }
    }

    /// Stacks the contact rows `contacts`, `couplings` coupling rows and the unit rows of the
    /// velocities `drives` (driven) and `held`; the storage is sized anew only when the number
    /// of rows changes.
    pub fn arrange(
        &mut self,
        contacts: &[usize],
        couplings: usize,
        drives: &[usize],
        held: &[usize],
    ) {
        if self.contacts != contacts {
            self.contacts.clear();
            self.contacts.extend_from_slice(contacts);
        }
        self.couplings = couplings;
        self.drives.clear();
        self.drives.extend_from_slice(drives);
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
        self.contacts.len() + self.couplings + self.drives.len() + self.held.len()
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The contact rows stacked.
    pub fn contact_rows(&self) -> &[usize] {
        &self.contacts
    }

    /// Fills G and γ from the contacts' rows `all` (γ as they hold it) and the couplings
    /// `mimics` (the first `couplings` of them), the unit rows after them (the driven rows'
    /// γ at zero until `prescribe`).
    pub fn gather(&mut self, all: &ContactRows, mimics: &[Mimic]) {
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
        for (i, &velocity) in self.drives.iter().chain(&self.held).enumerate() {
            self.g[(first + i, velocity)] = 1.0;
        }
    }

    /// Sets the driven rows' right-hand sides, eₖᵀ a = `accelerations[k]` (the laws'
    /// accelerations, in the order of the driven velocities): γₖ = −law''(t).
    pub fn prescribe(&mut self, accelerations: impl IntoIterator<Item = f64>) {
        let first = self.contacts.len() + self.couplings;
        for (i, acceleration) in accelerations
            .into_iter()
            .take(self.drives.len())
            .enumerate()
        {
            self.bias[first + i] = -acceleration;
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

    /// The multipliers of the last solve: the contacts' rows', then the couplings', then the
    /// driven and the held velocities' (each a force along its velocity).
    pub fn multipliers(&self) -> &[f64] {
        self.right.as_slice()
    }

    /// The forces that held the velocities `held` at the last solve.
    pub fn held_forces(&self) -> &[f64] {
        &self.right.as_slice()[self.contacts.len() + self.couplings + self.drives.len()..]
    }

    /// The forces that imposed the driven velocities at the last solve: the drives' efforts.
    pub fn drive_forces(&self) -> &[f64] {
        let first = self.contacts.len() + self.couplings;
        &self.right.as_slice()[first..first + self.drives.len()]
    }

    /// Adds the forces of the last solve's coupling, driven and held rows to the generalised forces
    /// `tau` (over the state's velocities): they act along coordinates, as link efforts do
    /// (the contacts' act on bodies instead, `contact_forces`).
    pub fn add_coordinate_forces(&self, mimics: &[Mimic], tau: &mut DVector<f64>) {
        let multipliers = &self.right.as_slice()[self.contacts.len()..];
        let (couplings, unit) = multipliers.split_at(self.couplings);
        for (mimic, force) in mimics.iter().zip(couplings) {
            tau[mimic.velocity] += force;
            tau[mimic.leader_velocity] -= mimic.multiplier * force;
        }
        for (&velocity, force) in self.drives.iter().chain(&self.held).zip(unit) {
            tau[velocity] += force;
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
