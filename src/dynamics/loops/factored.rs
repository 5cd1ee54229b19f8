//! The QR factorisation of the rows a run keeps (made dimensionless): Gₛᵀ = Q₁R, with Q₂
//! completing Q₁ to an orthogonal matrix, so that Q₂ spans the motions those rows allow. It
//! serves the equations of motion (`solve`), the projection (`project`) and the decisions on the
//! rows (`structure`).

use nalgebra::{DMatrix, DVector};

/// Which of the loops' rows (6 per loop) are kept, and the factor making each dimensionless.
#[derive(Clone, Debug, PartialEq)]
pub struct RowChoice {
    /// The firm rows first, then the `weak` ones.
    pub rows: Vec<usize>,
    pub scales: Vec<f64>,
    /// How many of the last rows close their loop only at second order: independent of the
    /// others by about the square root of the closure residual (1e-8), so they are solved
    /// exactly, never damped.
    pub weak: usize,
}

impl RowChoice {
    /// The rows given (firm first, then `weak` of them), made dimensionless with the
    /// characteristic length L (see `row_scale`).
    pub fn new(rows: Vec<usize>, weak: usize, length: f64) -> RowChoice {
        let scales = rows.iter().map(|&r| row_scale(r, length)).collect();
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

/// The QR factorisation of the kept rows of G at one state.
pub struct Factored {
    /// Q₁: an orthonormal basis of the kept rows' span (one column per kept row).
    range: DMatrix<f64>,
    /// Q₂: an orthonormal basis of the motions the kept rows allow.
    pub null_space: DMatrix<f64>,
    /// R, upper triangular: Gₛᵀ = Q₁R.
    triangle: DMatrix<f64>,
    rows: Vec<usize>,
    scales: Vec<f64>,
    firm: usize,
}

/// The kept rows are dependent at this state: it is exactly a singular configuration. The row
/// (among the 6 per loop) that lost its independence.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Singular {
    pub row: usize,
}

impl Factored {
    pub fn new(jacobian: &DMatrix<f64>, choice: &RowChoice) -> Factored {
        let n = jacobian.ncols();
        let r = choice.rows.len();
        let transposed = DMatrix::from_fn(n, r, |column, k| {
            jacobian[(choice.rows[k], column)] * choice.scales[k]
        });
        let (range, null_space, triangle) = if r == 0 {
            (
                DMatrix::zeros(n, 0),
                DMatrix::identity(n, n),
                DMatrix::zeros(0, 0),
            )
        } else {
            let qr = transposed.qr();
            let mut q_transposed = DMatrix::identity(n, n);
            qr.q_tr_mul(&mut q_transposed);
            let q = q_transposed.transpose();
            (
                q.columns(0, r).into_owned(),
                q.columns(r, n - r).into_owned(),
                qr.r(),
            )
        };
        Factored {
            range,
            null_space,
            triangle,
            rows: choice.rows.clone(),
            scales: choice.scales.clone(),
            firm: choice.firm(),
        }
    }

    /// The kept rows of a vector of rows (6 per loop), made dimensionless.
    pub fn kept(&self, all: &DVector<f64>) -> DVector<f64> {
        DVector::from_iterator(
            self.rows.len(),
            self.rows.iter().zip(&self.scales).map(|(&r, s)| all[r] * s),
        )
    }

    /// The smallest x with Gₛx = b (b as from `kept`), or the row lost at a singularity.
    pub fn least_norm(&self, b: &DVector<f64>) -> Result<DVector<f64>, Singular> {
        let y = self
            .triangle
            .tr_solve_upper_triangular(b)
            .filter(|y| y.iter().all(|x| x.is_finite()))
            .ok_or_else(|| self.singular())?;
        Ok(&self.range * y)
    }

    /// `least_norm` damped by `damping` (relative, see `DAMPING`): the same wherever the rows
    /// are independent, bounded at a singular configuration.
    pub fn damped_least_norm(
        &self,
        b: &DVector<f64>,
        damping: f64,
    ) -> Result<DVector<f64>, Singular> {
        let y = self.normal_solve(b, damping)?;
        Ok(&self.range * (&self.triangle * y))
    }

    /// v without its part across the kept rows, damped by `damping`: the closest motion they
    /// allow wherever they are independent; near a singular configuration, a velocity off the
    /// rows by a small error is not thrown along the direction they are about to lose (which
    /// would kick a parallelogram onto its other branch).
    pub fn damped_allowed_part(
        &self,
        v: &DVector<f64>,
        damping: f64,
    ) -> Result<DVector<f64>, Singular> {
        let across = self.triangle.tr_mul(&(self.range.transpose() * v));
        let y = self.normal_solve(&across, damping)?;
        Ok(v - &self.range * (&self.triangle * y))
    }

    /// (RᵀR + μ²E)⁻¹ b, with μ = `damping` times the largest diagonal entry of R and E the
    /// identity on the firm rows, zero on the weak ones: R⁻¹R⁻ᵀb wherever the rows are
    /// independent, bounded where the firm rows lose their independence.
    fn normal_solve(&self, b: &DVector<f64>, damping: f64) -> Result<DVector<f64>, Singular> {
        let largest = self.triangle.diagonal().amax();
        let damping = (damping * largest).powi(2);
        let mut normal = self.triangle.tr_mul(&self.triangle);
        for k in 0..self.firm {
            normal[(k, k)] += damping;
        }
        normal
            .cholesky()
            .map(|c| c.solve(b))
            .filter(|y| y.iter().all(|x| x.is_finite()))
            .ok_or_else(|| self.singular())
    }

    /// v without its part across the kept rows: the closest motion they allow.
    pub fn allowed_part(&self, v: &DVector<f64>) -> DVector<f64> {
        v - &self.range * (self.range.transpose() * v)
    }

    /// λ, 6 per loop (zero on the rows not kept), with Gᵀλ = y for y in the kept rows' span.
    pub fn multipliers(&self, y: &DVector<f64>, total: usize) -> Result<DVector<f64>, Singular> {
        let kept = self.normal_solve(
            &self.triangle.tr_mul(&(self.range.transpose() * y)),
            DAMPING,
        )?;
        let mut all = DVector::zeros(total);
        for (k, (&row, scale)) in self.rows.iter().zip(&self.scales).enumerate() {
            all[row] = kept[k] * scale;
        }
        Ok(all)
    }

    /// How far the firm rows are from dependent: the smallest diagonal entry of R over the
    /// largest, among the firm rows (1 for rows orthogonal and of equal length, 0 at a singular
    /// configuration), and the row (among the 6 per loop) of the smallest.
    pub fn conditioning(&self) -> (f64, Option<usize>) {
        let diagonal = self.triangle.diagonal().map(f64::abs);
        let firm = diagonal.rows(0, self.firm);
        if firm.is_empty() {
            return (1.0, None);
        }
        let (largest, smallest) = (firm.max(), firm.imin());
        let ratio = if largest > 0.0 {
            firm[smallest] / largest
        } else {
            0.0
        };
        (ratio, Some(self.rows[smallest]))
    }

    fn singular(&self) -> Singular {
        Singular {
            row: self.conditioning().1.unwrap_or(0),
        }
    }
}
