//! An orthogonal elimination of a matrix's rows on their sparsity, for the decisions taken once
//! on the loops' constraint rows G (the rows kept, the rank reported, the allowed motions, the
//! closure's minimum-norm steps): each
//! row picked is reflected onto one of its columns by a Householder reflection acting on the
//! columns (an LQ factorisation, G Q = [L 0], taken row by row), and the rows not yet picked
//! keep only their part orthogonal to those picked. A row's part meets only the rows that share
//! a column with it, so a chain of loops (the ladder) costs what its length costs, where a
//! dense Gram–Schmidt on G costs its cube. The parts are those of Gram–Schmidt on the same rows
//! in the same order (an orthogonal transformation of the columns changes no inner product:
//! Golub & Van Loan, Matrix Computations, 4th ed., §5.2 and §5.4 on column-pivoted QR, here on
//! the rows), so the choices are the dense ones' up to round-off.

use std::cmp::Reverse;
use std::collections::BTreeSet;

use nalgebra::{DMatrix, DVector};

/// A sparse vector: (column, value) pairs in increasing column order.
pub type Sparse = Vec<(usize, f64)>;

/// A reflection I − β v vᵀ that maps the part of a picked row onto its pivot column.
struct Reflector {
    v: Sparse,
    beta: f64,
    pivot: usize,
}

/// The elimination of a set of rows (over `columns` columns), one picked row at a time.
pub struct Elimination {
    columns: usize,
    /// Per row, its part orthogonal to the rows picked so far, over the columns not pivoted.
    parts: Vec<Sparse>,
    /// Per row, its coefficients along the picked rows' directions (pick index, value): the
    /// row's entries of L.
    coefficients: Vec<Vec<(usize, f64)>>,
    /// Per column, the rows whose part may have an entry over it.
    by_column: Vec<Vec<usize>>,
    reflectors: Vec<Reflector>,
    /// The rows picked, in order, with the size of their part when picked.
    picked: Vec<(usize, f64)>,
    is_picked: Vec<bool>,
    /// Scratch: the last reflection each row was met by (to visit it once per reflection).
    visited: Vec<usize>,
}

impl Elimination {
    /// The elimination of `rows` (sparse, over `columns` columns), nothing picked yet.
    pub fn new(rows: Vec<Sparse>, columns: usize) -> Elimination {
        let mut by_column = vec![Vec::new(); columns];
        for (r, row) in rows.iter().enumerate() {
            for &(c, _) in row {
                by_column[c].push(r);
            }
        }
        let count = rows.len();
        Elimination {
            columns,
            parts: rows,
            coefficients: vec![Vec::new(); count],
            by_column,
            reflectors: Vec::new(),
            picked: Vec::new(),
            is_picked: vec![false; count],
            visited: vec![usize::MAX; count],
        }
    }

    /// The size (Euclidean norm) of row `row`'s part orthogonal to the rows picked so far.
    pub fn size(&self, row: usize) -> f64 {
        norm(&self.parts[row])
    }

    /// The rows picked, in order, each with the size of its part when it was picked.
    pub fn picked(&self) -> &[(usize, f64)] {
        &self.picked
    }

    /// Picks `row`: its part becomes a pivot, and every row sharing a column with it keeps
    /// only its part orthogonal to it. Returns the rows whose part changed.
    pub fn pick(&mut self, row: usize) -> Vec<usize> {
        let x = std::mem::take(&mut self.parts[row]);
        let size = norm(&x);
        let index = self.reflectors.len();
        self.picked.push((row, size));
        self.is_picked[row] = true;
        if size == 0.0 {
            return Vec::new();
        }
        let at = (0..x.len())
            .max_by(|&a, &b| x[a].1.abs().total_cmp(&x[b].1.abs()))
            .expect("a row of non-zero size has an entry");
        let pivot = x[at].0;
        let sigma = size.copysign(x[at].1);
        let mut v = x;
        v[at].1 += sigma;
        let beta = 1.0 / (sigma * v[at].1);
        self.coefficients[row].push((index, -sigma));
        let mut changed = Vec::new();
        for &(c, _) in &v {
            for k in 0..self.by_column[c].len() {
                let other = self.by_column[c][k];
                if self.is_picked[other] || self.visited[other] == index {
                    continue;
                }
                self.visited[other] = index;
                changed.push(other);
            }
        }
        for &other in &changed {
            let part = &mut self.parts[other];
            let along = beta * dot(part, &v);
            let added = if along != 0.0 {
                axpy(part, -along, &v)
            } else {
                Vec::new()
            };
            // The entry over the pivot is the row's coefficient along the picked row.
            if let Ok(p) = part.binary_search_by_key(&pivot, |e| e.0) {
                let (_, coefficient) = part.remove(p);
                if coefficient != 0.0 {
                    self.coefficients[other].push((index, coefficient));
                }
            }
            for c in added.into_iter().filter(|&c| c != pivot) {
                self.by_column[c].push(other);
            }
        }
        self.reflectors.push(Reflector { v, beta, pivot });
        changed
    }

