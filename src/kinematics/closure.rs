//! Closure of the complementary links: for a join `A on a`, `B on b` with chain D(q), the loop is
//! closed when pose(a)·A·D(q) = pose(b)·B. The residual has 6 rows per loop: the rotation error
//! of the relative rotation (its skew part, zero when the frames agree, see `RotationError`)
//! and the position difference, both in the world frame; its Jacobian is exact (not a finite
//! difference).

use nalgebra::{DMatrix, DVector, Matrix3, Rotation3, UnitQuaternion, Vector3};

use super::eval::EvalError;
use super::forward::{forward, Configuration};
use super::model::KinematicModel;
use crate::spatial::{self, Twist};

pub struct Closure {
    /// 6 rows per complementary link, in link order.
    pub residual: DVector<f64>,
    /// ∂residual/∂q, 6 rows per complementary link.
    pub jacobian: DMatrix<f64>,
    pub configuration: Configuration,
}

impl Closure {
    /// Largest position error and largest rotation error (skew part, ≈ angle) of loop k.
    pub fn loop_errors(&self, k: usize) -> (f64, f64) {
        let rows = self.residual.rows(6 * k, 6);
        let rotation = rows.rows(0, 3).amax();
        let position = rows.rows(3, 3).amax();
        (position, rotation)
    }
}

/// The error of a relative rotation R by angle θ about a unit axis, from its skew part
/// s = sin θ · axis: s itself within a quarter turn (θ ≤ 90°). Beyond, s shrinks back to zero
/// at a half turn, which would make a loop closed in position but turned by 180° look closed (a
/// cut revolute assembled at q + π): there the error grows on, (2 − |s|) · s / |s|, continuous
/// at 90° and 2 at a half turn.
struct RotationError {
    skew: Vector3<f64>,
    /// Beyond a quarter turn, |s| (0 at a half turn exactly).
    beyond: Option<f64>,
}

impl RotationError {
    fn of(relative: &Matrix3<f64>) -> RotationError {
        let skew = spatial::skew_vector(relative);
        let beyond = (relative.trace() < 1.0).then(|| skew.norm());
        RotationError { skew, beyond }
    }

    fn value(&self, relative: &Matrix3<f64>) -> Vector3<f64> {
        match self.beyond {
            None => self.skew,
            Some(norm) if norm > 0.0 => self.skew * (2.0 / norm - 1.0),
            // At a half turn exactly, the axis from the rotation's quaternion.
            Some(_) => {
                let rotation = Rotation3::from_matrix_unchecked(*relative);
                UnitQuaternion::from_rotation_matrix(&rotation)
                    .axis()
                    .map_or(self.skew, |axis| axis.into_inner() * 2.0)
            }
        }
    }

    /// The error's derivative, from the skew part's `d_skew`: exact but at a half turn exactly.
    fn derivative(&self, d_skew: Vector3<f64>) -> Vector3<f64> {
        match self.beyond {
            Some(norm) if norm > 0.0 => {
                let s = &self.skew;
                d_skew * (2.0 / norm - 1.0) - s * (2.0 * s.dot(&d_skew) / norm.powi(3))
            }
            _ => d_skew,
        }
    }
}

pub fn closure(model: &KinematicModel, q: &[f64]) -> Result<Closure, EvalError> {
    let configuration = forward(model, q)?;
    let loops = model.complementary();
    let nq = model.coordinate_count;
    let mut residual = DVector::zeros(6 * loops.len());
    let mut jacobian = DMatrix::zeros(6 * loops.len(), nq);
    for (k, joint) in loops.iter().enumerate() {
        let coordinates = &q[joint.offset..joint.offset + joint.coordinate_count()];
        let (chain, subspace) = joint.chain(coordinates)?;
        let base = configuration.poses[joint.first_body] * joint.first;
        let end = base * chain;
        let target = configuration.poses[joint.second_body] * joint.second;
        let (r_end, r_target) = (
            end.rotation.to_rotation_matrix(),
            target.rotation.to_rotation_matrix(),
        );
        let (p_end, p_target) = (end.translation.vector, target.translation.vector);
        let relative = r_end.matrix().transpose() * r_target.matrix();
        let error = RotationError::of(&relative);
        let rotation_error = error.value(&relative);
        let position_error = p_target - p_end;
        for r in 0..3 {
            residual[6 * k + r] = rotation_error[r];
            residual[6 * k + 3 + r] = position_error[r];
        }
        // Twists of the chain's end and of the target frame per coordinate.
        let mut end_twists = configuration.jacobians[joint.first_body].clone();
        for c in 0..joint.coordinate_count() {
            let column = Twist::from_column_slice(subspace.column(c).as_slice());
            let world = spatial::motion_to_parent(&base, &column);
            for r in 0..6 {
                end_twists[(r, joint.offset + c)] += world[r];
            }
        }
        let target_twists = &configuration.jacobians[joint.second_body];
        for c in 0..nq {
            let v_end = Twist::from_column_slice(end_twists.column(c).as_slice());
            let v_target = Twist::from_column_slice(target_twists.column(c).as_slice());
            let dw: Vector3<f64> = spatial::angular(&v_target) - spatial::angular(&v_end);
            let d_relative = r_end.matrix().transpose() * spatial::skew(&dw) * r_target.matrix();
            let d_rotation = error.derivative(spatial::skew_vector(&d_relative));
            let d_position = spatial::point_velocity(&v_target, &p_target)
                - spatial::point_velocity(&v_end, &p_end);
            for r in 0..3 {
                jacobian[(6 * k + r, c)] = d_rotation[r];
                jacobian[(6 * k + 3 + r, c)] = d_position[r];
            }
        }
    }
    // An overflowing configuration has no closure error worth solving for (and no SVD).
    if !residual
        .iter()
        .chain(jacobian.iter())
        .all(|x| x.is_finite())
    {
        return Err(EvalError::NotFinite);
    }
    Ok(Closure {
        residual,
        jacobian,
        configuration,
    })
}
