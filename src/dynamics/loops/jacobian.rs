//! The constraint Jacobian G, stored by loop: a loop's six rows move only the coordinates on the
//! paths from its two bodies to the root and its own complementary coordinates, so each loop
//! keeps a 6 × k block over those k columns. A row of N four-bars has 4 columns per loop out of
//! 3N + 1; storing G densely would cost more than the dynamics of the tree beside it.

use nalgebra::{DMatrix, DVector, Dyn, OMatrix, U6};

use crate::spatial::Real;

/// The rows of one loop over the columns it touches, in the scalar `T` (`f64`, or dual
/// numbers: `DynamicsScalar`).
#[derive(Clone, Debug)]
pub struct LoopBlock<T: Real = f64> {
    /// The state velocities the loop's rows depend on, in increasing order.
    pub columns: Vec<usize>,
    /// 6 × `columns.len()`.
    pub values: OMatrix<T, U6, Dyn>,
}

impl<T: Real> LoopBlock<T> {
    /// A block of zeros over these columns (sorted, without repeats).
    pub fn zeros(columns: Vec<usize>) -> LoopBlock<T> {
        let values = OMatrix::<T, U6, Dyn>::zeros(columns.len());
        LoopBlock { columns, values }
    }

    /// The local index of a state velocity among the block's columns.
    pub fn local(&self, column: usize) -> usize {
        self.columns
            .binary_search(&column)
            .expect("a loop's rows are written only on its own columns")
    }
}

/// G: 6 rows per loop, one column per state velocity.
#[derive(Clone, Debug)]
pub struct ConstraintJacobian<T: Real = f64> {
    pub columns: usize,
    pub blocks: Vec<LoopBlock<T>>,
    /// Per loop, the loops (itself included) whose columns meet its own, each with the pairs of
    /// local columns they share (this loop's, the other's), in increasing column order: where
    /// the entries of GGᵀ between their rows come from.
    pub neighbours: Vec<Vec<Neighbour>>,
}

/// A loop (or the loop itself) and the local columns it shares with a loop.
#[derive(Clone, Debug)]
pub struct Neighbour {
    pub other: usize,
    pub shared: Vec<(usize, usize)>,
}

impl<T: Real> ConstraintJacobian<T> {
    /// G over these loop blocks.
    pub fn new(columns: usize, blocks: Vec<LoopBlock<T>>) -> ConstraintJacobian<T> {
        // The loops over each column, so that a loop's neighbours are searched among the loops
        // meeting its own columns, not among all of them (a ladder of N loops: N² pairs).
        let mut by_column = vec![Vec::new(); columns];
        for (j, block) in blocks.iter().enumerate() {
            for &c in &block.columns {
                by_column[c].push(j);
            }
        }
        let neighbours = (0..blocks.len())
            .map(|i| {
                let mut meeting: Vec<usize> = (blocks[i].columns.iter())
                    .flat_map(|&c| by_column[c].iter().copied())
                    .collect();
                meeting.sort_unstable();
                meeting.dedup();
                meeting
                    .into_iter()
                    .filter_map(|j| {
                        let shared = shared_columns(&blocks[i].columns, &blocks[j].columns);
                        (!shared.is_empty()).then_some(Neighbour { other: j, shared })
                    })
                    .collect()
            })
            .collect();
        ConstraintJacobian {
            columns,
            blocks,
            neighbours,
        }
    }

    pub fn nrows(&self) -> usize {
        6 * self.blocks.len()
    }

    pub fn ncols(&self) -> usize {
        self.columns
    }

    /// Row `row` (among the 6 per loop) as (column, value) pairs.
    pub fn row(&self, row: usize) -> impl Iterator<Item = (usize, T)> + '_ {
        let block = &self.blocks[row / 6];
        let r = row % 6;
        block
            .columns
            .iter()
            .enumerate()
            .map(move |(local, &column)| (column, block.values[(r, local)]))
    }

    /// G v into `out` (of G's rows).
    pub fn mul_into(&self, v: &[T], out: &mut DVector<T>) {
        out.fill(T::zero());
        for (k, block) in self.blocks.iter().enumerate() {
            let mut rows = out.fixed_rows_mut::<6>(6 * k);
            for (local, &column) in block.columns.iter().enumerate() {
                rows += block.values.column(local) * v[column];
            }
        }
    }

    /// G as a dense matrix, for the decisions taken once (the rows kept, the rank, the nearby
    /// configurations), never inside an evaluation.
    pub fn dense(&self) -> DMatrix<T> {
        let mut dense = DMatrix::zeros(self.nrows(), self.columns);
        for (k, block) in self.blocks.iter().enumerate() {
            for (local, &column) in block.columns.iter().enumerate() {
                dense
                    .view_mut((6 * k, column), (6, 1))
                    .copy_from(&block.values.column(local));
            }
        }
        dense
    }
}

/// The positions of the columns two sorted column lists share, in increasing column order.
fn shared_columns(first: &[usize], second: &[usize]) -> Vec<(usize, usize)> {
    first
        .iter()
        .enumerate()
        .filter_map(|(i, column)| second.binary_search(column).ok().map(|j| (i, j)))
        .collect()
}
