//! Small dense solves in storage kept between evaluations, so that they allocate nothing once
//! sized: a Cholesky factorisation (of a mass matrix, or of the allowed motions' small systems)
//! and Gaussian elimination (of the small, not always symmetric, systems of contact
//! multipliers).

use nalgebra::{DMatrix, DVector};

pub use crate::linalg::inverse_power_of_two;

/// The lower Cholesky factor of the leading r × r block of `a` in place (its lower triangle read
/// and written), without allocating: the smallest and the largest squared pivot, or None when
/// the block is not positive definite.
pub fn dense_cholesky(a: &mut DMatrix<f64>, r: usize) -> Option<(f64, f64)> {
    let (mut smallest, mut largest) = (f64::INFINITY, 0.0_f64);
    for j in 0..r {
        let mut diagonal = a[(j, j)];
        for k in 0..j {
            diagonal -= a[(j, k)] * a[(j, k)];
        }
        if !(diagonal > 0.0 && diagonal.is_finite()) {
            return None;
        }
        (smallest, largest) = (smallest.min(diagonal), largest.max(diagonal));
        let pivot = diagonal.sqrt();
        a[(j, j)] = pivot;
        for i in j + 1..r {
            let mut value = a[(i, j)];
            for k in 0..j {
                value -= a[(i, k)] * a[(j, k)];
            }
            a[(i, j)] = value / pivot;
        }
    }
    Some((smallest, largest))
}

/// The Cholesky factor of a symmetric positive definite matrix (a mass matrix), in storage
/// that the next factorisation of a matrix of the same size reuses.
#[derive(Clone, Debug)]
pub struct Factor {
    lower: DMatrix<f64>,
}

impl Factor {
    pub fn new(size: usize) -> Factor {
        Factor {
            lower: DMatrix::zeros(size, size),
        }
    }

    /// Factors `matrix` (square, of this factor's size): false when it is not positive
    /// definite, and the factor is then not usable.
    pub fn factor(&mut self, matrix: &DMatrix<f64>) -> bool {
        self.lower.copy_from(matrix);
        dense_cholesky(&mut self.lower, matrix.nrows()).is_some()
    }

    /// Solves A x = b for every column of `b` in place, A the last matrix factored.
    pub fn solve_mut(&self, b: &mut DMatrix<f64>) {
        // The triangular solves read the lower triangle only: the upper one holds the matrix.
        self.lower.solve_lower_triangular_mut(b);
        self.lower.tr_solve_lower_triangular_mut(b);
    }

    /// `solve_mut` for one right-hand side.
    pub fn solve_vector_mut(&self, b: &mut DVector<f64>) {
        self.lower.solve_lower_triangular_mut(b);
        self.lower.tr_solve_lower_triangular_mut(b);
    }
}

/// Solves `a x = b` in place (x into `b`, `a` overwritten) by Gaussian elimination with
/// partial pivoting (Golub and Van Loan, *Matrix Computations*, §3.4), for systems that are
/// not positive definite (the range-space method's saddle-point system is symmetric but
/// indefinite). The column whose pivot vanished (below 1e-14 of the largest
/// entry), if any: the rows are dependent there.
pub fn solve_in_place(a: &mut DMatrix<f64>, b: &mut [f64]) -> Result<(), usize> {
    let n = b.len();
    let largest = a.amax();
    for j in 0..n {
        let (offset, best) =
            (j..n)
                .map(|i| a[(i, j)].abs())
                .enumerate()
                .fold(
                    (0, -1.0),
                    |best, (i, x)| if x > best.1 { (i, x) } else { best },
                );
        if best <= 1e-14 * largest || !largest.is_finite() {
            return Err(j);
        }
        let p = j + offset;
        if p != j {
            a.swap_rows(p, j);
            b.swap(p, j);
        }
        let pivot = a[(j, j)];
        for i in j + 1..n {
            let factor = a[(i, j)] / pivot;
            if factor != 0.0 {
                for l in j + 1..n {
                    a[(i, l)] -= factor * a[(j, l)];
                }
                b[i] -= factor * b[j];
            }
        }
    }
    for j in (0..n).rev() {
        let dot: f64 = (j + 1..n).map(|l| a[(j, l)] * b[l]).sum();
        b[j] = (b[j] - dot) / a[(j, j)];
    }
    Ok(())
}

