//! The mass matrix factored along the tree, M = Lᵀ D L (Featherstone, "Rigid Body Dynamics
//! Algorithms", 2008, §6.5, Tables 6.3 and 6.4): L unit lower triangular with the mass matrix's
//! own sparsity, an entry L_ij only where velocity j is an ancestor of velocity i. Velocities
//! form a tree of their own (a joint's velocities a chain, its first one the child of its
//! parent joint's last), numbered parents first, so the factorisation fills nothing in: it costs
//! Σ dᵢ² and a solve 2 Σ dᵢ + n (dᵢ the depth of velocity i) where a dense Cholesky factor costs
//! n³/3 and its solve 2 n². The matrices the derivatives solve with (∂τ/∂q, ∂τ/∂v, the identity)
//! share M's pattern, zero between velocities of separate trees (a fixed base's branches, Talos's
//! legs and upper body, never meet): a row's operations run over its own tree's columns only.
//!
//! The factor numbers the velocities depth first (its *order*), whatever the model's numbering:
//! the bodies are numbered breadth first, which interleaves separate branches (Talos's legs and
//! upper body take turns), so that a subtree's or a tree's velocities would span almost all
//! columns. Depth first, each subtree and each tree is one contiguous span, and the solves by
//! rows run over it alone.

use nalgebra::DMatrix;
use wide::f64x2;

use crate::dynamics::model::Model;

/// The factor and the tree of velocities it follows; `new(&model)` once, `factor` per mass
/// matrix. Its fields are indexed by places in its depth-first order (the module's
/// documentation), not by velocities.
pub struct MassFactor {
    /// The velocity at each place, and each velocity's place; whether every velocity is at its
    /// own place (a chain, or a model numbered depth first), where the copies between the two
    /// orders are skipped.
    order: Vec<usize>,
    place: Vec<usize>,
    in_order: bool,
    /// Per place i, `ancestors[start[i]..start[i + 1]]` its ancestors' places from its parent
    /// up, and `lower` at the same places L_ij along them.
    start: Vec<usize>,
    ancestors: Vec<usize>,
    lower: Vec<f64>,
    /// 1 / D_ii per place.
    inverse_diagonal: Vec<f64>,
    /// Per place, one past the last of its descendants, and its root (the first place of its
    /// tree, whose others follow it).
    subtree_end: Vec<usize>,
    root: Vec<usize>,
    /// Per place i, `lineage[lineage_start[i]..lineage_start[i + 1]]` the places of its
    /// ancestors, itself and its descendants as contiguous runs in increasing order: where a
    /// row of the tree's pattern can be nonzero when the solve from the leaves carries it up.
    /// Between the runs lie earlier siblings' subtrees (Talos's left arm, for a row of its
    /// right arm), zero there.
    lineage_start: Vec<usize>,
    lineage: Vec<std::ops::Range<usize>>,
    /// A matrix by rows in the factor's order, for `solve_negated` and `inverse_into`, and a
    /// vector in that order, for `solve`.
    rows: Vec<f64>,
    vector: Vec<f64>,
}

