//! The mass matrix factored along the tree, M = Lᵀ D L (Featherstone, "Rigid Body Dynamics
//! Algorithms", 2008, §6.5, Tables 6.3 and 6.4): L unit lower triangular with the mass matrix's
//! own sparsity, an entry L_ij only where velocity j is an ancestor of velocity i. Velocities
//! form a tree of their own (a joint's velocities a chain, its first one the child of its
//! parent joint's last), numbered parents first, so the factorisation fills nothing in: it costs
//! Σ dᵢ² and a solve 2 Σ dᵢ + n (dᵢ the depth of velocity i) where a dense Cholesky factor costs
//! n³/3 and its solve 2 n². The matrices the derivatives solve with (∂τ/∂q, ∂τ/∂v, the identity)
//! share M's pattern: column j vanishes outside j's ancestors and descendants, so its solve starts
//! at j's last descendant and ends with the tree below j's root (a fixed base's separate
//! branches, Talos's legs and upper body, never meet).

use nalgebra::DMatrix;

use crate::dynamics::model::Model;

/// The factor and the tree of velocities it follows; `new(&model)` once, `factor` per mass
/// matrix.
pub struct MassFactor {
    /// Per velocity i, `ancestors[start[i]..start[i + 1]]` its ancestors from its parent up, and
    /// `lower` at the same places L_ij along them.
    start: Vec<usize>,
    ancestors: Vec<usize>,
    lower: Vec<f64>,
    /// 1 / D_ii per velocity.
    inverse_diagonal: Vec<f64>,
    /// Per velocity, one past the last of its descendants, and its root (the first of the
    /// root's descendants, which are numbered after it).
    subtree_end: Vec<usize>,
    root: Vec<usize>,
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
        let mut start = vec![0];
        let mut ancestors = Vec::new();
        let mut root: Vec<usize> = (0..nv).collect();
        for (i, &above) in parent.iter().enumerate() {
            let mut next = above;
            while let Some(j) = next {
                debug_assert!(j < i, "velocities are numbered parents first");
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
        MassFactor {
            start,
            lower: vec![0.0; ancestors.len()],
            ancestors,
            inverse_diagonal: vec![0.0; nv],
            subtree_end,
            root,
        }
    }

    fn range(&self, i: usize) -> std::ops::Range<usize> {
        self.start[i]..self.start[i + 1]
    }

    /// Factors `mass` (read only between a velocity and its ancestors, as the composite rigid
    /// bodies write it); false if it is not positive definite.
    pub fn factor(&mut self, mass: &DMatrix<f64>) -> bool {
        let nv = self.inverse_diagonal.len();
        let mut diagonal = std::mem::take(&mut self.inverse_diagonal);
        for i in 0..nv {
            diagonal[i] = mass[(i, i)];
            for at in self.range(i) {
                self.lower[at] = mass[(i, self.ancestors[at])];
            }
        }
        // Table 6.3 from the leaves: row k's entries scaled by D_kk, its outer product taken
        // from the rows above. Velocity k's ancestors past i are i's ancestors, in order, so the
        // entries H_kj for j above i are the tail of k's row.
        for k in (0..nv).rev() {
            let row = self.range(k);
            for at in row.clone() {
                let i = self.ancestors[at];
                let ratio = self.lower[at] / diagonal[k];
                diagonal[i] -= self.lower[at] * ratio;
                let tail = at + 1..row.end;
                let above = self.range(i);
                for (target, source) in above.zip(tail) {
                    self.lower[target] -= self.lower[source] * ratio;
                }
                self.lower[at] = ratio;
            }
        }
        let mut positive = true;
        for d in diagonal.iter_mut() {
            positive &= *d > 0.0 && d.is_finite();
            *d = 1.0 / *d;
        }
        self.inverse_diagonal = diagonal;
        positive
    }

    /// x ← M⁻¹ x (Table 6.4): Lᵀ y = x from the leaves, D, then L x = y from the roots.
    pub fn solve(&self, x: &mut [f64]) {
        for i in (0..x.len()).rev() {
            self.carry_up(x, i);
        }
        self.finish_solve(x, 0..x.len());
    }

    /// x ← M⁻¹ x for x zero outside velocity j's ancestors and descendants.
    fn solve_column(&self, x: &mut [f64], j: usize) {
        let (root, end) = (self.root[j], self.subtree_end[self.root[j]]);
        for i in (root..self.subtree_end[j]).rev() {
            self.carry_up(x, i);
        }
        self.finish_solve(x, root..end);
    }

    /// Row i of Lᵀ y = x solved (its descendants' done): L_ij y_i taken from its ancestors'.
    #[inline]
    fn carry_up(&self, x: &mut [f64], i: usize) {
        let xi = x[i];
        for at in self.range(i) {
            x[self.ancestors[at]] -= self.lower[at] * xi;
        }
    }

    /// D⁻¹ and the solve from the root over `span`, after Lᵀ y = x, x zero outside `span`
    /// (whole trees below roots).
    fn finish_solve(&self, x: &mut [f64], span: std::ops::Range<usize>) {
        for i in span.clone() {
            x[i] *= self.inverse_diagonal[i];
        }
        for i in span {
            let range = self.range(i);
            let sum: f64 = (self.lower[range.clone()].iter())
                .zip(&self.ancestors[range])
                .map(|(l, &j)| l * x[j])
                .sum();
            x[i] -= sum;
        }
    }

    /// M⁻¹ into `inverse` (nv × nv): column c solves M x = e_c, whose first solve reaches only
    /// c and its ancestors.
    pub fn inverse_into(&self, inverse: &mut DMatrix<f64>) {
        let nv = self.inverse_diagonal.len();
        let columns = inverse.as_mut_slice().chunks_exact_mut(nv.max(1));
        for (c, x) in columns.enumerate() {
            x.fill(0.0);
            x[c] = 1.0;
            for i in std::iter::once(c).chain(self.ancestors[self.range(c)].iter().copied()) {
                self.carry_up(x, i);
            }
            self.finish_solve(x, self.root[c]..self.subtree_end[self.root[c]]);
        }
    }

    /// X ← −M⁻¹ X, column by column, for X of M's pattern (column j zero outside j's
    /// ancestors and descendants, as ∂τ/∂q and ∂τ/∂v are).
    pub fn solve_negated(&self, matrix: &mut DMatrix<f64>) {
        let nv = self.inverse_diagonal.len();
        for (j, x) in matrix.as_mut_slice().chunks_exact_mut(nv.max(1)).enumerate() {
            x.iter_mut().for_each(|e| *e = -*e);
            self.solve_column(x, j);
        }
    }
}