    /// Q w for w given over the columns (Q = H₁H₂⋯Hₖ, the reflections of the first `count`
    /// picks), in place.
    fn reflect_back(&self, count: usize, w: &mut [f64]) {
        for reflector in self.reflectors[..count].iter().rev() {
            let along: f64 = reflector.v.iter().map(|&(c, x)| x * w[c]).sum();
            if along != 0.0 {
                let along = reflector.beta * along;
                for &(c, x) in &reflector.v {
                    w[c] -= along * x;
                }
            }
        }
    }

    /// y's part orthogonal to the first `count` picked rows (y given over the columns), in
    /// place: Qᵀy with its entries over their pivots zeroed, then Q of that. The projection of
    /// Gram–Schmidt against the picked rows, each reflection touching only its own columns.
    pub fn orthogonal_part(&self, count: usize, y: &mut [f64]) {
        for reflector in &self.reflectors[..count] {
            let along: f64 = reflector.v.iter().map(|&(c, x)| x * y[c]).sum();
            if along != 0.0 {
                let along = reflector.beta * along;
                for &(c, x) in &reflector.v {
                    y[c] -= along * x;
                }
            }
        }
        for reflector in &self.reflectors[..count] {
            y[reflector.pivot] = 0.0;
        }
        self.reflect_back(count, y);
    }

    /// An orthonormal basis of the motions the first `count` picked rows allow: Q eⱼ for each
    /// column j none of them pivoted on.
    pub fn null_space(&self, count: usize) -> DMatrix<f64> {
        let mut pivoted = vec![false; self.columns];
        for reflector in &self.reflectors[..count] {
            pivoted[reflector.pivot] = true;
        }
        let free: Vec<usize> = (0..self.columns).filter(|&c| !pivoted[c]).collect();
        self.reflected_units(count, &free)
    }

    /// An orthonormal basis of the span of the first `count` picked rows: Q eⱼ for each column
    /// j they pivoted on (G Q = [L 0]: each row is a combination of those).
    pub fn row_space(&self, count: usize) -> DMatrix<f64> {
        let pivots: Vec<usize> = (self.reflectors[..count].iter())
            .map(|reflector| reflector.pivot)
            .collect();
        self.reflected_units(count, &pivots)
    }

    /// Q eⱼ for each column j of `units`, Q of the first `count` reflections.
    fn reflected_units(&self, count: usize, units: &[usize]) -> DMatrix<f64> {
        let mut basis = DMatrix::zeros(self.columns, units.len());
        for (k, &c) in units.iter().enumerate() {
            let mut column = basis.column_mut(k);
            column[c] = 1.0;
            self.reflect_back(count, column.as_mut_slice());
        }
        basis
    }

    /// The smallest change δ with Gₚ δ = −r over the first `count` picked rows Gₚ (r given per
    /// row of G): the minimum-norm solution, L w = −r forward, then δ = Q w.
    pub fn minimum_norm_correction(&self, count: usize, residual: &[f64]) -> DVector<f64> {
        let mut w = vec![0.0; count];
        for (i, &(row, _)) in self.picked[..count].iter().enumerate() {
            let mut sum = -residual[row];
            let mut diagonal = 0.0;
            for &(j, l) in &self.coefficients[row] {
                if j == i {
                    diagonal = l;
                } else if j < i {
                    sum -= l * w[j];
                }
            }
            w[i] = if diagonal != 0.0 { sum / diagonal } else { 0.0 };
        }
        let mut step = DVector::zeros(self.columns);
        for (i, reflector) in self.reflectors[..count].iter().enumerate() {
            step[reflector.pivot] = w[i];
        }
        self.reflect_back(count, step.as_mut_slice());
        step
    }
}

/// Pivoted Gram–Schmidt on sparse rows: at each step the row of `candidates` with the largest
/// part orthogonal to those taken (the lowest-numbered among equals), until that part is at
/// most `tolerance` times the largest of the candidates. The candidates are taken in blocks of
/// `PIVOTED_BLOCK` in their order, each block to its end before the next, where there are more
/// than `ONE_SEARCH_UP_TO` (a mechanism of up to a hundred loops of six rows is decided by one
/// search), so that a longer chain costs a block's search per block (see `PIVOTED_BLOCK`). A
/// part only shrinks as rows are taken, so a row left in its block at the tolerance would not
/// have been taken later. The elimination, its picks in the order taken.
pub fn pivoted(
    rows: Vec<Sparse>,
    columns: usize,
    candidates: &[usize],
    tolerance: f64,
) -> Elimination {
    let block = if candidates.len() <= ONE_SEARCH_UP_TO {
        ONE_SEARCH_UP_TO
    } else {
        PIVOTED_BLOCK
    };
    pivoted_in_blocks(rows, columns, candidates, tolerance, block)
}