impl MassFactor {
    pub fn new(model: &Model) -> MassFactor {
        let nv = model.nv;
        let mut parent = vec![None; nv];
        for &k in &model.dynamic_joints {
            let joint = &model.joints[k];
            let own = joint.v_offset..joint.v_offset + joint.nv();
            // The branch lists the joint's velocities, then its ancestors' (numbered before it):
            // the last velocity of the nearest ancestor with any is the largest of those.
            let above = (model.branch_velocities(k).iter())
                .filter(|row| !own.contains(row))
                .max()
                .copied();
            for index in own.clone() {
                parent[index] = if index == own.start {
                    above
                } else {
                    Some(index - 1)
                };
            }
        }
        let order = depth_first(&parent);
        let mut place = vec![0; nv];
        for (at, &velocity) in order.iter().enumerate() {
            place[velocity] = at;
        }
        let parent: Vec<Option<usize>> = (order.iter())
            .map(|&velocity| parent[velocity].map(|p| place[p]))
            .collect();
        let mut start = vec![0];
        let mut ancestors = Vec::new();
        let mut root: Vec<usize> = (0..nv).collect();
        for (i, &above) in parent.iter().enumerate() {
            let mut next = above;
            while let Some(j) = next {
                debug_assert!(j < i, "places are numbered parents first");
                ancestors.push(j);
                root[i] = j;
                next = parent[j];
            }
            start.push(ancestors.len());
        }
        let mut subtree_end: Vec<usize> = (1..=nv).collect();
        for i in (0..nv).rev() {
            if let Some(j) = parent[i] {
                subtree_end[j] = subtree_end[j].max(subtree_end[i]);
            }
        }
        let mut lineage_start = vec![0];
        let mut lineage: Vec<std::ops::Range<usize>> = Vec::new();
        for i in 0..nv {
            let first = lineage.len();
            let places = ancestors[start[i]..start[i + 1]].iter().rev();
            for &j in places.chain([&i]) {
                match lineage[first..].last_mut() {
                    Some(run) if run.end == j => run.end = j + 1,
                    _ => lineage.push(j..j + 1),
                }
            }
            lineage.last_mut().expect("i's own run").end = subtree_end[i];
            lineage_start.push(lineage.len());
        }
        let in_order = order
            .iter()
            .enumerate()
            .all(|(at, &velocity)| at == velocity);
        MassFactor {
            order,
            place,
            in_order,
            start,
            lower: vec![0.0; ancestors.len()],
            ancestors,
            inverse_diagonal: vec![0.0; nv],
            subtree_end,
            root,
            lineage_start,
            lineage,
            rows: vec![0.0; nv * nv],
            vector: vec![0.0; nv],
        }
    }

    /// Each velocity's place in the factor's order: row r of a matrix given to
    /// `solve_rows_negated_into` is at `place[r]` nv, its entry along velocity c at `place[c]`
    /// in that row.
    pub fn places(&self) -> &[usize] {
        &self.place
    }

    fn range(&self, i: usize) -> std::ops::Range<usize> {
        self.start[i]..self.start[i + 1]
    }

    /// Place i's ancestors' places with L_ij along them, from its parent up.
    #[inline]
    fn ancestry(
        &self,
        i: usize,
    ) -> std::iter::Zip<std::slice::Iter<'_, usize>, std::slice::Iter<'_, f64>> {
        let range = self.range(i);
        self.ancestors[range.clone()].iter().zip(&self.lower[range])
    }

    /// Factors `mass` (read only between a velocity and its ancestors, as the composite rigid
    /// bodies write it); false if it is not positive definite.
    pub fn factor(&mut self, mass: &DMatrix<f64>) -> bool {
        let mut diagonal = std::mem::take(&mut self.inverse_diagonal);
        for (i, (d, &velocity)) in diagonal.iter_mut().zip(&self.order).enumerate() {
            *d = mass[(velocity, velocity)];
            for at in self.range(i) {
                self.lower[at] = mass[(velocity, self.order[self.ancestors[at]])];
            }
        }
        // Table 6.3 from the leaves: row k's entries scaled by D_kk, its outer product taken
        // from the rows above. Velocity k's ancestors past i are i's ancestors, in order, so the
        // entries H_kj for j above i are the tail of k's row. Any order that takes a row after
        // its descendants will do: the model's breadth-first one (places of velocities from the
        // last) alternates between separate branches, whose rows do not wait on each other,
        // where depth first each row waits on the one before it (its child's update, then a
        // division), and the processor overlaps the branches' chains.
        let mut positive = true;
        for &k in self.place.iter().rev() {
            // D_kk is final once the rows below k are taken: its reciprocal scales the row by
            // products (one division per velocity instead of one per entry, whose latency the
            // row's updates waited on).
            let d = diagonal[k];
            positive &= d > 0.0 && d.is_finite();
            let reciprocal = 1.0 / d;
            diagonal[k] = reciprocal;
            let row = self.range(k);
            // Row k's entries lie after its ancestors' rows, which its updates write.
            let (above_rows, own) = self.lower.split_at_mut(row.start);
            let own = &mut own[..row.len()];
            for (offset, &i) in self.ancestors[row].iter().enumerate() {
                let ratio = own[offset] * reciprocal;
                diagonal[i] -= own[offset] * ratio;
                // `range(i)`, written out: a call would borrow all of `self`.
                let above = &mut above_rows[self.start[i]..self.start[i + 1]];
                for (target, source) in above.iter_mut().zip(&own[offset + 1..]) {
                    *target -= source * ratio;
                }
                own[offset] = ratio;
            }
        }
        self.inverse_diagonal = diagonal;
        positive
    }

