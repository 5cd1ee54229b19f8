//! The factorisation of the rows a run keeps (made dimensionless), Gₛ, that serves the equations
//! of motion (`solve`), the projection (`project`) and the watch on singular configurations: a
//! Cholesky factorisation of the normal matrix A = GₛGₛᵀ + μ²E (damped on the firm rows, see
//! `DAMPING`). Loops touch few bodies, so A is sparse: two rows meet only where their loops
//! share a coordinate, and in a chain of loops A is banded. A is stored and factored in its
//! envelope (per row, from its first non-zero entry to the diagonal), where the factor creates
//! no fill, so the cost follows the structure: linear in the number of loops for a chain of
//! them, against a cube for a dense factorisation.
//!
//! The rows are factored in the order of `RowChoice` (firm rows, then weak ones, each by index):
//! loop order keeps the envelope narrow. The diagonal of the factor L equals, up to signs, that
//! of R in a QR factorisation Gₛᵀ = QR taken in the same order; it measures how independent each
//! row is of the rows before it (`conditioning`).

use std::cell::OnceCell;

use nalgebra::{DMatrix, DVector};

use super::jacobian::ConstraintJacobian;
use super::triples::{self, DiagonalBlock};
use crate::dynamics::dense::dense_cholesky;
use crate::elimination::{pivoted, Elimination, Sparse};

/// Which of the loops' rows (6 per loop) are kept, and the factor making each dimensionless.
#[derive(Clone, Debug, PartialEq)]
pub struct RowChoice {
    /// The firm rows first, then the `weak` ones; each group in increasing order.
    pub rows: Vec<usize>,
    pub scales: Vec<f64>,
    /// How many of the last rows close their loop only at second order: independent of the
    /// others by about the square root of the closure residual (1e-8), so they are solved
    /// exactly, never damped.
    pub weak: usize,
}

impl RowChoice {
    /// The rows given (firm first, then `weak` of them), made dimensionless with their loop's
    /// length (`lengths`, one per loop; see `row_scale` and `structure::loop_lengths`).
    pub fn new(mut rows: Vec<usize>, weak: usize, lengths: &[f64]) -> RowChoice {
        let firm = rows.len() - weak;
        rows[..firm].sort_unstable();
        rows[firm..].sort_unstable();
        let scales = rows.iter().map(|&r| loop_row_scale(r, lengths)).collect();
        RowChoice { rows, scales, weak }
    }

    pub const NONE: RowChoice = RowChoice {
        rows: Vec::new(),
        scales: Vec::new(),
        weak: 0,
    };

    fn firm(&self) -> usize {
        self.rows.len() - self.weak
    }
}

/// 1 for a rotation row (the first three of a loop), 1/L for a translation row.
pub fn row_scale(row: usize, length: f64) -> f64 {
    if row % 6 < 3 {
        1.0
    } else {
        1.0 / length
    }
}

/// `row_scale` with the length of the row's own loop (`lengths`, one per loop, 6 rows each).
pub fn loop_row_scale(row: usize, lengths: &[f64]) -> f64 {
    row_scale(row, lengths[row / 6])
}

/// The damping of the solves on the firm rows, relative to their largest scale: its effect is
/// (μ/σ)² where σ measures the rows' independence, below round-off unless the mechanism is
/// within 1e-4 or so of a singular configuration, where it bounds what an error off the
/// closed set can do to the accelerations (damped least squares: Nakamura and Hanafusa 1986;
/// Wampler 1986).
pub const DAMPING: f64 = 1e-9;

/// The damping of the projections (positions and velocities): larger, since what they correct
/// is the integration's error, which a projection near a singular configuration would
/// otherwise amplify into a jump; (μ/σ)² is still below round-off for σ above 1e-2.
pub const PROJECTION_DAMPING: f64 = 1e-6;

/// For the rows the equations keep: a row is independent when its part orthogonal to the rows
/// already kept is above this fraction of the largest (dimensionless) row. Rows that close a
/// loop only at second order (maille1, maille2) are independent at first order by about 1e-9
/// at a configuration closed to 1e-15, and must be kept; rows that depend on others are at
/// round-off, 1e-15. A row left out whose entries are all below this fraction of the kept
/// rows' largest is at round-off (`Damped::reproduction`).
pub const KEEP_TOLERANCE: f64 = 1e-12;

/// The kept rows of G, compressed: row k's entries are `starts[k]..starts[k + 1]` of `columns`
/// and `values`, over every column of its loop (zeros included) in increasing column order. The
/// columns and where each value is read from are fixed as long as the same rows are kept; an
/// evaluation only gathers the values.
#[derive(Default)]
struct KeptRows {
    starts: Vec<usize>,
    columns: Vec<usize>,
    values: Vec<f64>,
    /// Per kept row, its loop block and its row there (0 to 5): its entries are that row of
    /// the block's values (column-major, 6 rows), every sixth value from the row's.
    sources: Vec<(usize, usize)>,
}

impl KeptRows {
    /// The structure of the rows `indices` (among the 6 per loop) of `jacobian`.
    fn lay_out(&mut self, jacobian: &ConstraintJacobian, indices: &[usize]) {
        self.starts.clear();
        self.columns.clear();
        self.sources.clear();
        self.starts.push(0);
        for &r in indices {
            let (block, row) = (r / 6, r % 6);
            let columns = &jacobian.blocks[block].columns;
            self.columns.extend_from_slice(columns);
            self.sources.push((block, row));
            self.starts.push(self.columns.len());
        }
        self.values.resize(self.columns.len(), 0.0);
    }

