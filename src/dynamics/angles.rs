//! The angles a program declared for a spherical or free joint, recovered from the quaternion
//! the dynamics integrates (and back). Three rotations about axes a1, a2, a3 with a1 ⊥ a2 and
//! a2 ⊥ a3 (Euler and Bryant angles) reach every rotation; at the singularity (the middle angle
//! makes a1 and a3 parallel) only the sum or difference of the outer angles is defined. A
//! reference (the run's angles and rates at its last step, [`AngleReference`]) chooses among
//! the solutions, so reported angles stay continuous and keep their turns.

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

#[cfg(lsdc_internals)]
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
    let branches = angle_branches(axes, r, previous[0]);
    nearest_branch(&branches, &[*previous; 2]).1
}

/// The two solutions (θ1, θ2, θ3) of R = R(a1, θ1) R(a2, θ2) R(a3, θ3), each up to turns: the
/// middle angle θ2 = φ ± s, and its mirror, whose outer angles differ by π. Near the
/// singularity (s or π − s below 1e-7), where only a combination of the outer angles is
/// defined, the first is `first_if_singular` and the third takes the rest.
pub fn angle_branches(
    axes: &[Vector3<f64>; 3],
    r: &UnitQuaternion<f64>,
    first_if_singular: f64,
) -> [[f64; 3]; 2] {
    let [a1, a2, a3] = axes;
    // a1·R a3 = a1·R(a2, θ2) a3 = α cos θ2 + β sin θ2.
    let target = a1.dot(&(r * a3));
    let (alpha, beta) = (a1.dot(a3), a1.dot(&a2.cross(a3)));
    let rho = (alpha * alpha + beta * beta).sqrt();
    let phi = beta.atan2(alpha);
    let spread = (target / rho).clamp(-1.0, 1.0).acos();
    let singular = spread.abs() < 1e-7 || (PI - spread).abs() < 1e-7;
    [phi + spread, phi - spread].map(|middle| {
        if singular {
            // The outer angles are coupled: keep the first and solve for the third from the
            // whole rotation.
            let first = first_if_singular;
            let rest = UnitQuaternion::from_axis_angle(&Unit::new_normalize(*a2), middle).inverse()
                * UnitQuaternion::from_axis_angle(&Unit::new_normalize(*a1), first).inverse()
                * r;
            let normal = a1.cross(a3).try_normalize(1e-12).unwrap_or(*a2);
            return [first, middle, angle_between(a3, &normal, &(rest * normal))];
        }
        let w = rotate(a2, middle, a3);
        let first = angle_between(a1, &w, &(r * a3));
        let w_back = rotate(a2, -middle, a1);
        let third = -angle_between(a3, &w_back, &(r.inverse() * a1));
        [first, middle, third]
    })
}

/// Of the two branches, each angle moved by whole turns to its nearest to `predicted` (one
/// prediction per branch), the branch nearest its prediction over the three angles together,
/// and which it is.
pub fn nearest_branch(branches: &[[f64; 3]; 2], predicted: &[[f64; 3]; 2]) -> (usize, [f64; 3]) {
    let unwrapped = [0, 1].map(|k| [0, 1, 2].map(|i| unwrap(branches[k][i], predicted[k][i])));
    let distance = |k: usize| -> f64 {
        (unwrapped[k].iter().zip(&predicted[k]))
            .map(|(a, b)| (a - b).abs())
            .sum()
    };
    let nearest = usize::from(distance(1) < distance(0));
    (nearest, unwrapped[nearest])
}

/// Where the declared coordinates of a run are expected: their values and rates at `time`. An
/// angle recovered from a quaternion at time t is taken on the branch and turn nearest the
/// trapezoid prediction c + ½ (ċ + ċ(t)) (t − time), from the reference's rates and the
/// state's own: the angles keep every turn however far an angle advances between two
/// references as long as its rate changes by much less than π over the interval, and the
/// middle angle passes a singular configuration on the side its rate carries it to.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct AngleReference {
    pub time: f64,
    pub coordinates: Vec<f64>,
    pub rates: Vec<f64>,
}

impl AngleReference {
    /// The reference of coordinates at rest at t = 0: angles are taken nearest them.
    pub fn at_rest(coordinates: Vec<f64>) -> AngleReference {
        let rates = vec![0.0; coordinates.len()];
        AngleReference {
            time: 0.0,
            coordinates,
            rates,
        }
    }
}

/// One joint's share of an [`AngleReference`], seen from time t.
#[derive(Clone, Copy, Debug)]
pub struct JointReference<'r> {
    pub coordinates: &'r [f64],
    pub rates: &'r [f64],
    /// t less the reference's time.
    pub elapsed: f64,
}

impl Joint {
    /// Declared coordinates and their rates from the joint's positions and velocities, angles
    /// on the branch nearest `reference` (see [`AngleReference`]).
    pub fn declared(
        &self,
        q: &[f64],
        v: &[f64],
        reference: JointReference,
    ) -> Result<(Vec<f64>, Vec<f64>), EvalError> {
        let n = self.chain.coordinate_count();
        let (mut coordinates, mut rates) = (vec![0.0; n], vec![0.0; n]);
        let mut chain = ChainMotion::default();
        let out = (&mut coordinates[..], &mut rates[..]);
        self.declared_into(q, v, reference, out, &mut chain)?;
        Ok((coordinates, rates))
    }

    /// `declared` into `out` (coordinates, rates: the chain's count each), with `chain` as
    /// scratch: nothing is allocated once it has held this chain's motion.
    pub fn declared_into(
        &self,
        q: &[f64],
        v: &[f64],
        reference: JointReference,
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
        let start = if free { 3 } else { 0 };
        let JointReference {
            coordinates: before,
            rates: rates_before,
            elapsed,
        } = reference;
        let first_if_singular = before[start] + rates_before[start] * elapsed;
        let branches = angle_branches(axes, &chain.rotation, first_if_singular);
        if free {
            coordinates[..3].copy_from_slice(chain.translation.vector.as_slice());
        }
        // Rates: the chain's spatial twist equals S(declared) · rates. S has the angles' period
        // 2π, so the first branch gives them whatever its turns; the mirror branch, whose
        // outer angles differ by the constant π, has the same outer rates and the opposite
        // middle one.
        coordinates[start..].copy_from_slice(&branches[0]);
        let body_twist = body_twist(v, free);
        let spatial_twist = if self.first_on_parent {
            motion_to_parent(&moving, &body_twist)
        } else {
            -body_twist
        };
        self.chain
            .chain_motion_into(coordinates, None, chain_motion)?;
        solve_least_squares(chain_motion, &spatial_twist, rates);
        let branch_rates = [
            [rates[start], rates[start + 1], rates[start + 2]],
            [rates[start], -rates[start + 1], rates[start + 2]],
        ];
        let predicted = branch_rates.map(|now| {
            [0, 1, 2].map(|i| {
                let k = start + i;
                before[k] + 0.5 * (rates_before[k] + now[i]) * elapsed
            })
        });
        let (branch, angles) = nearest_branch(&branches, &predicted);
        rates[start + 1] = branch_rates[branch][1];
        coordinates[start..].copy_from_slice(&angles);
        Ok(())
    }

    /// The joint's positions and velocities from declared coordinates and rates.
    pub fn state_from_declared(
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