    /// x ← M⁻¹ x (Table 6.4): Lᵀ y = x from the leaves, D, then L x = y from the roots, in the
    /// factor's order.
    pub fn solve(&mut self, x: &mut [f64]) {
        if self.in_order {
            self.solve_in_order(x);
            return;
        }
        let mut y = std::mem::take(&mut self.vector);
        for (y, &velocity) in y.iter_mut().zip(&self.order) {
            *y = x[velocity];
        }
        self.solve_in_order(&mut y);
        for (y, &velocity) in y.iter().zip(&self.order) {
            x[velocity] = *y;
        }
        self.vector = y;
    }

    /// `solve` of a vector given in the factor's order, its rows taken in the model's
    /// breadth-first order (`factor` says why).
    fn solve_in_order(&self, y: &mut [f64]) {
        for &i in self.place.iter().rev() {
            let yi = y[i];
            for at in self.range(i) {
                y[self.ancestors[at]] -= self.lower[at] * yi;
            }
        }
        for (yi, d) in y.iter_mut().zip(&self.inverse_diagonal) {
            *yi *= d;
        }
        for &i in &self.place {
            let range = self.range(i);
            let sum: f64 = (self.lower[range.clone()].iter())
                .zip(&self.ancestors[range])
                .map(|(l, &j)| l * y[j])
                .sum();
            y[i] -= sum;
        }
    }

    /// M⁻¹ into `inverse` (nv × nv): the solve of the identity. Its phase from the leaves
    /// leaves row i nonzero on i's descendants only (Lᵀ's inverse has the tree's pattern), a
    /// contiguous span; M⁻¹ is symmetric, so the phase from the roots forms each row from its
    /// diagonal on (row i's entries right of i need only its ancestors' entries right of
    /// themselves) and the rest is mirrored. Out of order, solved by rows in the factor's order,
    /// then copied into `inverse` over each tree's block.
    pub fn inverse_into(&mut self, inverse: &mut DMatrix<f64>) {
        let mut rows = std::mem::take(&mut self.rows);
        self.inverse_into_using(inverse, &mut rows);
        self.rows = rows;
    }

    /// `inverse_into` solving in `scratch` (nv × nv entries, whatever they hold): a matrix the
    /// caller is done with and has just touched (the mass matrix once factored), where the
    /// factor's own copy would be one more matrix in the cache.
    pub fn inverse_into_using(&self, inverse: &mut DMatrix<f64>, scratch: &mut [f64]) {
        let nv = self.inverse_diagonal.len();
        // In order, the rows are `inverse`'s own entries (M⁻¹ is symmetric).
        let entries = match self.in_order {
            true => inverse.as_mut_slice(),
            false => scratch,
        };
        match self.in_order {
            true => entries.fill(0.0),
            false => self.clear_subtrees(entries),
        }
        for c in 0..nv {
            entries[c + c * nv] = 1.0;
        }
        self.solve_rows(&mut [entries], Pattern::Identity);
        if self.in_order {
            // Row i of the solve by rows is column i of `inverse`: its upper part mirrored.
            for i in 0..nv {
                for c in i + 1..self.tree_end(i) {
                    inverse[(i, c)] = inverse[(c, i)];
                }
            }
            return;
        }
        // By `inverse`'s columns, whose entries lie together: entry (r, c) is the solve's row
        // min(place r, place c) at the other place.
        let entries = inverse.as_mut_slice();
        for (c, &k) in self.place.iter().enumerate() {
            let column = &mut entries[c * nv..(c + 1) * nv];
            let (above, below) = (self.root[k]..k + 1, k + 1..self.tree_end(k));
            for (&r, i) in self.order[above.clone()].iter().zip(above) {
                column[r] = scratch[i * nv + k];
            }
            let row = &scratch[k * nv..][below.clone()];
            for (&r, value) in self.order[below].iter().zip(row) {
                column[r] = *value;
            }
        }
    }

