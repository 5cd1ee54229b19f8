//! Small dense solves in storage kept between evaluations, so that they allocate nothing once
//! sized: a Cholesky factorisation (of a mass matrix, or of the allowed motions' small systems)
//! and Gaussian elimination (of the small, not always symmetric, systems of contact
//! multipliers).

use nalgebra::{DMatrix, DVector};

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

/// Solves A x = b by Gaussian elimination with partial pivoting, overwriting A and leaving x in
/// `b`; Err(k) when the k-th unknown is not determined (an exactly zero pivot, as where rows
/// are dependent), with A and b then spoilt.
pub fn solve_in_place(a: &mut DMatrix<f64>, b: &mut DVector<f64>) -> Result<(), usize> {
    let n = a.nrows();
    for k in 0..n {
        let pivot = (k..n)
            .max_by(|&i, &j| a[(i, k)].abs().total_cmp(&a[(j, k)].abs()))
            .unwrap_or(k);
        if a[(pivot, k)] == 0.0 || !a[(pivot, k)].is_finite() {
            return Err(k);
        }
        a.swap_rows(k, pivot);
        b.swap_rows(k, pivot);
        for i in k + 1..n {
            let factor = a[(i, k)] / a[(k, k)];
            for j in k..n {
                a[(i, j)] -= factor * a[(k, j)];
            }
            b[i] -= factor * b[k];
        }
    }
    for k in (0..n).rev() {
        let known: f64 = (k + 1..n).map(|j| a[(k, j)] * b[j]).sum();
        b[k] = (b[k] - known) / a[(k, k)];
    }
    Ok(())
}
