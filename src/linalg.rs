//! Decompositions that end on any matrix. nalgebra's SVD iterates until it converges, which a
//! matrix with a NaN or an infinite entry never does (a degenerate joint or an overflowing
//! configuration can produce one): here such a matrix has no decomposition, and the caller says
//! why it cannot go on. Beside them, the exact power-of-two scaling that brings rows of different
//! units to one size before a decomposition, and the QR decomposition with column pivoting that
//! tells which columns of a matrix are independent.

use nalgebra::{DMatrix, DVector, Dyn, SymmetricEigen, SVD};

/// Iterations of the SVD per row and column before it gives up: far more than a finite matrix
/// needs, so that only a pathological one is refused.
const ITERATIONS_PER_DIMENSION: usize = 1000;

/// The singular value decomposition, singular values largest first; `None` when an entry is not
/// finite or the iteration does not converge.
///
/// nalgebra's bidiagonal iteration is fast but, on some matrices (rank-deficient ones among
/// them, and matrices of ones), returns wrong singular values and vectors without saying so
/// (nalgebra issue #1172: an 8 × 11 matrix of rank 6 gave a pseudo-inverse off by 3e-2). So
/// its result is checked, by the identity Σσ² = ‖m‖²_F and, with the vectors, by the
/// reconstruction U Σ Vᵀ = m, and where it fails the decomposition is taken again by one-sided
/// Jacobi rotations ([`jacobi_svd`]), slower but accurate on any matrix.
pub fn svd(m: DMatrix<f64>, compute_u: bool, compute_v: bool) -> Option<SVD<f64, Dyn, Dyn>> {
    if !m.iter().all(|x| x.is_finite()) {
        return None;
    }
    let limit = ITERATIONS_PER_DIMENSION * (m.nrows() + m.ncols()).max(1);
    let original = m.clone();
    let vectors = compute_u && compute_v;
    // The vectors are computed for the check, and dropped after it if not asked for.
    let decomposition = SVD::try_new(m, true, true, f64::EPSILON * 5.0, limit);
    let mut checked = match decomposition {
        Some(found) if decomposition_holds(&original, &found) => found,
        _ => jacobi_svd(&original),
    };
    if !vectors {
        if !compute_u {
            checked.u = None;
        }
        if !compute_v {
            checked.v_t = None;
        }
    }
    Some(checked)
}

/// A decomposition's error, relative to ‖m‖_F, above which it is taken as wrong: a correct one is
/// at a few units of ε times the dimensions; the wrong ones seen are at 1e-2 and above.
const DECOMPOSITION_ERROR: f64 = 1e-11;

/// Whether `found` is a singular value decomposition of `m`: Σσ² = ‖m‖²_F, and U Σ Vᵀ = m.
fn decomposition_holds(m: &DMatrix<f64>, found: &SVD<f64, Dyn, Dyn>) -> bool {
    let scale = m.norm();
    if scale == 0.0 {
        return found.singular_values.iter().all(|&s| s == 0.0);
    }
    let squares = found.singular_values.norm_squared();
    if (squares - scale * scale).abs() > DECOMPOSITION_ERROR * scale * scale {
        return false;
    }
    let (Some(u), Some(v_t)) = (&found.u, &found.v_t) else {
        return false;
    };
    let mut scaled = u.clone();
    for (k, &s) in found.singular_values.iter().enumerate() {
        scaled.column_mut(k).scale_mut(s);
    }
    (scaled * v_t - m).norm() <= DECOMPOSITION_ERROR * scale
}