    /// `into` ← −M⁻¹ `from` (nv × nv each) for `from` of M's pattern (zero between velocities
    /// of separate trees, as ∂τ/∂q and ∂τ/∂v are), by rows in a copy in the factor's order.
    pub fn solve_negated(&mut self, from: &DMatrix<f64>, into: &mut DMatrix<f64>) {
        let nv = self.inverse_diagonal.len();
        let mut rows = std::mem::take(&mut self.rows);
        for (c, column) in from.as_slice().chunks_exact(nv.max(1)).enumerate() {
            for (r, value) in column.iter().enumerate() {
                rows[self.place[c] + self.place[r] * nv] = *value;
            }
        }
        self.solve_rows_negated_into([&mut rows[..]], [into]);
        self.rows = rows;
    }

    /// `into[m]` ← −M⁻¹ `rows[m]` for each of `M` matrices X (nv × nv) given by rows in the
    /// factor's order (`places`) with the tree's pattern (X_rc zero unless r and c are on one
    /// branch, as ∂τ/∂q and ∂τ/∂v are; only those entries are read, the others in each tree's
    /// block may hold anything), solved side by side in place in `rows`, then copied
    /// into `into`, in the model's order, column by column over its tree's rows (the entries
    /// outside stay as they are: zero).
    pub fn solve_rows_negated_into<const M: usize>(
        &self,
        mut rows: [&mut [f64]; M],
        into: [&mut DMatrix<f64>; M],
    ) {
        let nv = self.inverse_diagonal.len();
        self.solve_rows(&mut rows, Pattern::Branches);
        // All matrices at once: an entry's place in `into` is found once for all of them. By
        // `into`'s columns, whose entries lie together, where by the solve's rows each store
        // went to a line of its own (3 % of Talos's ∂ABA time).
        let mut out = into.map(|matrix| matrix.as_mut_slice());
        for (c, &k) in self.place.iter().enumerate() {
            let span = self.root[k]..self.tree_end(k);
            for (&r, i) in self.order[span.clone()].iter().zip(span) {
                let to = c * nv + r;
                for (out, rows) in out.iter_mut().zip(&rows) {
                    out[to] = -rows[i * nv + k];
                }
            }
        }
    }

    /// Zeroes each row of a matrix given by rows in the factor's order over its own subtree's
    /// places: the entries the identity's solve by rows reads before it writes them (its phase
    /// from the leaves carries a row into its ancestors' over its subtree, and writes the rest
    /// of the row up to its tree's end itself).
    fn clear_subtrees(&self, rows: &mut [f64]) {
        let nv = self.inverse_diagonal.len();
        for i in 0..nv {
            rows[i * nv..][i..self.subtree_end[i]].fill(0.0);
        }
    }

    /// One past the last place of i's tree.
    fn tree_end(&self, i: usize) -> usize {
        self.subtree_end[self.root[i]]
    }

    /// Row i's entries over `span` carried up into its ancestors' rows (Lᵀ's step of the
    /// solve from the leaves), in chunks of `WIDTH` held in registers, then one by one.
    #[inline(always)]
    fn carry_up_rows<const M: usize>(
        &self,
        x: &mut [&mut [f64]; M],
        i: usize,
        span: std::ops::Range<usize>,
    ) {
        let nv = self.inverse_diagonal.len();
        let ancestry = self.ancestry(i);
        let mut offset = span.start;
        while offset + WIDTH <= span.end {
            let mut chunks = [[f64x2::ZERO; 2]; M];
            for (chunk, matrix) in chunks.iter_mut().zip(x.iter()) {
                *chunk = load_chunk(&matrix[i * nv + offset..]);
            }
            for (&j, &l) in ancestry.clone() {
                let (at, l) = (j * nv + offset, f64x2::splat(l));
                for (matrix, chunk) in x.iter_mut().zip(&chunks) {
                    let row_j = &mut matrix[at..at + WIDTH];
                    let [low, high] = load_chunk(row_j);
                    store_chunk(row_j, [low - l * chunk[0], high - l * chunk[1]]);
                }
            }
            offset += WIDTH;
        }
        if offset + 2 <= span.end {
            let mut pairs = [f64x2::ZERO; M];
            for (pair, matrix) in pairs.iter_mut().zip(x.iter()) {
                *pair = load_pair(&matrix[i * nv + offset..]);
            }
            for (&j, &l) in ancestry.clone() {
                let (at, l) = (j * nv + offset, f64x2::splat(l));
                for (matrix, pair) in x.iter_mut().zip(&pairs) {
                    let row_j = &mut matrix[at..at + 2];
                    store_pair(row_j, load_pair(row_j) - l * *pair);
                }
            }
            offset += 2;
        }
        for c in offset..span.end {
            let xi: [f64; M] = std::array::from_fn(|m| x[m][i * nv + c]);
            for (&j, &l) in ancestry.clone() {
                for (matrix, xi) in x.iter_mut().zip(xi) {
                    matrix[j * nv + c] -= l * xi;
                }
            }
        }
    }

