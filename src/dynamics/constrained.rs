//! Forward dynamics with closed loops (first step towards simulating them): the coordinates are
//! those of the tree followed by those of the complementary links, the closure Jacobian J gives
//! the constraints J q̈ + J̇ q̇ = 0, and the equations M q̈ + h = Jᵀλ are solved by the null-space
//! method, which tolerates redundant constraints: q̈ = q̈ₚ + N z with q̈ₚ the minimum-norm solution
//! of the constraints, N a basis of the null space of J, and (NᵀMN) z = Nᵀ(−h − M q̈ₚ). The
//! complementary links' coordinates carry no inertia of their own (they move with the bodies).

use nalgebra::{DMatrix, DVector};

use super::algorithms::{crba, rnea, Data};
use super::model::Model;
use super::spatial::Force;
use crate::kinematics::closure::closure;
use crate::kinematics::model::KinematicModel;

/// Relative tolerance below which a singular value of J counts as zero.
const TOLERANCE: f64 = 1e-9;

pub struct ConstrainedAccelerations {
    /// Accelerations of every coordinate (tree, then complementary links).
    pub accelerations: DVector<f64>,
    /// Constraint forces, one per closure row (6 per complementary link).
    pub multipliers: DVector<f64>,
}

/// J̇ q̇ by a central difference of the closure Jacobian along q̇.
fn jacobian_rate_times_velocity(kinematics: &KinematicModel, q: &[f64], v: &[f64]) -> Result<DVector<f64>, String> {
    let speed = v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let step = 1e-6 / (1.0 + speed);
    let shifted = |sign: f64| -> Result<DMatrix<f64>, String> {
        let moved: Vec<f64> = q.iter().zip(v).map(|(x, r)| x + sign * step * r).collect();
        closure(kinematics, &moved).map(|c| c.jacobian).map_err(|e| format!("{e:?}"))
    };
    let derivative = (shifted(1.0)? - shifted(-1.0)?) / (2.0 * step);
    Ok(derivative * DVector::from_column_slice(v))
}

/// Splits the right singular vectors of `j` into a null-space basis and the pseudo-inverse.
fn null_space_and_pseudo_inverse(j: &DMatrix<f64>) -> (DMatrix<f64>, DMatrix<f64>) {
    let n = j.ncols();
    let rows = j.nrows().max(n);
    let mut square = DMatrix::zeros(rows, n);
    square.rows_mut(0, j.nrows()).copy_from(j);
    let svd = square.svd(true, true);
    let (Some(u), Some(v_t)) = (svd.u, svd.v_t) else { return (DMatrix::identity(n, n), DMatrix::zeros(n, j.nrows())) };
    let largest = svd.singular_values.iter().copied().fold(0.0, f64::max);
    let mut null = Vec::new();
    let mut pseudo = DMatrix::zeros(n, rows);
    for (k, &sigma) in svd.singular_values.iter().enumerate() {
        if sigma <= TOLERANCE * largest || largest == 0.0 {
            null.push(v_t.row(k).transpose());
        } else {
            pseudo += v_t.row(k).transpose() * u.column(k).transpose() / sigma;
        }
    }
    let basis = if null.is_empty() { DMatrix::zeros(n, 0) } else { DMatrix::from_columns(&null) };
    (basis, pseudo.columns(0, j.nrows()).into_owned())
}

/// Accelerations and constraint forces of a mechanism with loops at (q, v), under generalised
/// forces `tau` on the tree's coordinates and external forces on the bodies.
pub fn constrained_accelerations(
    model: &Model,
    kinematics: &KinematicModel,
    data: &mut Data,
    q: &[f64],
    v: &[f64],
    tau: &[f64],
    external: &[Force],
) -> Result<ConstrainedAccelerations, String> {
    let (nt, n) = (model.nv, kinematics.coordinate_count);
    if model.nq != model.nv {
        return Err("closed loops need joints in their own coordinates (no quaternion joints)".to_string());
    }
    let mass_tree = crba(model, data, &q[..nt]).map_err(|e| format!("{e:?}"))?;
    let bias = rnea(model, data, &q[..nt], &v[..nt], &vec![0.0; nt], external).map_err(|e| format!("{e:?}"))?;
    let mut mass = DMatrix::zeros(n, n);
    mass.view_mut((0, 0), (nt, nt)).copy_from(&mass_tree);
    let mut force = DVector::zeros(n);
    force.rows_mut(0, nt).copy_from(&(DVector::from_column_slice(tau) - bias));
    let jacobian = closure(kinematics, q).map_err(|e| format!("{e:?}"))?.jacobian;
    let rate = jacobian_rate_times_velocity(kinematics, q, v)?;
    let (null, pseudo_inverse) = null_space_and_pseudo_inverse(&jacobian);
    let particular = -(&pseudo_inverse * &rate);
    let reduced_mass = null.transpose() * &mass * &null;
    let reduced_force = null.transpose() * (&force - &mass * &particular);
    let z = reduced_mass
        .cholesky()
        .ok_or_else(|| "the mechanism has a motion that moves no mass: the constrained mass matrix is singular".to_string())?
        .solve(&reduced_force);
    let accelerations = particular + &null * z;
    let residual_force = &mass * &accelerations - &force;
    let multipliers = pseudo_inverse.transpose() * residual_force;
    Ok(ConstrainedAccelerations { accelerations, multipliers })
}
