//! Which side of a singular configuration of its loops a state lies on, seen from a reference
//! state: per loop, the determinant of G(q) G(q₀)ᵀ over its kept firm rows (made
//! dimensionless), relative to its value at the reference, where it is det(G(q₀) G(q₀)ᵀ) > 0.
//! Where the loop's rows lose their independence the determinant vanishes, and a motion that
//! passes the singular configuration (a parallelogram through its flat configurations) changes
//! its sign: the smallest singular value of the rows, continued smoothly along the motion,
//! changes sign there while the rows' other directions hardly move (Bunse-Gerstner, Byers,
//! Mehrmann and Nichols, "Numerical computation of an analytic singular value decomposition of
//! a matrix valued function", Numer. Math. 60, 1991). The conditioning of the rows
//! (`Factored::conditioning`) is never negative: two states on either side of the singular
//! configuration may both be well conditioned, and a step between them jumps across it unseen.
//! Near the passage the measure is close to σ(q)/σ(q₀), linear in the distance to it, so that
//! where it changes sign over a step the fraction of the step where it vanished follows from
//! its value at the step's end (`simulate::constraints::LoopMonitor::crossing`).

use nalgebra::Matrix6;

use super::factored::RowChoice;
use super::jacobian::ConstraintJacobian;

/// A loop's determinant at the reference below this, relative to the product of its rows'
/// squared lengths, says that its own rows are dependent there (they are independent only
/// with other loops' rows, or the reference is singular): its sign says nothing, the loop is
/// left out.
const DEPENDENT: f64 = 1e-24;

/// The kept firm rows of one loop at the reference state.
#[derive(Clone, Debug, Default)]
struct LoopReference {
    block: usize,
    /// The rows (0 to 5 in the loop's block) and their scales.
    rows: Vec<(usize, f64)>,
    /// Row-major: the rows' values over the block's columns, scaled.
    values: Vec<f64>,
    /// det(G₀G₀ᵀ) over these rows.
    determinant: f64,
}

/// The loops' kept rows at a reference state, to tell on which side of a singular configuration
/// other states lie (see the module's documentation). Its storage is kept from one reference to
/// the next: a run sets one at every step it keeps, and a step allocates nothing.
#[derive(Clone, Debug, Default)]
pub struct Orientation {
    /// The first `count` hold the reference; the others keep their storage for the next one.
    loops: Vec<LoopReference>,
    count: usize,
    /// One loop's rows at the state `relative` is asked about.
    row: Vec<f64>,
    /// The firm rows and their scales, by loop (`set`).
    firm: Vec<(usize, f64)>,
}

impl Orientation {
    /// Takes the rows of `choice` (the firm ones) of `jacobian` as the reference.
    pub fn set(&mut self, jacobian: &ConstraintJacobian, choice: &RowChoice) {
        self.count = 0;
        let firm = &choice.rows[..choice.rows.len() - choice.weak];
        // The firm rows grouped by loop, each loop's in their order in `choice`, in one pass
        // over them rather than one per loop (quadratic in the loops: a ladder of 1,000 loops
        // spent half its projections' time here). The sort is stable, and the rows are sorted
        // already (`RowChoice::new`).
        self.firm.clear();
        self.firm
            .extend(firm.iter().copied().zip(choice.scales.iter().copied()));
        self.firm.sort_by_key(|&(row, _)| row / 6);
        let mut next = 0;
        for (block_index, block) in jacobian.blocks.iter().enumerate() {
            if self.loops.len() == self.count {
                self.loops.push(LoopReference::default());
            }
            let reference = &mut self.loops[self.count];
            reference.block = block_index;
            reference.rows.clear();
            let start = next;
            while next < self.firm.len() && self.firm[next].0 / 6 == block_index {
                next += 1;
            }
            reference
                .rows
                .extend((self.firm[start..next].iter()).map(|&(row, scale)| (row % 6, scale)));
            if reference.rows.is_empty() {
                continue;
            }
            let columns = block.columns.len();
            reference.values.clear();
            for &(row, scale) in &reference.rows {
                (reference.values).extend((0..columns).map(|c| block.values[(row, c)] * scale));
            }
            let determinant = reference.product_determinant(&reference.values);
            let lengths: f64 = (reference.values.chunks(columns))
                .map(|row| row.iter().map(|x| x * x).sum::<f64>())
                .product();
            if determinant > DEPENDENT * lengths {
                reference.determinant = determinant;
                self.count += 1;
            }
        }
    }

    /// Forgets the reference (`crossing` then sees nothing).
    pub fn clear(&mut self) {
        self.count = 0;
    }

    /// The smallest, over the loops, of det(G G₀ᵀ) / det(G₀ G₀ᵀ) at the rows of `jacobian`
    /// (1 at the reference, negative past a singular configuration), and that loop; None
    /// without a reference.
    pub fn relative(&mut self, jacobian: &ConstraintJacobian) -> Option<(f64, usize)> {
        let Orientation {
            loops, count, row, ..
        } = self;
        loops[..*count]
            .iter()
            .map(|reference| {
                let block = &jacobian.blocks[reference.block];
                row.clear();
                for &(r, scale) in &reference.rows {
                    row.extend((0..block.columns.len()).map(|c| block.values[(r, c)] * scale));
                }
                let ratio = reference.product_determinant(row) / reference.determinant;
                (ratio, reference.block)
            })
            .min_by(|a, b| a.0.total_cmp(&b.0))
    }
}

impl LoopReference {
    /// det(R R₀ᵀ) for the rows R (row-major, as `values`) against the reference rows R₀.
    fn product_determinant(&self, rows: &[f64]) -> f64 {
        let count = self.rows.len();
        let columns = self.values.len() / count;
        // Padded with the identity past the loop's rows, which leaves the determinant alone.
        let mut product = Matrix6::<f64>::identity();
        for i in 0..count {
            for j in 0..count {
                let here = &rows[i * columns..(i + 1) * columns];
                let there = &self.values[j * columns..(j + 1) * columns];
                product[(i, j)] = here.iter().zip(there).map(|(a, b)| a * b).sum();
            }
        }
        product.determinant()
    }
}