    /// X ← M⁻¹ X for each of `M` matrices X (nv × nv) given by rows in the factor's order (the
    /// row at place i at i nv, its entries by places), zero outside the blocks of the separate
    /// trees (a tree's velocities by the same tree's), read only where X's pattern can be
    /// nonzero (the tree's pattern, or the identity's diagonal) and written over each tree's
    /// block: each step of Table 6.4 done on whole rows, over the columns where the row can be
    /// nonzero, in contiguous runs. The columns are independent, so the processor overlaps
    /// them, where a column's own solve is one chain of dependent products. In the phase from
    /// the leaves row i, when it is carried up, is nonzero only on i's ancestors and
    /// descendants (by induction: so is X's row, and its descendants' rows add their own
    /// ancestors' and descendants'), its `lineage`; for the identity, on its descendants only.
    /// Row i is final once carried up (only its descendants change it); D⁻¹ scales it as the
    /// phase from the roots loads it. The matrices share the pattern, so they are solved side
    /// by side: each ancestor's entry of L, loaded once, serves the same chunk of all.
    fn solve_rows<const M: usize>(&self, x: &mut [&mut [f64]; M], pattern: Pattern) {
        let nv = self.inverse_diagonal.len();
        let formed = |i: usize| match pattern {
            Pattern::Identity => i..self.tree_end(i),
            Pattern::Branches => self.root[i]..self.tree_end(i),
        };
        // Row i by chunks of `WIDTH` columns against all its ancestors' rows at once (the
        // ancestors' rows all lie before row i): a chunk of row i stays in registers while its
        // ancestors' are updated (from the leaves) or read (from the roots), where an update of
        // a whole row per ancestor would store row i's or reload it each time. The order of the
        // operations on every entry is Table 6.4's.
        for i in (0..nv).rev() {
            let descendants = i..self.subtree_end[i];
            let carried = match pattern {
                Pattern::Identity => std::slice::from_ref(&descendants),
                Pattern::Branches => {
                    &self.lineage[self.lineage_start[i]..self.lineage_start[i + 1]]
                }
            };
            for span in carried {
                self.carry_up_rows(x, i, span.clone());
            }
            // Row i is final here: the gaps between its runs that the phase from the roots
            // reads (up to its tree's end) are zeroed, whatever they held.
            let read = formed(i);
            for matrix in x.iter_mut() {
                let row = &mut matrix[i * nv..(i + 1) * nv];
                let mut gap_start = read.start;
                for span in carried {
                    row[gap_start..span.start].fill(0.0);
                    gap_start = span.end;
                }
                row[gap_start..read.end].fill(0.0);
            }
        }
        // D⁻¹ scales each row as the phase from the roots loads it.
        for i in 0..nv {
            let (span, ancestry) = (formed(i), self.ancestry(i));
            let d = self.inverse_diagonal[i];
            let d2 = f64x2::splat(d);
            let mut offset = span.start;
            while offset + WIDTH <= span.end {
                let mut sums = [[f64x2::ZERO; 2]; M];
                for (sum, matrix) in sums.iter_mut().zip(x.iter()) {
                    let [low, high] = load_chunk(&matrix[i * nv + offset..]);
                    *sum = [low * d2, high * d2];
                }
                for (&j, &l) in ancestry.clone() {
                    let (at, l) = (j * nv + offset, f64x2::splat(l));
                    for (matrix, sum) in x.iter().zip(sums.iter_mut()) {
                        let [low, high] = load_chunk(&matrix[at..at + WIDTH]);
                        *sum = [sum[0] - l * low, sum[1] - l * high];
                    }
                }
                for (matrix, sum) in x.iter_mut().zip(&sums) {
                    store_chunk(&mut matrix[i * nv + offset..], *sum);
                }
                offset += WIDTH;
            }
            if offset + 2 <= span.end {
                let mut sums = [f64x2::ZERO; M];
                for (sum, matrix) in sums.iter_mut().zip(x.iter()) {
                    *sum = load_pair(&matrix[i * nv + offset..]) * d2;
                }
                for (&j, &l) in ancestry.clone() {
                    let (at, l) = (j * nv + offset, f64x2::splat(l));
                    for (matrix, sum) in x.iter().zip(sums.iter_mut()) {
                        *sum -= l * load_pair(&matrix[at..at + 2]);
                    }
                }
                for (matrix, sum) in x.iter_mut().zip(&sums) {
                    store_pair(&mut matrix[i * nv + offset..], *sum);
                }
                offset += 2;
            }
            for c in offset..span.end {
                let mut sums: [f64; M] = std::array::from_fn(|m| x[m][i * nv + c] * d);
                for (&j, &l) in ancestry.clone() {
                    for (matrix, sum) in x.iter().zip(sums.iter_mut()) {
                        *sum -= l * matrix[j * nv + c];
                    }
                }
                for (matrix, sum) in x.iter_mut().zip(sums) {
                    matrix[i * nv + c] = sum;
                }
            }
        }
    }
}