    /// The values of `jacobian`'s rows, each times its scale (`scales`, one per row).
    fn gather(&mut self, jacobian: &ConstraintJacobian, scales: &[f64]) {
        for (k, (&scale, &(block, row))) in scales.iter().zip(&self.sources).enumerate() {
            let range = self.starts[k]..self.starts[k + 1];
            let columns = jacobian.blocks[block].values.as_slice().chunks_exact(6);
            for (value, column) in self.values[range].iter_mut().zip(columns) {
                *value = column[row] * scale;
            }
        }
    }

    fn len(&self) -> usize {
        self.starts.len().saturating_sub(1)
    }

    /// Row k as (column, value) pairs.
    fn row(&self, k: usize) -> impl Iterator<Item = (usize, f64)> + '_ {
        let range = self.starts[k]..self.starts[k + 1];
        self.columns[range.clone()]
            .iter()
            .copied()
            .zip(self.values[range].iter().copied())
    }

    fn iter(&self) -> impl Iterator<Item = impl Iterator<Item = (usize, f64)> + '_> + '_ {
        (0..self.len()).map(|k| self.row(k))
    }
}

/// The kept rows of G at one state, dimensionless, and their normal matrix.
pub struct Factored {
    rows: KeptRows,
    columns: usize,
    /// Indices among the 6 per loop, and the factors that made each row dimensionless.
    indices: Vec<usize>,
    /// Per row of G (6 per loop), whether it is among `indices`: the rows left out are found
    /// without searching them (`Damped::reproduction`).
    is_kept: Vec<bool>,
    /// Whether every loop keeps exactly three rows, contiguous in `indices`
    /// (`triples::kept_by_threes`): A is then factored by 3 × 3 blocks, whatever the form.
    by_threes: bool,
    scales: Vec<f64>,
    firm: usize,
    /// A = GₛGₛᵀ, undamped, and the products that fill it.
    normal: Envelope,
    plan: NormalPlan,
    /// Per column of G, the entries of the kept rows over it: (kept row, entry). The same for
    /// every state as long as the same rows are kept.
    by_column: Vec<Vec<(usize, usize)>>,
    /// `dense_null_space`, once asked for.
    null_space: OnceCell<DMatrix<f64>>,
}

/// The kept rows are dependent at this state: it is exactly a singular configuration. The row
/// (among the 6 per loop) that lost its independence.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Singular {
    pub row: usize,
}

/// The Cholesky factor L of A + μ²E (A = LLᵀ), with the rows it was made from.
pub struct Damped<'f> {
    factored: &'f Factored,
    factor: Envelope,
}

impl Factored {
    pub fn new(jacobian: &ConstraintJacobian, choice: &RowChoice) -> Factored {
        let mut factored = Factored {
            rows: KeptRows::default(),
            columns: 0,
            indices: Vec::new(),
            is_kept: Vec::new(),
            by_threes: false,
            scales: Vec::new(),
            firm: 0,
            normal: Envelope::default(),
            plan: NormalPlan::default(),
            by_column: Vec::new(),
            null_space: OnceCell::new(),
        };
        factored.lay_out(jacobian, choice);
        factored.refill(jacobian, choice);
        factored
    }

    /// The kept rows of another G (or another choice), in this factorisation's storage: once it
    /// has seen rows of that size, nothing is allocated. The rows' layout, where each column
    /// stands in them and the products filling A are found again only when the choice changes.
    pub fn refill(&mut self, jacobian: &ConstraintJacobian, choice: &RowChoice) {
        if self.indices != choice.rows || self.columns != jacobian.ncols() {
            self.lay_out(jacobian, choice);
        }
        self.scales.clone_from(&choice.scales);
        self.firm = choice.firm();
        self.rows.gather(jacobian, &self.scales);
        self.plan.fill(&self.rows.values, &mut self.normal);
        self.null_space = OnceCell::new();
    }

    /// The values of the same rows of another G (at nearby positions), leaving A as it was:
    /// for steps that keep a factor taken at the positions where they began
    /// (`loops::project_from`). A later `damped_in` would factor the earlier A: `refill` first.
    pub fn regather(&mut self, jacobian: &ConstraintJacobian) {
        self.rows.gather(jacobian, &self.scales);
        self.null_space = OnceCell::new();
    }

    /// The layout of `choice`'s rows of `jacobian`, filled by `refill`.
    fn lay_out(&mut self, jacobian: &ConstraintJacobian, choice: &RowChoice) {
        self.indices.clone_from(&choice.rows);
        self.is_kept.clear();
        self.is_kept.resize(jacobian.nrows(), false);
        for &row in &self.indices {
            self.is_kept[row] = true;
        }
        self.by_threes = triples::kept_by_threes(&self.indices, jacobian.nrows() / 6);
        self.columns = jacobian.ncols();
        self.rows.lay_out(jacobian, &self.indices);
        self.index_columns();
        self.plan
            .lay_out(jacobian, &self.rows, &self.indices, &mut self.normal);
    }

    /// `by_column` for the rows now held.
    fn index_columns(&mut self) {
        self.by_column.iter_mut().for_each(Vec::clear);
        self.by_column.resize_with(self.columns, Vec::new);
        for k in 0..self.rows.len() {
            for entry in self.rows.starts[k]..self.rows.starts[k + 1] {
                self.by_column[self.rows.columns[entry]].push((k, entry));
            }
        }
    }