impl Factor {
    /// The size of the matrices this factor's storage holds.
    pub fn size(&self) -> usize {
        self.lower.nrows()
    }
}

/// A rank-revealing solve of A x = b in storage kept between solves: Gaussian elimination with
/// complete pivoting that stops where the largest entry left falls below `tolerance` times the
/// largest entry of A equilibrated. The unknowns of the rows left (dependent on the others, as
/// a follower's row held together with its leader's, or a velocity held twice) are set to zero:
/// where the system is consistent, x is one of its solutions, and X Hᵀ x (the change of the
/// motion) is the same for all of them.
///
/// A's rows and columns are first scaled by powers of two so that each one's largest entry is
/// in [1, 2) (exact, so a well-scaled system is solved as it was): the rows of one stack have
/// different units (a held angle's 1/I beside a contact's 1/m), and without it a row of small
/// entries, independent of the others, would fall under a cutoff relative to the largest.
#[derive(Clone, Debug, Default)]
pub struct Pivoted {
    columns: Vec<usize>,
    solution: Vec<f64>,
    column_scales: Vec<f64>,
}

impl Pivoted {
    /// Solves A x = b, overwriting A and leaving x in `b`; the rank found.
    pub fn solve(&mut self, a: &mut DMatrix<f64>, b: &mut DVector<f64>, tolerance: f64) -> usize {
        let n = a.nrows();
        self.columns.clear();
        self.columns.extend(0..n);
        self.equilibrate(a, b);
        let scale = a.amax();
        let mut rank = 0;
        while rank < n {
            let k = rank;
            let (mut row, mut column, mut largest) = (k, k, 0.0);
            for j in k..n {
                for i in k..n {
                    if a[(i, j)].abs() > largest {
                        (row, column, largest) = (i, j, a[(i, j)].abs());
                    }
                }
            }
            // A NaN entry (in the scale: the search skips it) ends the elimination too.
            if largest <= tolerance * scale || scale.is_nan() {
                break;
            }
            a.swap_rows(k, row);
            b.swap_rows(k, row);
            a.swap_columns(k, column);
            self.columns.swap(k, column);
            for i in k + 1..n {
                let factor = a[(i, k)] / a[(k, k)];
                for j in k..n {
                    a[(i, j)] -= factor * a[(k, j)];
                }
                b[i] -= factor * b[k];
            }
            rank += 1;
        }
        for k in (0..rank).rev() {
            let known: f64 = (k + 1..rank).map(|j| a[(k, j)] * b[j]).sum();
            b[k] = (b[k] - known) / a[(k, k)];
        }
        self.solution.clear();
        self.solution.resize(n, 0.0);
        for k in 0..rank {
            let column = self.columns[k];
            self.solution[column] = b[k] * self.column_scales[column];
        }
        b.as_mut_slice().copy_from_slice(&self.solution);
        rank
    }

    /// Scales A's rows (and b with them), then its columns (kept in `column_scales`, to scale
    /// the solution back), so that the largest entry of each is in [1, 2).
    fn equilibrate(&mut self, a: &mut DMatrix<f64>, b: &mut DVector<f64>) {
        for i in 0..a.nrows() {
            let scale = inverse_power_of_two(a.row(i).amax());
            a.row_mut(i).scale_mut(scale);
            b[i] *= scale;
        }
        self.column_scales.clear();
        for j in 0..a.ncols() {
            let scale = inverse_power_of_two(a.column(j).amax());
            a.column_mut(j).scale_mut(scale);
            self.column_scales.push(scale);
        }
    }
}