/// The singular value decomposition by one-sided Jacobi rotations (Hestenes, "Inversion of
/// matrices by biorthogonalization", J. SIAM 6, 1958; Demmel and Veselić, "Jacobi's method is
/// more accurate than QR", SIAM J. Matrix Anal. Appl. 13, 1992): the columns of the tall
/// orientation B of `m` are rotated in pairs until they are orthogonal, B V = U Σ. Singular
/// values largest first, U's columns for zero singular values completed to an orthonormal set.
pub fn jacobi_svd(m: &DMatrix<f64>) -> SVD<f64, Dyn, Dyn> {
    let wide = m.nrows() < m.ncols();
    let mut b = if wide { m.transpose() } else { m.clone() };
    let n = b.ncols();
    let mut v = DMatrix::<f64>::identity(n, n);
    for _ in 0..JACOBI_SWEEPS {
        let mut rotated = false;
        for p in 0..n {
            for q in p + 1..n {
                let alpha = b.column(p).norm_squared();
                let beta = b.column(q).norm_squared();
                let gamma = b.column(p).dot(&b.column(q));
                if gamma == 0.0 || gamma.abs() <= f64::EPSILON * (alpha * beta).sqrt() {
                    continue;
                }
                rotated = true;
                // The rotation that makes columns p and q orthogonal (the smaller angle).
                let zeta = (beta - alpha) / (2.0 * gamma);
                let t = zeta.signum() / (zeta.abs() + (1.0 + zeta * zeta).sqrt());
                let c = 1.0 / (1.0 + t * t).sqrt();
                let s = c * t;
                for matrix in [&mut b, &mut v] {
                    for i in 0..matrix.nrows() {
                        let (x, y) = (matrix[(i, p)], matrix[(i, q)]);
                        matrix[(i, p)] = c * x - s * y;
                        matrix[(i, q)] = s * x + c * y;
                    }
                }
            }
        }
        if !rotated {
            break;
        }
    }
    let mut order: Vec<usize> = (0..n).collect();
    let norms: Vec<f64> = (0..n).map(|j| b.column(j).norm()).collect();
    order.sort_by(|&i, &j| norms[j].total_cmp(&norms[i]));
    let rows = b.nrows();
    let mut u = DMatrix::zeros(rows, n);
    let mut values = DVector::zeros(n);
    let mut v_sorted = DMatrix::zeros(n, n);
    let largest = norms.iter().fold(0.0f64, |a, &b| a.max(b));
    let mut filled = Vec::new();
    for (k, &j) in order.iter().enumerate() {
        values[k] = norms[j];
        v_sorted.set_column(k, &v.column(j));
        if norms[j] > f64::EPSILON * largest && norms[j] > 0.0 {
            u.set_column(k, &(b.column(j) / norms[j]));
            filled.push(k);
        }
    }
    complete_orthonormal(&mut u, &filled);
    let (u, v_t) = match wide {
        false => (u, v_sorted.transpose()),
        true => (v_sorted, u.transpose()),
    };
    SVD {
        u: Some(u),
        v_t: Some(v_t),
        singular_values: values,
    }
}

/// Sweeps of the Jacobi rotations before they stop: they converge quadratically, in well under
/// 20 on any matrix met here (about 6 to 10 usually).
const JACOBI_SWEEPS: usize = 60;

/// Fills the columns of `u` not in `filled` with unit vectors orthogonal to every other column
/// (Gram–Schmidt, twice, on the coordinate vectors).
fn complete_orthonormal(u: &mut DMatrix<f64>, filled: &[usize]) {
    let mut basis: Vec<usize> = filled.to_vec();
    let mut candidate = 0;
    for k in 0..u.ncols() {
        if filled.contains(&k) {
            continue;
        }
        while candidate < u.nrows() {
            let mut x = DVector::zeros(u.nrows());
            x[candidate] = 1.0;
            candidate += 1;
            for _ in 0..2 {
                for &j in &basis {
                    let projection = u.column(j).dot(&x);
                    x.axpy(-projection, &u.column(j), 1.0);
                }
            }
            let norm = x.norm();
            if norm > 0.5 {
                u.set_column(k, &(x / norm));
                basis.push(k);
                break;
            }
        }
    }
}

/// The pseudo-inverse, singular values up to `floor` taken as zero; `None` as for [`svd`].
pub fn pseudo_inverse(m: DMatrix<f64>, floor: f64) -> Option<DMatrix<f64>> {
    svd(m, true, true)?.pseudo_inverse(floor).ok()
}

/// The smallest eigenvalue of the symmetric matrix `m` (its lower triangle is read) and a unit
/// eigenvector for it; `None` for an empty matrix, one with an entry that is not finite, or an
/// iteration that does not converge.
pub fn smallest_eigenpair(m: &DMatrix<f64>) -> Option<(f64, DVector<f64>)> {
    if m.is_empty() || !m.iter().all(|x| x.is_finite()) {
        return None;
    }
    let limit = ITERATIONS_PER_DIMENSION * 2 * m.nrows();
    let eigen = SymmetricEigen::try_new(m.clone(), f64::EPSILON * 5.0, limit)?;
    let smallest = eigen.eigenvalues.imin();
    Some((
        eigen.eigenvalues[smallest],
        eigen.eigenvectors.column(smallest).into_owned(),
    ))
}