    /// Whether these are the rows of `choice`.
    pub fn holds(&self, choice: &RowChoice) -> bool {
        self.indices == choice.rows && self.scales == choice.scales && self.firm == choice.firm()
    }

    /// The factorisation of these rows from a factor already taken of them (`damped_in`, then
    /// `Damped::into_storage`) with the rows unchanged since: no work, no allocation.
    pub fn with_factor(&self, factor: Envelope) -> Damped<'_> {
        Damped {
            factored: self,
            factor,
        }
    }

    /// How many columns G has (the coordinates the rows are over).
    pub fn columns(&self) -> usize {
        self.columns
    }

    /// How many rows are kept.
    pub fn len(&self) -> usize {
        self.rows.len()
    }

    #[cfg(lsdc_internals)]
    pub fn is_empty(&self) -> bool {
        self.rows.len() == 0
    }

    /// The kept rows of a vector of rows (6 per loop), made dimensionless.
    pub fn kept(&self, all: &DVector<f64>) -> DVector<f64> {
        let mut out = vec![0.0; self.len()];
        self.kept_into(all.as_slice(), &mut out);
        DVector::from_vec(out)
    }

    /// `kept` into `out` (resized to the kept rows).
    pub fn kept_into(&self, all: &[f64], out: &mut Vec<f64>) {
        out.clear();
        out.extend(
            self.indices
                .iter()
                .zip(&self.scales)
                .map(|(&r, s)| all[r] * s),
        );
    }

    /// Kept row k of Gₛ (made dimensionless) as (column, value) pairs, over its loop's columns.
    pub fn row_entries(&self, k: usize) -> impl Iterator<Item = (usize, f64)> + '_ {
        self.rows.row(k)
    }

    /// Column `column` of Gₛ into `out` (resized to the kept rows).
    fn column_into(&self, column: usize, out: &mut Vec<f64>) {
        out.clear();
        out.resize(self.rows.len(), 0.0);
        for &(k, entry) in &self.by_column[column] {
            out[k] = self.rows.values[entry];
        }
    }

    /// Gₛ x into `out` (resized to the kept rows).
    pub fn times_into(&self, x: &[f64], out: &mut Vec<f64>) {
        out.clear();
        out.extend(
            self.rows
                .iter()
                .map(|row| row.map(|(c, value)| value * x[c]).sum::<f64>()),
        );
    }

    /// Gₛᵀ y.
    pub fn transpose_times(&self, y: &DVector<f64>) -> DVector<f64> {
        let mut out = DVector::zeros(self.columns);
        self.transpose_times_into(y.as_slice(), out.as_mut_slice());
        out
    }

    /// Gₛᵀ y into `out` (of G's columns).
    pub fn transpose_times_into(&self, y: &[f64], out: &mut [f64]) {
        out.fill(0.0);
        for (row, &weight) in self.rows.iter().zip(y) {
            for (c, value) in row {
                out[c] += value * weight;
            }
        }
    }

    /// `transpose_times_into` of y into `y_out` and of z into `z_out` in one pass over the
    /// rows: each output summed in the same order as alone (the same results).
    fn transpose_times_pair_into(
        &self,
        (y, z): (&[f64], &[f64]),
        (y_out, z_out): (&mut [f64], &mut [f64]),
    ) {
        y_out.fill(0.0);
        z_out.fill(0.0);
        for ((row, &y_weight), &z_weight) in self.rows.iter().zip(y).zip(z) {
            for (c, value) in row {
                y_out[c] += value * y_weight;
                z_out[c] += value * z_weight;
            }
        }
    }

    /// The factorisation of A + μ²E, with μ = `damping` times the largest diagonal entry of the
    /// undamped factor (the largest row's independent length) and E the identity on the firm
    /// rows, zero on the weak ones: A⁻¹ wherever the rows are independent, bounded where the
    /// firm rows lose their independence.
    pub fn damped(&self, damping: f64) -> Result<Damped<'_>, Singular> {
        self.damped_in(damping, Envelope::default())
    }

    /// `damped`, factored in the storage of `factor` (from `Damped::into_storage`): nothing is
    /// allocated once it has held a factor of this size. Factored by 3 × 3 blocks where every
    /// loop keeps three contiguous rows (`by_threes`), row by row otherwise: the same factor to
    /// round-off.
    pub fn damped_in(&self, damping: f64, mut factor: Envelope) -> Result<Damped<'_>, Singular> {
        let largest = self.normal.largest_diagonal().sqrt();
        let shift = (damping * largest).powi(2);
        factor.copy_from(&self.normal);
        for k in 0..self.firm {
            let at = factor.index(k, k);
            factor.values[at] += shift;
        }
        let factored = if self.by_threes {
            factor.cholesky_by_triples()
        } else {
            factor.cholesky()
        };
        factored.map_err(|k| Singular {
            row: self.indices[k],
        })?;
        Ok(Damped {
            factored: self,
            factor,
        })
    }

    /// The smallest x with Gₛx = b (b as from `kept`), or the row lost at a singularity.
    pub fn least_norm(&self, b: &DVector<f64>) -> Result<DVector<f64>, Singular> {
        Ok(self.damped(0.0)?.least_norm(b))
    }

    /// How far the firm rows are from dependent (`Damped::conditioning`, with `DAMPING`); 0 at
    /// the row whose pivot vanished when they cannot be factored.
    pub fn conditioning(&self) -> (f64, Option<usize>) {
        self.conditioning_of(&self.damped(DAMPING))
    }

    /// `conditioning` from a factorisation already taken with `DAMPING`.
    pub fn conditioning_of(&self, damped: &Result<Damped<'_>, Singular>) -> (f64, Option<usize>) {
        if self.firm == 0 {
            return (1.0, None);
        }
        match damped {
            Ok(damped) => damped.conditioning(),
            Err(lost) => (0.0, Some(lost.row)),
        }
    }

    /// Whether a kept row has `column` among the columns it is stored over (the loops' columns
    /// are found once per model, so a column outside them never moves with a kept row).
    pub fn touches(&self, column: usize) -> bool {
        self.by_column.get(column).is_some_and(|at| !at.is_empty())
    }

    /// An orthonormal basis of the motions the kept rows allow, from a dense QR factorisation
    /// (taken once per `Factored`): for the decisions taken once and for the variational
    /// integrator's small systems, not for the equations of motion.
    pub fn dense_null_space(&self) -> &DMatrix<f64> {
        self.null_space
            .get_or_init(|| self.orthonormal_null_space())
    }

    /// The sparse elimination of the kept rows, every row of non-zero part picked
    /// (`elimination::pivoted`): its `null_space` spans the allowed motions, its `row_space`
    /// the kept rows.
    pub fn sparse_elimination(&self) -> Elimination {
        let rows: Vec<Sparse> = (self.rows.iter())
            .map(|row| row.filter(|&(_, value)| value != 0.0).collect())
            .collect();
        let every: Vec<usize> = (0..rows.len()).collect();
        pivoted(rows, self.columns, &every, 0.0)
    }

    fn orthonormal_null_space(&self) -> DMatrix<f64> {
        let (n, r) = (self.columns, self.rows.len());
        if r == 0 {
            return DMatrix::identity(n, n);
        }
        let mut transposed = DMatrix::zeros(n, r);
        for (k, row) in self.rows.iter().enumerate() {
            for (c, value) in row {
                transposed[(c, k)] = value;
            }
        }
        let qr = transposed.qr();
        let mut q_transposed = DMatrix::identity(n, n);
        qr.q_tr_mul(&mut q_transposed);
        q_transposed.transpose().columns(r, n - r).into_owned()
    }
}

