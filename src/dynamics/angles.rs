//! The angles a program declared for a spherical or free joint, recovered from the quaternion
//! the dynamics integrates (and back). Three rotations about axes a1, a2, a3 with a1 ⊥ a2 and
//! a2 ⊥ a3 (Euler and Bryant angles) reach every rotation; at the singularity (the middle angle
//! makes a1 and a3 parallel) only the sum or difference of the outer angles is defined, and the
//! previous values choose among the solutions, so reported angles stay continuous.

use std::f64::consts::PI;

use nalgebra::{Rotation3, Unit, UnitQuaternion, Vector3};

use super::joint::{quaternion, Joint, JointType};
use crate::kinematics::eval::EvalError;
use crate::kinematics::model::ChainMotion;
use crate::spatial::{motion_to_parent, Motion, Pose};

fn rotate(axis: &Vector3<f64>, angle: f64, v: &Vector3<f64>) -> Vector3<f64> {
    Rotation3::from_axis_angle(&Unit::new_normalize(*axis), angle) * v
}

/// Angle of the rotation about `axis` that carries `from` onto `to` (their components normal to
/// the axis).
fn angle_between(axis: &Vector3<f64>, from: &Vector3<f64>, to: &Vector3<f64>) -> f64 {
    let sine = axis.dot(&from.cross(to));
    let cosine = from.dot(to) - axis.dot(from) * axis.dot(to);
    sine.atan2(cosine)
}

/// `angle + 2πk` closest to `reference`.
fn unwrap(angle: f64, reference: f64) -> f64 {
    angle + 2.0 * PI * ((reference - angle) / (2.0 * PI)).round()
}

pub fn rotation_from_angles(axes: &[Vector3<f64>; 3], angles: &[f64]) -> UnitQuaternion<f64> {
    (0..3).fold(UnitQuaternion::identity(), |r, k| {
        r * UnitQuaternion::from_axis_angle(&Unit::new_normalize(axes[k]), angles[k])
    })
}

/// Angles (θ1, θ2, θ3) with R = R(a1, θ1) R(a2, θ2) R(a3, θ3), closest to `previous`.
pub fn angles_from_rotation(
    axes: &[Vector3<f64>; 3],
    r: &UnitQuaternion<f64>,
    previous: &[f64; 3],
) -> [f64; 3] {
    let [a1, a2, a3] = axes;
    // a1·R a3 = a1·R(a2, θ2) a3 = α cos θ2 + β sin θ2.
    let target = a1.dot(&(r * a3));
    let (alpha, beta) = (a1.dot(a3), a1.dot(&a2.cross(a3)));
    let rho = (alpha * alpha + beta * beta).sqrt();
    let phi = beta.atan2(alpha);
    let spread = (target / rho).clamp(-1.0, 1.0).acos();
    let mut best = [0.0; 3];
    let mut best_distance = f64::INFINITY;
    for middle in [phi + spread, phi - spread] {
        let middle = unwrap(middle, previous[1]);
        let w = rotate(a2, middle, a3);
        let first_raw = angle_between(a1, &w, &(r * a3));
        let w_back = rotate(a2, -middle, a1);
        let third_raw = -angle_between(a3, &w_back, &(r.inverse() * a1));
        // Near the singularity the outer angles are coupled: keep the first where it was and
        // solve for the third from the whole rotation.
        let singular = spread.abs() < 1e-7 || (PI - spread).abs() < 1e-7;
        let (first, third) = if singular {
            let first = previous[0];
            let rest = UnitQuaternion::from_axis_angle(&Unit::new_normalize(*a2), middle).inverse()
                * UnitQuaternion::from_axis_angle(&Unit::new_normalize(*a1), first).inverse()
                * r;
            let third = angle_between(
                a3,
                &a1.cross(a3).try_normalize(1e-12).unwrap_or(*a2),
                &(rest * a1.cross(a3).try_normalize(1e-12).unwrap_or(*a2)),
            );
            (first, unwrap(third, previous[2]))
        } else {
            (
                unwrap(first_raw, previous[0]),
                unwrap(third_raw, previous[2]),
            )
        };
        let candidate = [first, middle, third];
        let distance: f64 = candidate
            .iter()
            .zip(previous)
            .map(|(a, b)| (a - b).abs())
            .sum();
        if distance < best_distance {
            best_distance = distance;
            best = candidate;
        }
    }
    best
}

impl Joint {
    /// Declared coordinates and their rates from the joint's positions and velocities.
    /// `previous` (declared coordinates at the last output) keeps angles continuous.
    pub fn declared(
        &self,
        q: &[f64],
        v: &[f64],
        previous: &[f64],
    ) -> Result<(Vec<f64>, Vec<f64>), EvalError> {
        let n = self.chain.coordinate_count();
        let (mut coordinates, mut rates) = (vec![0.0; n], vec![0.0; n]);
        let mut chain = ChainMotion::default();
        let out = (&mut coordinates[..], &mut rates[..]);
        self.declared_into(q, v, previous, out, &mut chain)?;
        Ok((coordinates, rates))
    }

