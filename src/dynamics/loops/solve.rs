//! The constrained equations `M v̇ = f + Gᵀλ`, `G v̇ + γ = 0`, solved on the rows the loops'
//! `Structure` keeps, by the null-space method on a QR factorisation of those rows (made
//! dimensionless): Gₛᵀ = Q₁R, and Q₂ completes Q₁ to an orthonormal basis, so Q₂ spans the
//! motions the loops allow. Then
//!
//! - the particular acceleration a₀ = −Q₁R⁻ᵀγₛ, the smallest with Gₛa₀ = −γₛ;
//! - the allowed part a = a₀ + Q₂z, with (Q₂ᵀMQ₂) z = Q₂ᵀ(f − Ma₀) by Cholesky;
//! - the multipliers Rλₛ = Q₁ᵀ(Ma − f).
//!
//! The kept rows are fixed along the run and independent wherever the mechanism is regular, so
//! the accelerations are a smooth function of the state there; the basis Q₂ may turn from one
//! evaluation to the next, but the accelerations do not depend on it. Motions that move no mass
//! (their number is part of the structure) are left at rest.

use nalgebra::{DMatrix, DVector};

use super::rows::Constraints;
use super::structure::{full_mass, Structure};

/// How the constraints are kept: by projecting the state after each step (exact), by Baumgarte's
/// feedback in the accelerations (with this rate, in 1/s, critically damped), by the integrator's
/// own equations (the symplectic integrator's RATTLE steps), or not at all.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Stabilisation {
    Projection,
    Baumgarte(f64),
    Integrator,
    None,
}

pub struct Solution {
    /// Accelerations of every state velocity.
    pub accelerations: DVector<f64>,
    /// Constraint wrench of each loop on its second body, at the loop point in fixed axes:
    /// moment, then force (6 per loop).
    pub multipliers: DVector<f64>,
}

#[derive(Clone, Debug, PartialEq)]
pub enum LoopError {
    /// An effort acts on a motion that moves no mass: its acceleration would be infinite. The
    /// state velocity that motion moves most.
    MasslessMotion { velocity: usize },
    /// The kept rows are dependent here: the mechanism is exactly at a singular configuration.
    /// The row (among the 6 per loop) that lost its independence.
    Singular { row: usize },
}

/// A force on a motion without mass stops the run above this fraction of the largest force on
/// the motions: it is a model that forgot a mass, not the residue (1e-6 relative seen on the
/// Delta's rod spins) of evaluating forces that balance exactly.
const MASSLESS_FORCE: f64 = 1e-3;

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
}