impl Damped<'_> {
    /// How far the firm rows are from dependent: the smallest diagonal entry of the factor over
    /// the largest, among the firm rows (1 for rows orthogonal and of equal length, 0 at a
    /// singular configuration), and the row (among the 6 per loop) of the smallest.
    pub fn conditioning(&self) -> (f64, Option<usize>) {
        let firm = self.factored.firm;
        if firm == 0 {
            return (1.0, None);
        }
        let diagonal = || self.factor.diagonal().take(firm);
        let largest = diagonal().fold(0.0, f64::max);
        let (smallest, value) =
            diagonal()
                .enumerate()
                .fold((0, f64::INFINITY), |a, b| if b.1 < a.1 { b } else { a });
        let ratio = if largest > 0.0 { value / largest } else { 0.0 };
        (ratio, Some(self.factored.indices[smallest]))
    }

    /// The factor's storage, to factor again without allocating (`Factored::damped_in`).
    pub fn into_storage(self) -> Envelope {
        self.factor
    }

    /// (A + μ²E)⁻¹ b.
    pub fn normal_solve(&self, b: &DVector<f64>) -> DVector<f64> {
        let mut y = b.clone();
        self.factor.solve(y.as_mut_slice());
        y
    }

    /// Gₛᵀ(A + μ²E)⁻¹ b: the smallest x with Gₛx = b where the rows are independent.
    pub fn least_norm(&self, b: &DVector<f64>) -> DVector<f64> {
        self.factored.transpose_times(&self.normal_solve(b))
    }

    /// `least_norm` of b (consumed as scratch) into `out` (of G's columns).
    pub fn least_norm_into(&self, b: &mut [f64], out: &mut [f64]) {
        self.factor.solve(b);
        self.factored.transpose_times_into(b, out);
    }

    /// `least_norm_into` of b into `out`, then `allowed_motions_into` of `free` into `basis`
    /// from its first column, with `rows` as scratch: the first motion's solve is taken beside
    /// b's (`Envelope::solve_pair`). Each triangular solve is a chain of dependent divisions;
    /// two taken together fill each other's waits, with the same operations on each, so the
    /// same results as one after the other.
    pub fn least_norm_and_allowed_motions_into(
        &self,
        b: &mut [f64],
        out: &mut [f64],
        free: &[usize],
        rows: &mut Vec<f64>,
        basis: &mut DMatrix<f64>,
    ) {
        let Some(&first) = free.first() else {
            return self.least_norm_into(b, out);
        };
        self.factored.column_into(first, rows);
        if rows.iter().all(|&g| g == 0.0) {
            self.least_norm_into(b, out);
            return self.allowed_motions_into(free, rows, basis, 0);
        }
        self.factor.solve_pair(b, rows);
        let mut column = basis.column_mut(0);
        (self.factored).transpose_times_pair_into((b, rows), (out, column.as_mut_slice()));
        column.neg_mut();
        column[first] += 1.0;
        self.allowed_motions_into(&free[1..], rows, basis, 1);
    }

    /// v − Gₛᵀ(A + μ²E)⁻¹Gₛv into `out`, with `rows` as scratch: v without its part across the
    /// kept rows. Damped, near a singular configuration a velocity off the rows by a small error
    /// is not thrown along the direction they are about to lose (which would kick a
    /// parallelogram onto its other branch).
    pub fn allowed_part_into(&self, v: &[f64], rows: &mut Vec<f64>, out: &mut [f64]) {
        self.factored.times_into(v, rows);
        self.least_norm_into(rows, out);
        for (o, x) in out.iter_mut().zip(v) {
            *o = x - *o;
        }
    }

    /// How well the kept rows reproduce the active rows of G left out (`active`, 6 per loop):
    /// the smallest, over those rows g, of 1/√(1 + |c|²) for the coefficients c of g's
    /// least-squares combination of the kept rows (all dimensionless, each with its loop's length): 1 for a
    /// row at round-off, about 1/|c| for one the kept rows reproduce only with large
    /// coefficients, which off the closed set is violated |c| times more than they are. On the
    /// closed set and with one row left out, 1/√(1 + |c|²) is that row's share of the unit
    /// dependency among the rows. `row` and `coefficients` are scratch.
    pub fn reproduction(
        &self,
        jacobian: &ConstraintJacobian,
        active: &[bool],
        lengths: &[f64],
        row: &mut Vec<f64>,
        coefficients: &mut Vec<f64>,
    ) -> f64 {
        let factored = self.factored;
        let largest = (factored.rows.values.iter()).fold(0.0_f64, |m, v| m.max(v.abs()));
        let mut smallest = 1.0_f64;
        for r in (0..jacobian.nrows()).filter(|&r| active[r] && !factored.is_kept[r]) {
            let scale = loop_row_scale(r, lengths);
            let size = jacobian
                .row(r)
                .fold(0.0_f64, |m, (_, v)| m.max((v * scale).abs()));
            // Rows at round-off (out of the plane of a planar loop) could never be kept.
            if size <= KEEP_TOLERANCE * largest {
                continue;
            }
            row.clear();
            row.resize(factored.columns, 0.0);
            for (column, value) in jacobian.row(r) {
                row[column] = value * scale;
            }
            factored.times_into(row, coefficients);
            self.factor.solve(coefficients);
            let size: f64 = coefficients.iter().map(|c| c * c).sum();
            smallest = smallest.min(1.0 / (1.0 + size).sqrt());
        }
        smallest
    }

    /// λ into `all`, 6 per loop (zero on the rows not kept), with Gᵀλ = y for y in the kept
    /// rows' span; `rows` is scratch.
    pub fn multipliers_into(&self, y: &[f64], rows: &mut Vec<f64>, all: &mut [f64]) {
        self.factored.times_into(y, rows);
        self.factor.solve(rows);
        all.fill(0.0);
        let factored = self.factored;
        for ((&row, scale), kept) in factored.indices.iter().zip(&factored.scales).zip(rows) {
            all[row] = *kept * scale;
        }
    }

    /// The motions the kept rows allow, one per coordinate of `free`: the allowed part of that
    /// coordinate's unit motion. They span the allowed motions when `free` parametrises them
    /// (`Structure` chooses it so); unlike an orthonormal basis, they cost one sparse solve
    /// each.
    pub fn allowed_motions(&self, free: &[usize]) -> DMatrix<f64> {
        let mut basis = DMatrix::zeros(self.factored.columns, free.len());
        self.allowed_motions_into(free, &mut Vec::new(), &mut basis, 0);
        basis
    }

    /// `allowed_motions` into the columns of `basis` (of G's columns) from `first` on, with
    /// `rows` as scratch.
    pub fn allowed_motions_into(
        &self,
        free: &[usize],
        rows: &mut Vec<f64>,
        basis: &mut DMatrix<f64>,
        first: usize,
    ) {
        for (k, &coordinate) in free.iter().enumerate() {
            // The allowed part of a unit motion eᵢ: eᵢ − Gₛᵀ(A + μ²E)⁻¹Gₛeᵢ, Gₛeᵢ being column i.
            self.factored.column_into(coordinate, rows);
            let mut column = basis.column_mut(first + k);
            if rows.iter().all(|&g| g == 0.0) {
                // No kept row moves with this coordinate (a ball's own angles): its unit motion
                // is allowed as it is, and the solve of a zero right-hand side can be skipped
                // (the same entries: −0 off the coordinate, 1 on it).
                column.fill(-0.0);
            } else {
                self.least_norm_into(rows, column.as_mut_slice());
                column.neg_mut();
            }
            column[coordinate] += 1.0;
        }
    }

    /// How well the coordinates `free` parametrise the motions the kept rows allow: the smallest
    /// squared pivot (at most 1) of a Cholesky factorisation of the block over `free` of the
    /// projector onto them, P = I − Gₛᵀ(A + μ²E)⁻¹Gₛ; 1 when the allowed motions are exactly
    /// the free coordinates' own, 0 when the free coordinates no longer parametrise them (the
    /// block is then singular). With A + μ²E = LLᵀ the block is I − XᵀX for X = L⁻¹Gₛ over the
    /// free columns: one forward substitution per free coordinate. `rows`, `columns` (X) and
    /// `work` (the block) are scratch, sized here; nothing is allocated once they have their
    /// sizes.
    pub fn free_quality_into(
        &self,
        free: &[usize],
        rows: &mut Vec<f64>,
        columns: &mut DMatrix<f64>,
        work: &mut DMatrix<f64>,
    ) -> f64 {
        let (r, n) = (self.factored.len(), free.len());
        if columns.shape() != (r, n) {
            *columns = DMatrix::zeros(r, n);
        }
        if work.shape() != (n, n) {
            *work = DMatrix::zeros(n, n);
        }
        for (k, &coordinate) in free.iter().enumerate() {
            self.factored.column_into(coordinate, rows);
            self.factor.forward(rows);
            columns.column_mut(k).copy_from_slice(rows);
        }
        for j in 0..n {
            for i in j..n {
                let identity = if i == j { 1.0 } else { 0.0 };
                work[(i, j)] = identity - columns.column(i).dot(&columns.column(j));
            }
        }
        projector_block_quality(work, n)
    }
}

