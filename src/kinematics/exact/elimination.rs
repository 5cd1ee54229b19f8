//! Gauss–Jordan elimination over an exact field: the rank, the pivot columns, and a basis of
//! the kernel written in the free columns. Every zero test is exact, so the rank is the rank
//! (no threshold), and the cost, for the matrices of mechanisms (tens of rows and columns),
//! is that of the numbers' growth, small here.

use super::field::Number;

/// The reduced row echelon form of a matrix whose columns are taken in `order`.
pub struct Echelon {
    /// The reduced rows, over the columns in `order`'s order.
    pub rows: Vec<Vec<Number>>,
    /// Positions (in `order`) of the pivot columns, one per row of `rows`.
    pub pivots: Vec<usize>,
    /// The column order used.
    pub order: Vec<usize>,
}

impl Echelon {
    pub fn rank(&self) -> usize {
        self.pivots.len()
    }

    /// The original indices of the columns without pivot: the free ones.
    pub fn free_columns(&self) -> Vec<usize> {
        (0..self.order.len())
            .filter(|k| !self.pivots.contains(k))
            .map(|k| self.order[k])
            .collect()
    }

    /// A kernel basis, one vector per free column (in `free_columns` order), indexed by the
    /// original columns: the free column itself 1, the other free ones 0, each pivot column
    /// minus its row's entry in the free column.
    pub fn kernel(&self) -> Vec<Vec<Number>> {
        let n = self.order.len();
        let zero = |r: u64| Number::integer(0, r);
        let radicand = self
            .rows
            .iter()
            .flatten()
            .map(|x| x.radicand)
            .max()
            .unwrap_or(1);
        (0..n)
            .filter(|k| !self.pivots.contains(k))
            .map(|free| {
                let mut v = vec![zero(radicand); n];
                v[self.order[free]] = Number::integer(1, radicand);
                for (row, &pivot) in self.rows.iter().zip(&self.pivots) {
                    v[self.order[pivot]] = row[free].neg();
                }
                v
            })
            .collect()
    }
}

/// Reduces `matrix` (rows of equal length) taking its columns in `order`.
pub fn echelon(matrix: &[Vec<Number>], order: &[usize]) -> Echelon {
    let mut rows: Vec<Vec<Number>> = matrix
        .iter()
        .map(|row| order.iter().map(|&c| row[c].clone()).collect())
        .collect();
    let mut pivots = Vec::new();
    let mut next = 0;
    for column in 0..order.len() {
        let Some(found) = (next..rows.len()).find(|&r| !rows[r][column].is_zero()) else {
            continue;
        };
        rows.swap(next, found);
        let inverse = rows[next][column].inverse().expect("a non-zero pivot");
        rows[next] = rows[next].iter().map(|x| x.mul(&inverse)).collect();
        for r in 0..rows.len() {
            if r != next && !rows[r][column].is_zero() {
                let factor = rows[r][column].clone();
                let reduced: Vec<Number> = rows[r]
                    .iter()
                    .zip(&rows[next])
                    .map(|(x, p)| x.sub(&factor.mul(p)))
                    .collect();
                rows[r] = reduced;
            }
        }
        pivots.push(column);
        next += 1;
        if next == rows.len() {
            break;
        }
    }
    rows.truncate(next);
    Echelon {
        rows,
        pivots,
        order: order.to_vec(),
    }
}

/// The rank of `matrix`.
pub fn rank(matrix: &[Vec<Number>]) -> usize {
    let columns = matrix.first().map_or(0, |r| r.len());
    echelon(matrix, &(0..columns).collect::<Vec<_>>()).rank()
}