/// `pivoted` with blocks of `block` candidates.
pub fn pivoted_in_blocks(
    rows: Vec<Sparse>,
    columns: usize,
    candidates: &[usize],
    tolerance: f64,
    block: usize,
) -> Elimination {
    let mut elimination = Elimination::new(rows, columns);
    let largest = (candidates.iter())
        .map(|&r| elimination.size(r))
        .fold(0.0, f64::max);
    let key = |size: f64, row: usize| (size.to_bits(), Reverse(row));
    let mut sizes = vec![0.0; elimination.parts.len()];
    for block in candidates.chunks(block.max(1)) {
        let mut queue = BTreeSet::new();
        for &r in block {
            sizes[r] = elimination.size(r);
            queue.insert(key(sizes[r], r));
        }
        while let Some((bits, Reverse(row))) = queue.pop_last() {
            let size = f64::from_bits(bits);
            if size <= tolerance * largest || size == 0.0 {
                break;
            }
            for other in elimination.pick(row) {
                if queue.remove(&key(sizes[other], other)) {
                    sizes[other] = elimination.size(other);
                    queue.insert(key(sizes[other], other));
                }
            }
        }
    }
    elimination
}

/// The most candidates `pivoted` searches together, in one search: the ladder of 100 loops,
/// and every mechanism of the examples and the tests, so their decisions and round-off are
/// those of the single search.
pub const ONE_SEARCH_UP_TO: usize = 600;

/// The candidates `pivoted` searches together beyond `ONE_SEARCH_UP_TO`. The search by largest
/// part ignores the rows' structure: on a chain of loops sharing columns (the ladder) it takes
/// every loop's rotation rows first (a rotation row is about N times a translation row made
/// dimensionless by the chain's length), and the translation rows' parts orthogonal to all of
/// them fill in: the last 2N picks of the ladder of N = 100 reflected rows over 202 to 2 of its
/// 302 columns, a dense block whose cost grows as N³. Taken block by block along the rows
/// (loop after loop, eight loops of six rows), a block's fill stays within the block and the
/// few columns it leaves unpivoted.
pub const PIVOTED_BLOCK: usize = 48;

/// Gram–Schmidt on sparse rows in the order of `candidates`: a row is taken when its part
/// orthogonal to the rows taken before it is above `tolerance` times `largest`. The rows
/// taken and the rows left, in order.
pub fn in_order(
    rows: Vec<Sparse>,
    columns: usize,
    candidates: &[usize],
    tolerance: f64,
    largest: f64,
) -> (Vec<usize>, Vec<usize>) {
    let mut elimination = Elimination::new(rows, columns);
    let (mut taken, mut left) = (Vec::new(), Vec::new());
    for &r in candidates {
        let size = elimination.size(r);
        if size <= tolerance * largest || size == 0.0 {
            left.push(r);
        } else {
            elimination.pick(r);
            taken.push(r);
        }
    }
    (taken, left)
}

/// The Euclidean norm of x; +0 for an empty x (a sum of no terms is −0, whose bits would sort
/// it above every size in `pivoted`'s queue).
pub fn norm(x: &Sparse) -> f64 {
    x.iter().fold(0.0, |sum, e| sum + e.1 * e.1).sqrt()
}

/// x · v for sparse x and v.
fn dot(x: &Sparse, v: &Sparse) -> f64 {
    let (mut i, mut j, mut sum) = (0, 0, 0.0);
    while i < x.len() && j < v.len() {
        match x[i].0.cmp(&v[j].0) {
            std::cmp::Ordering::Less => i += 1,
            std::cmp::Ordering::Greater => j += 1,
            std::cmp::Ordering::Equal => {
                sum += x[i].1 * v[j].1;
                i += 1;
                j += 1;
            }
        }
    }
    sum
}

/// x ← x + a v for sparse x and v; returns the columns x gained.
fn axpy(x: &mut Sparse, a: f64, v: &Sparse) -> Vec<usize> {
    let mut merged = Vec::with_capacity(x.len() + v.len());
    let mut added = Vec::new();
    let (mut i, mut j) = (0, 0);
    while i < x.len() || j < v.len() {
        if j == v.len() || (i < x.len() && x[i].0 < v[j].0) {
            merged.push(x[i]);
            i += 1;
        } else if i == x.len() || v[j].0 < x[i].0 {
            merged.push((v[j].0, a * v[j].1));
            added.push(v[j].0);
            j += 1;
        } else {
            merged.push((x[i].0, x[i].1 + a * v[j].1));
            i += 1;
            j += 1;
        }
    }
    *x = merged;
    added
}