/// The columns `solve_rows` takes together: two of the portable x86-64 build's 2-wide vectors.
const WIDTH: usize = 4;

/// The `WIDTH` entries a row's chunk starts with, as two pairs, loaded as pairs: built as
/// arrays (`array::from_fn` over `try_into`), the chunks were copied about on the stack (a
/// tenth of the solves' time on Talos). Each pair's products and sums are the scalar ones: the
/// same operations in the same order on every entry.
#[inline(always)]
fn load_chunk(row: &[f64]) -> [f64x2; 2] {
    let chunk = &row[..WIDTH];
    [
        f64x2::new([chunk[0], chunk[1]]),
        f64x2::new([chunk[2], chunk[3]]),
    ]
}

/// Two entries a row's remainder starts with, as a pair (the same operations as the scalar
/// ones on each), and written back.
#[inline(always)]
fn load_pair(row: &[f64]) -> f64x2 {
    f64x2::new([row[0], row[1]])
}

#[inline(always)]
fn store_pair(row: &mut [f64], pair: f64x2) {
    row[..2].copy_from_slice(&pair.to_array());
}

/// `load_chunk`'s pairs written back.
#[inline(always)]
fn store_chunk(row: &mut [f64], [low, high]: [f64x2; 2]) {
    let chunk = &mut row[..WIDTH];
    chunk[..2].copy_from_slice(&low.to_array());
    chunk[2..].copy_from_slice(&high.to_array());
}

/// What a matrix solved by rows holds: the identity, or a matrix of the tree's pattern.
#[derive(Clone, Copy)]
enum Pattern {
    Identity,
    Branches,
}

/// The velocities depth first: each root (a velocity without parent) in increasing order, then
/// its children's subtrees, each in increasing order of the child. Parents come before their
/// children, and a subtree's velocities follow one another.
fn depth_first(parent: &[Option<usize>]) -> Vec<usize> {
    let mut children = vec![Vec::new(); parent.len()];
    let mut stack = Vec::new();
    for (velocity, above) in parent.iter().enumerate().rev() {
        match above {
            Some(p) => children[*p].push(velocity),
            None => stack.push(velocity),
        }
    }
    // Pushed in decreasing order, so that the smallest is taken first.
    let mut order = Vec::with_capacity(parent.len());
    while let Some(velocity) = stack.pop() {
        order.push(velocity);
        stack.extend(children[velocity].iter().copied());
    }
    order
}