/// The power of two 2⁻ᵉ for `largest` in [2ᵉ, 2ᵉ⁺¹), read from its exponent's bits (no
/// logarithm: it runs for every row of every solve); 1 where `largest` is zero or not finite.
pub fn inverse_power_of_two(largest: f64) -> f64 {
    if !(largest > 0.0 && largest.is_finite()) {
        return 1.0;
    }
    let exponent = ((largest.to_bits() >> 52) & 0x7ff) as i64 - 1023;
    // Bounded to the normal numbers' exponents: a subnormal `largest` (its field reads
    // −1023) is scaled by 2¹⁰²², the largest power of two, and the largest numbers by 2⁻¹⁰²².
    let inverse = (-exponent).clamp(-1022, 1022);
    f64::from_bits(((inverse + 1023) as u64) << 52)
}

/// The R factor of m P = Q R and the column order P (`order[k]` is the column of m that came
/// k-th), by Householder reflections with column pivoting: at each step the remaining column
/// of largest norm comes next (Businger & Golub, "Linear least squares solutions by Householder
/// transformations", Numer. Math. 7, 1965; Golub & Van Loan, Matrix Computations, §5.4.1). The
/// magnitudes of R's diagonal then decrease, and the first r columns of the order whose
/// diagonal stands above a tolerance are independent, the others combinations of them:
/// R₁⁻¹ R₂ gives the combinations. Norms are recomputed at each step rather than downdated, so
/// that no cancellation hides a small column.
pub fn pivoted_qr(m: &DMatrix<f64>) -> (DMatrix<f64>, Vec<usize>) {
    let (rows, columns) = m.shape();
    let mut a = m.clone();
    let mut order: Vec<usize> = (0..columns).collect();
    for k in 0..rows.min(columns) {
        let norm_below = |a: &DMatrix<f64>, j: usize| a.view((k, j), (rows - k, 1)).norm();
        let pivot = (k..columns)
            .max_by(|&i, &j| norm_below(&a, i).total_cmp(&norm_below(&a, j)))
            .unwrap_or(k);
        a.swap_columns(k, pivot);
        order.swap(k, pivot);
        let norm = norm_below(&a, k);
        if norm == 0.0 {
            break;
        }
        // The reflection I − 2 w wᵀ/(wᵀw) that maps the column below k onto ∓norm e_k, its
        // sign chosen against cancellation.
        let alpha = if a[(k, k)] > 0.0 { -norm } else { norm };
        let mut w = a.view((k, k), (rows - k, 1)).into_owned();
        w[0] -= alpha;
        let w_norm_squared = w.norm_squared();
        for j in k..columns {
            let mut column = a.view_mut((k, j), (rows - k, 1));
            let projection = 2.0 * w.dot(&column) / w_norm_squared;
            column -= &w * projection;
        }
        for i in k + 1..rows {
            a[(i, k)] = 0.0;
        }
    }
    let r = a.rows(0, rows.min(columns)).upper_triangle();
    (r, order)
}

/// The minimum-norm solutions of a x = b on the independent rows of a, for a matrix factored
/// once and solved for several right-hand sides. aᵀ P = Q R by Householder reflections with
/// column pivoting (as [`pivoted_qr`], on aᵀ: the rows of a come in order of their size left
/// independent of those before), stopped where the next diagonal falls to `relative_floor`
/// times the first: the r rows before are independent, the rest taken as their combinations.
/// Then x = Q₁ R₁₁⁻ᵀ (Pᵀ b)₁ solves those r rows and lies in their span, hence has the
/// least norm (Björck, *Numerical Methods for Least Squares Problems*, SIAM 1996, §1.3 and
/// §2.7). The reflections are kept and applied to the solutions: Q is never formed, so a
/// solve costs O(n r) per right-hand side after the factorisation's O(n r p).
pub struct MinimumNormRows {
    /// aᵀ after the reflections: R₁₁ in its first r rows and columns.
    reduced: DMatrix<f64>,
    /// The reflections I − β w wᵀ, the k-th acting on rows k.. of a column of n.
    reflections: Vec<(DVector<f64>, f64)>,
    /// `order[k]`: the row of a that came k-th.
    order: Vec<usize>,
}