/// The free coordinates' quality from the projector's block over them, in the leading n × n
/// lower triangle of `work` (factored in place): its smallest squared Cholesky pivot, at most
/// 1, or 0 when it is not positive definite.
pub fn projector_block_quality(work: &mut DMatrix<f64>, n: usize) -> f64 {
    dense_cholesky(work, n).map_or(0.0, |(smallest, _)| smallest.min(1.0))
}

/// A symmetric matrix stored by rows from each row's first non-zero entry to the diagonal; the
/// Cholesky factor of such a matrix lives in the same envelope. The rows lie end to end in one
/// vector, so that copying a matrix into a factor's storage is one copy.
#[derive(Clone, Debug, Default)]
pub struct Envelope {
    first: Vec<usize>,
    /// Row k holds columns first[k]..=k at values[starts[k]..starts[k + 1]].
    starts: Vec<usize>,
    values: Vec<f64>,
    /// Whether the rows are laid out by blocks of three (`triples::by_triples`).
    triples: bool,
    /// The diagonal blocks of a factor taken by blocks of three rows (`cholesky_by_triples`),
    /// which its substitutions take; empty for a factor taken row by row.
    blocks: Vec<DiagonalBlock>,
}

impl Envelope {
    /// The envelope of rows starting at the columns `first` (each at most its row), zeroed.
    fn shape(&mut self, first: impl Iterator<Item = usize>) {
        self.first.clear();
        self.first.extend(first);
        self.starts.clear();
        self.starts.push(0);
        for (k, &fk) in self.first.iter().enumerate() {
            self.starts.push(self.starts[k] + k - fk + 1);
        }
        self.values.clear();
        self.values
            .resize(*self.starts.last().expect("a start"), 0.0);
        self.triples = triples::by_triples(&self.first);
        self.blocks.clear();
    }