    /// `declared` into `out` (coordinates, rates: the chain's count each), with `chain` as
    /// scratch: nothing is allocated once it has held this chain's motion.
    pub fn declared_into(
        &self,
        q: &[f64],
        v: &[f64],
        previous: &[f64],
        (coordinates, rates): (&mut [f64], &mut [f64]),
        chain_motion: &mut ChainMotion,
    ) -> Result<(), EvalError> {
        let axes = match &self.kind {
            JointType::Chain => {
                coordinates.copy_from_slice(q);
                rates.copy_from_slice(v);
                return Ok(());
            }
            JointType::Spherical { axes } | JointType::Free { axes } => axes,
        };
        let free = matches!(self.kind, JointType::Free { .. });
        let (translation, rotation) = if free {
            (Vector3::new(q[0], q[1], q[2]), quaternion(&q[3..7]))
        } else {
            (Vector3::zeros(), quaternion(&q[0..4]))
        };
        let moving = Pose::from_parts(translation.into(), rotation);
        let chain = if self.first_on_parent {
            moving
        } else {
            moving.inverse()
        };
        let angle_start = if free { 3 } else { 0 };
        let reference = [
            previous[angle_start],
            previous[angle_start + 1],
            previous[angle_start + 2],
        ];
        let angles = angles_from_rotation(axes, &chain.rotation, &reference);
        if free {
            coordinates[..3].copy_from_slice(chain.translation.vector.as_slice());
        }
        coordinates[angle_start..].copy_from_slice(&angles);
        // Rates: the chain's spatial twist equals S(declared) · rates.
        let body_twist = body_twist(v, free);
        let spatial_twist = if self.first_on_parent {
            motion_to_parent(&moving, &body_twist)
        } else {
            -body_twist
        };
        self.chain
            .chain_motion_into(coordinates, None, chain_motion)?;
        solve_least_squares(chain_motion, &spatial_twist, rates);
        Ok(())
    }

    /// The joint's positions and velocities from declared coordinates and rates.
    pub fn from_declared(
        &self,
        coordinates: &[f64],
        rates: &[f64],
    ) -> Result<(Vec<f64>, Vec<f64>), EvalError> {
        if self.kind == JointType::Chain {
            return Ok((coordinates.to_vec(), rates.to_vec()));
        }
        let free = matches!(self.kind, JointType::Free { .. });
        let motion = self.chain.chain_motion(coordinates, Some(rates))?;
        let moving = if self.first_on_parent {
            motion.pose
        } else {
            motion.pose.inverse()
        };
        let body = if self.first_on_parent {
            crate::spatial::motion_to_child(&motion.pose, &motion.velocity)
        } else {
            -motion.velocity
        };
        let r = moving.rotation;
        let mut q = Vec::with_capacity(7);
        if free {
            q.extend_from_slice(moving.translation.vector.as_slice());
        }
        q.extend_from_slice(&[r.w, r.i, r.j, r.k]);
        let v = if free {
            body.as_slice().to_vec()
        } else {
            body.as_slice()[0..3].to_vec()
        };
        Ok((q, v))
    }
}

fn body_twist(v: &[f64], free: bool) -> Motion {
    if free {
        Motion::from_column_slice(v)
    } else {
        Motion::new(v[0], v[1], v[2], 0.0, 0.0, 0.0)
    }
}

/// Least-squares solution of `S x = b` into x, S the chain's subspace: by QR while S has full
/// column rank (accurate to round-off), by the minimum-norm SVD solution at a singular
/// configuration (gimbal lock). On S padded to 6 × 6 (`ChainMotion::padded_subspace`), so that
/// nothing is allocated.
fn solve_least_squares(motion: &ChainMotion, b: &Motion, x: &mut [f64]) {
    let n = motion.subspace.ncols();
    let padded = motion.padded_subspace();
    let qr = padded.qr();
    let r = qr.r();
    let diagonal = r.diagonal();
    let largest = diagonal.rows(0, n).amax();
    if diagonal
        .rows(0, n)
        .iter()
        .all(|d| d.abs() > 1e-10 * largest)
    {
        let mut rhs = qr.q().transpose() * b;
        let mut top = rhs.rows_mut(0, n);
        if r.view((0, 0), (n, n)).solve_upper_triangular_mut(&mut top) {
            x.copy_from_slice(top.as_slice());
            return;
        }
    }
    // nalgebra's SVD never ends on a non-finite matrix (see `crate::linalg`).
    if !padded.iter().all(|v| v.is_finite()) {
        x.fill(f64::NAN);
        return;
    }
    match padded.svd(true, true).solve(b, 1e-12) {
        Ok(solution) => x.copy_from_slice(&solution.as_slice()[..n]),
        Err(_) => x.fill(f64::NAN),
    }
}