impl MinimumNormRows {
    /// The factorisation of `a`, its independent rows found by the pivoting; `None` where an
    /// entry is not finite.
    pub fn new(a: &DMatrix<f64>, relative_floor: f64) -> Option<MinimumNormRows> {
        let order = (0..a.nrows()).collect();
        MinimumNormRows::factor(a.transpose(), order, true, relative_floor)
    }

    /// The factorisation of `a` on the rows `rows` (in that order, without pivoting), as found
    /// independent by [`MinimumNormRows::new`] at a nearby matrix: the same solutions at the
    /// cost of the factorisation alone. `None` where an entry is not finite or those rows are
    /// no longer independent.
    pub fn on_rows(
        a: &DMatrix<f64>,
        rows: &[usize],
        relative_floor: f64,
    ) -> Option<MinimumNormRows> {
        let transposed = DMatrix::from_fn(a.ncols(), rows.len(), |i, k| a[(rows[k], i)]);
        let factors = MinimumNormRows::factor(transposed, rows.to_vec(), false, relative_floor)?;
        (factors.rank() == rows.len()).then_some(factors)
    }

    /// The rows of a found independent, in the factorisation's order.
    pub fn independent_rows(&self) -> &[usize] {
        &self.order[..self.rank()]
    }

    /// Householder reflections on `t` = aᵀ (columns: the rows `order` of a), each column
    /// brought next by its size when `pivoting`, stopped at the first diagonal at or below
    /// `relative_floor` times the first.
    fn factor(
        mut t: DMatrix<f64>,
        mut order: Vec<usize>,
        pivoting: bool,
        relative_floor: f64,
    ) -> Option<MinimumNormRows> {
        if !t.iter().all(|x| x.is_finite()) {
            return None;
        }
        let (n, p) = t.shape();
        let mut reflections = Vec::new();
        let mut first = 0.0;
        for k in 0..n.min(p) {
            let norm_below = |t: &DMatrix<f64>, j: usize| t.view_range(k.., j).norm();
            let (pivot, norm) = match pivoting {
                true => (k..p)
                    .map(|j| (j, norm_below(&t, j)))
                    .max_by(|a, b| a.1.total_cmp(&b.1))
                    .unwrap_or((k, 0.0)),
                false => (k, norm_below(&t, k)),
            };
            if k == 0 {
                first = norm;
            }
            if norm == 0.0 || norm <= relative_floor * first {
                break;
            }
            t.swap_columns(k, pivot);
            order.swap(k, pivot);
            // The reflection maps the column below k onto alpha e_k, its sign chosen against
            // cancellation.
            let alpha = if t[(k, k)] > 0.0 { -norm } else { norm };
            let mut w: DVector<f64> = t.view_range(k.., k).into_owned();
            w[0] -= alpha;
            let beta = 2.0 / w.norm_squared();
            for j in k + 1..p {
                let mut column = t.view_range_mut(k.., j);
                let projection = beta * w.dot(&column);
                column.axpy(-projection, &w, 1.0);
            }
            t[(k, k)] = alpha;
            reflections.push((w, beta));
        }
        Some(MinimumNormRows {
            reduced: t,
            reflections,
            order,
        })
    }

    /// How many rows of a are independent.
    pub fn rank(&self) -> usize {
        self.reflections.len()
    }

    /// The minimum-norm solution of the independent rows of a x = b, column by column of b.
    pub fn solve(&self, b: &DMatrix<f64>) -> DMatrix<f64> {
        let (n, rank) = (self.reduced.nrows(), self.rank());
        let mut x = DMatrix::zeros(n, b.ncols());
        for (column, mut solution) in b.column_iter().zip(x.column_iter_mut()) {
            // R₁₁ᵀ y = (Pᵀ b)₁ by forward substitution, y in the solution's first rows.
            for i in 0..rank {
                let mut sum = column[self.order[i]];
                for l in 0..i {
                    sum -= self.reduced[(l, i)] * solution[l];
                }
                solution[i] = sum / self.reduced[(i, i)];
            }
            // x = H₀ H₁ … H_{r−1} [y; 0].
            for (k, (w, beta)) in self.reflections.iter().enumerate().rev() {
                let mut below = solution.rows_mut(k, n - k);
                let projection = beta * w.dot(&below);
                below.axpy(-projection, w, 1.0);
            }
        }
        x
    }
}