impl Factored {
    pub fn new(jacobian: &DMatrix<f64>, structure: &Structure) -> Factored {
        let n = jacobian.ncols();
        let r = structure.rows.len();
        let transposed = DMatrix::from_fn(n, r, |column, k| {
            jacobian[(structure.rows[k], column)] * structure.scales[k]
        });
        let (range, null_space, triangle) = if r == 0 {
            (DMatrix::zeros(n, 0), DMatrix::identity(n, n), DMatrix::zeros(0, 0))
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
            rows: structure.rows.clone(),
            scales: structure.scales.clone(),
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
    pub fn least_norm(&self, b: &DVector<f64>) -> Result<DVector<f64>, LoopError> {
        let y = self
            .triangle
            .tr_solve_upper_triangular(b)
            .filter(|y| y.iter().all(|x| x.is_finite()))
            .ok_or_else(|| self.singular())?;
        Ok(&self.range * y)
    }

    /// v without its part across the kept rows: the closest motion they allow.
    pub fn allowed_part(&self, v: &DVector<f64>) -> DVector<f64> {
        v - &self.range * (self.range.transpose() * v)
    }

    /// λ, 6 per loop (zero on the rows not kept), with Gᵀλ = y for y in the kept rows' span.
    fn multipliers(&self, y: &DVector<f64>, total: usize) -> Result<DVector<f64>, LoopError> {
        let kept = self
            .triangle
            .solve_upper_triangular(&(self.range.transpose() * y))
            .filter(|l| l.iter().all(|x| x.is_finite()))
            .ok_or_else(|| self.singular())?;
        let mut all = DVector::zeros(total);
        for (k, (&row, scale)) in self.rows.iter().zip(&self.scales).enumerate() {
            all[row] = kept[k] * scale;
        }
        Ok(all)
    }

    /// How far the kept rows are from dependent: the smallest diagonal entry of R over the
    /// largest (1 for rows orthogonal and of equal length, 0 at a singular configuration), and
    /// the row (among the 6 per loop) of the smallest.
    pub fn conditioning(&self) -> (f64, Option<usize>) {
        let diagonal = self.triangle.diagonal().map(f64::abs);
        if diagonal.is_empty() {
            return (1.0, None);
        }
        let largest = diagonal.max();
        let smallest = diagonal.imin();
        let ratio = if largest > 0.0 {
            diagonal[smallest] / largest
        } else {
            0.0
        };
        (ratio, Some(self.rows[smallest]))
    }

    fn singular(&self) -> LoopError {
        LoopError::Singular {
            row: self.conditioning().1.unwrap_or(0),
        }
    }
}

/// Solves `M v̇ = f + Gᵀλ`, `G v̇ + γ = 0` on the kept rows (γ with Baumgarte's terms when asked
/// for); `mass` is the tree's mass matrix, `force` has the state's length.
pub fn solve(
    mass: &DMatrix<f64>,
    force: &DVector<f64>,
    c: &Constraints,
    structure: &Structure,
    stabilisation: Stabilisation,
) -> Result<Solution, LoopError> {
    let full_mass = full_mass(mass, force.len());
    let mut gamma = c.bias.clone();
    if let Stabilisation::Baumgarte(rate) = stabilisation {
        gamma += 2.0 * rate * &c.velocity + rate * rate * &c.residual;
    }
    let factored = Factored::new(&c.jacobian, structure);
    let particular = factored.least_norm(&-factored.kept(&gamma))?;
    let null = &factored.null_space;
    let reduced_mass = null.transpose() * &full_mass * null;
    let reduced_force = null.transpose() * (force - &full_mass * &particular);
    let z = massive_solve(reduced_mass, &reduced_force, structure.massless).map_err(|k| {
        LoopError::MasslessMotion {
            velocity: null.column(k).iamax(),
        }
    })?;
    let accelerations = particular + null * z;
    let multipliers =
        factored.multipliers(&(&full_mass * &accelerations - force), c.residual.len())?;
    Ok(Solution {
        accelerations,
        multipliers,
    })
}

/// Solves the symmetric positive semi-definite system `a z = b` in the span of the eigenvectors
/// that carry mass: the `massless` smallest eigenvalues count as without mass (their number is
/// part of the structure, not decided here). A motion without mass stays at rest unless a force
/// acts on it (then its eigenvector index is the error).
fn massive_solve(
    a: DMatrix<f64>,
    b: &DVector<f64>,
    massless: usize,
) -> Result<DVector<f64>, usize> {
    if a.nrows() == 0 {
        return Ok(DVector::zeros(0));
    }
    if massless == 0 {
        if let Some(cholesky) = a.clone().cholesky() {
            return Ok(cholesky.solve(b));
        }
    }
    let eigen = a.symmetric_eigen();
    let mut order: Vec<usize> = (0..eigen.eigenvalues.len()).collect();
    order.sort_by(|&i, &j| eigen.eigenvalues[i].total_cmp(&eigen.eigenvalues[j]));
    let scale = b.amax().max(f64::MIN_POSITIVE);
    let mut z = DVector::zeros(b.len());
    for (rank, &k) in order.iter().enumerate() {
        let (value, vector) = (eigen.eigenvalues[k], eigen.eigenvectors.column(k));
        let component = vector.dot(b);
        if rank >= massless && value > 0.0 {
            z += vector * (component / value);
        } else if component.abs() > MASSLESS_FORCE * scale {
            return Err(k);
        }
    }
    Ok(z)
}