    fn len(&self) -> usize {
        self.first.len()
    }

    /// Where row k's entry in column l (within its envelope) is stored.
    fn index(&self, k: usize, l: usize) -> usize {
        self.starts[k] + l - self.first[k]
    }

    /// y ← L⁻¹ y for the factor L held.
    fn forward(&self, y: &mut [f64]) {
        if !self.blocks.is_empty() {
            let envelope = (&self.first[..], &self.starts[..], &self.values[..]);
            return triples::forward(envelope, &self.blocks, [y]);
        }
        for (k, bound) in self.starts.windows(2).enumerate().take(y.len()) {
            let (left, diagonal) = split_diagonal(&self.values[bound[0]..bound[1]]);
            let (done, rest) = y.split_at_mut(k);
            let dot = in_order_dot(left, &done[k - left.len()..]);
            rest[0] = (rest[0] - dot) / diagonal;
        }
    }

    /// y ← (LLᵀ)⁻¹ y and z ← (LLᵀ)⁻¹ z together (of one length), each by the operations of
    /// `solve` in the same order: the same results, with the two chains of dependent divisions
    /// interleaved.
    fn solve_pair(&self, y: &mut [f64], z: &mut [f64]) {
        assert_eq!(y.len(), z.len(), "two right-hand sides of one length");
        if !self.blocks.is_empty() {
            return self.solve_by_triples([y, z]);
        }
        let count = y.len();
        let rows = || self.starts.windows(2).take(count).enumerate();
        for (k, bound) in rows() {
            let (left, diagonal) = split_diagonal(&self.values[bound[0]..bound[1]]);
            let (y_done, y_rest) = y.split_at_mut(k);
            let (z_done, z_rest) = z.split_at_mut(k);
            let y_dot = in_order_dot(left, &y_done[k - left.len()..]);
            let z_dot = in_order_dot(left, &z_done[k - left.len()..]);
            y_rest[0] = (y_rest[0] - y_dot) / diagonal;
            z_rest[0] = (z_rest[0] - z_dot) / diagonal;
        }
        for (k, bound) in rows().rev() {
            let (left, diagonal) = split_diagonal(&self.values[bound[0]..bound[1]]);
            let (y_done, y_rest) = y.split_at_mut(k);
            let (z_done, z_rest) = z.split_at_mut(k);
            y_rest[0] /= diagonal;
            z_rest[0] /= diagonal;
            let (y_value, z_value) = (y_rest[0], z_rest[0]);
            let targets = y_done[k - left.len()..].iter_mut();
            for ((y_target, z_target), entry) in
                targets.zip(&mut z_done[k - left.len()..]).zip(left)
            {
                *y_target -= entry * y_value;
                *z_target -= entry * z_value;
            }
        }
    }

    /// `other`'s entries in this envelope's storage (a derived `clone_from` would allocate anew).
    /// The shape is copied only when it differs: a factor taken again of the same rows has it
    /// already, and comparing costs less than copying.
    fn copy_from(&mut self, other: &Envelope) {
        if self.first != other.first {
            self.first.clone_from(&other.first);
            self.starts.clone_from(&other.starts);
            self.triples = other.triples;
        }
        self.values.clone_from(&other.values);
        self.blocks.clear();
    }

    /// The Cholesky factor in place by blocks of three rows (`triples`), where the envelope is laid
    /// out by them, otherwise row by row (`cholesky`); the first row whose pivot is not
    /// positive.
    fn cholesky_by_triples(&mut self) -> Result<(), usize> {
        if !self.triples || self.first.is_empty() {
            return self.cholesky();
        }
        let factored = triples::cholesky(
            &self.first,
            &self.starts,
            &mut self.values,
            &mut self.blocks,
        );
        if factored.is_err() {
            self.blocks.clear();
        }
        factored
    }

    /// (LLᵀ)⁻¹ y for each y of `ys`, for a factor taken by blocks.
    fn solve_by_triples<const N: usize>(&self, mut ys: [&mut [f64]; N]) {
        let envelope = (&self.first[..], &self.starts[..], &self.values[..]);
        triples::forward(envelope, &self.blocks, ys.each_mut().map(|y| &mut **y));
        triples::backward(envelope, &self.blocks, ys);
    }

    fn diagonal(&self) -> impl Iterator<Item = f64> + '_ {
        self.starts[1..].iter().map(|&end| self.values[end - 1])
    }

    /// The largest diagonal entry (at least 0): `diagonal`'s largest, taken in four running
    /// maxima so that each comparison does not wait on the one before (the maximum is the
    /// same in any order).
    fn largest_diagonal(&self) -> f64 {
        let mut largest = [0.0f64; 4];
        let ends = self.starts[1..].chunks_exact(4);
        let rest = ends.remainder();
        for chunk in ends {
            for (running, &end) in largest.iter_mut().zip(chunk) {
                *running = running.max(self.values[end - 1]);
            }
        }
        let rest = rest.iter().map(|&end| self.values[end - 1]);
        rest.fold(
            largest[0].max(largest[1]).max(largest[2].max(largest[3])),
            f64::max,
        )
    }

    /// The Cholesky factor in place, or the first row whose pivot is not positive. Rows are
    /// taken three at a time (`cholesky_triple`: a planar loop's kept rows), the last one or
    /// two as a pair (`cholesky_pair`) or alone.
    fn cholesky(&mut self) -> Result<(), usize> {
        let mut k = 0;
        while k + 2 < self.len() {
            self.cholesky_triple(k)?;
            k += 3;
        }
        match self.len() - k {
            2 => self.cholesky_pair(k),
            1 => self.cholesky_row(k),
            _ => Ok(()),
        }
    }

    /// Rows k, k + 1 and k + 2 of the Cholesky factor, rows before them done: `cholesky_pair`
    /// with a third row. The three rows' entries left of column k wait on none of the three,
    /// so they are taken column by column together (three chains of dependent divisions
    /// interleaved), each by the operations of `cholesky_row` in the same order (the same
    /// results); then the entries in columns k and k + 1, each after its row's diagonal.
    fn cholesky_triple(&mut self, k: usize) -> Result<(), usize> {
        let (fa, fb, fc) = (self.first[k], self.first[k + 1], self.first[k + 2]);
        let (above, below) = self.values.split_at_mut(self.starts[k]);
        let (row_a, rest) = below.split_at_mut(k - fa + 1);
        let (row_b, rest) = rest.split_at_mut(k + 2 - fb);
        let row_c = &mut rest[..k + 3 - fc];
        let from = fa.min(fb).min(fc);
        for (j, bound) in self.starts.windows(2).enumerate().take(k).skip(from) {
            let (left, pivot) = split_diagonal(&above[bound[0]..bound[1]]);
            if j >= fa {
                eliminate(row_a, j - fa, left, pivot);
            }
            if j >= fb {
                eliminate(row_b, j - fb, left, pivot);
            }
            if j >= fc {
                eliminate(row_c, j - fc, left, pivot);
            }
        }
        finish_diagonal(row_a).map_err(|()| k)?;
        let (left, pivot) = split_diagonal(row_a);
        if fb <= k {
            eliminate(row_b, k - fb, left, pivot);
        }
        if fc <= k {
            eliminate(row_c, k - fc, left, pivot);
        }
        finish_diagonal(row_b).map_err(|()| k + 1)?;
        if fc <= k + 1 {
            let (left, pivot) = split_diagonal(row_b);
            eliminate(row_c, k + 1 - fc, left, pivot);
        }
        finish_diagonal(row_c).map_err(|()| k + 2)
    }

    /// Rows k and k + 1 of the Cholesky factor, rows before them done. Each entry of a row is a
    /// division waiting on the row's entries before it; row k + 1's entries left of column k do
    /// not wait on row k, so the two rows' entries are taken column by column together, each
    /// by the operations of `cholesky_row` in the same order (the same results). Then row k's
    /// diagonal, row k + 1's entry in column k, and its diagonal.
    fn cholesky_pair(&mut self, k: usize) -> Result<(), usize> {
        let (fk, fl) = (self.first[k], self.first[k + 1]);
        let (above, below) = self.values.split_at_mut(self.starts[k]);
        let (row_k, rest) = below.split_at_mut(k - fk + 1);
        let row_l = &mut rest[..k + 2 - fl];
        for (j, bound) in self.starts.windows(2).enumerate().take(k).skip(fk.min(fl)) {
            let (left, pivot) = split_diagonal(&above[bound[0]..bound[1]]);
            if j >= fk {
                eliminate(row_k, j - fk, left, pivot);
            }
            if j >= fl {
                eliminate(row_l, j - fl, left, pivot);
            }
        }
        finish_diagonal(row_k).map_err(|()| k)?;
        if fl <= k {
            let (left, pivot) = split_diagonal(row_k);
            eliminate(row_l, k - fl, left, pivot);
        }
        finish_diagonal(row_l).map_err(|()| k + 1)
    }

    /// Row k of the Cholesky factor, rows before it done.
    fn cholesky_row(&mut self, k: usize) -> Result<(), usize> {
        let (fk, start) = (self.first[k], self.starts[k]);
        let (above, below) = self.values.split_at_mut(start);
        let row = &mut below[..k - fk + 1];
        // Rows fk..k of the factor, each with its envelope's bounds: zipped, so that the loop
        // over them slices without looking the bounds up one by one.
        let bounds = self.starts[fk..=k].windows(2);
        for (done, bound) in (0..).zip(bounds) {
            let (left, pivot) = split_diagonal(&above[bound[0]..bound[1]]);
            eliminate(row, done, left, pivot);
        }
        finish_diagonal(row).map_err(|()| k)
    }

    /// y ← (LLᵀ)⁻¹ y for the factor L held.
    fn solve(&self, y: &mut [f64]) {
        if !self.blocks.is_empty() {
            return self.solve_by_triples([y]);
        }
        self.forward(y);
        let rows = self.starts.windows(2).take(y.len()).enumerate();
        for (k, bound) in rows.rev() {
            let (left, diagonal) = split_diagonal(&self.values[bound[0]..bound[1]]);
            let (done, rest) = y.split_at_mut(k);
            rest[0] /= diagonal;
            let value = rest[0];
            for (target, entry) in done[k - left.len()..].iter_mut().zip(left) {
                *target -= entry * value;
            }
        }
    }
}

/// How A = RRᵀ is filled for the kept rows R (`KeptRows`): per entry of A's envelope whose two
/// rows share columns, the pairs of R's entries over those columns, in increasing column order.
/// Row k's envelope starts at the first kept row of a loop sharing columns with its own. Laid
/// out once per choice of rows; each state then costs one dot product per entry.
#[derive(Default)]
struct NormalPlan {
    /// (index in A's envelope storage, end of its pairs in `pairs`): an entry's pairs follow the
    /// previous entry's.
    entries: Vec<(usize, usize)>,
    pairs: Vec<(usize, usize)>,
}

impl NormalPlan {
    /// The plan for the kept rows `rows` of `jacobian` (rows `indices` among the 6 per loop),
    /// and `normal`'s envelope shaped for it.
    fn lay_out(
        &mut self,
        jacobian: &ConstraintJacobian,
        rows: &KeptRows,
        indices: &[usize],
        normal: &mut Envelope,
    ) {
        let mut by_loop = vec![Vec::new(); jacobian.blocks.len()];
        for (k, &row) in indices.iter().enumerate() {
            by_loop[row / 6].push(k);
        }
        let neighbours = |k: usize| jacobian.neighbours[indices[k] / 6].iter();
        normal.shape((0..indices.len()).map(|k| {
            neighbours(k)
                .filter_map(|n| by_loop[n.other].first().copied())
                .fold(k, usize::min)
        }));
        self.entries.clear();
        self.pairs.clear();
        for k in 0..indices.len() {
            for neighbour in neighbours(k) {
                for &l in by_loop[neighbour.other].iter().filter(|&&l| l <= k) {
                    let (here, there) = (rows.starts[k], rows.starts[l]);
                    self.pairs
                        .extend(neighbour.shared.iter().map(|&(i, j)| (here + i, there + j)));
                    self.entries.push((normal.index(k, l), self.pairs.len()));
                }
            }
        }
    }

    /// A's entries from the rows' `values`.
    fn fill(&self, values: &[f64], normal: &mut Envelope) {
        let mut start = 0;
        for &(at, end) in &self.entries {
            normal.values[at] = self.pairs[start..end]
                .iter()
                .fold(0.0, |sum, &(i, j)| sum + values[i] * values[j]);
            start = end;
        }
    }
}

/// Entry `done` of an envelope row of the Cholesky factor, its entries before it done, from
/// the factor's row of that column (`left` of its diagonal `pivot`): their common columns are
/// the last of each.
fn eliminate(row: &mut [f64], done: usize, left: &[f64], pivot: f64) {
    let (row_left, rest) = row.split_at_mut(done);
    let common = done.min(left.len());
    let dot = in_order_dot(&row_left[done - common..], &left[left.len() - common..]);
    rest[0] = (rest[0] - dot) / pivot;
}

/// The diagonal of an envelope row of the Cholesky factor, its entries left of it done; an
/// error where the pivot is not positive.
fn finish_diagonal(row: &mut [f64]) -> Result<(), ()> {
    let (diagonal, left) = row.split_last_mut().expect("a diagonal");
    let square = *diagonal - left.iter().map(|x| x * x).sum::<f64>();
    if !(square > 0.0 && square.is_finite()) {
        return Err(());
    }
    *diagonal = square.sqrt();
    Ok(())
}

/// An envelope row's entries left of its diagonal, and the diagonal.
fn split_diagonal(row: &[f64]) -> (&[f64], f64) {
    let (diagonal, left) = row.split_last().expect("a diagonal");
    (left, *diagonal)
}

/// Σ aᵢbᵢ summed in increasing i, over slices of the same length (zipped, so that the loop
/// carries no bounds checks).
fn in_order_dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).fold(0.0, |sum, (x, y)| sum + x * y)
}
