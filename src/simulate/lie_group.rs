//! The configuration space the variational integrator steps on: the chain joints' coordinates
//! (and the complementary links') move by their rates, as in a vector space; a spherical joint
//! turns on SO(3) (unit quaternion, body angular velocity ω) and a free joint moves on SE(3)
//! (position and unit quaternion, body twist (ω, v) in the `Motion` layout, angular part
//! first), each through its group's exponential: q_{k+1} = q_k · exp(X), X = h ξ the step's
//! increment in the joint's velocities. These are the motions `Joint::position_rate` integrates
//! exactly when the velocity is constant.
//!
//! The discrete Euler–Lagrange equations on a group need, per joint, the derivatives of its
//! exponential (left-trivialised: exp(X + δX) = exp(X) · exp(J_r(X) δX) to first order),
//! J_r(X) = Σ (−ad_X)ⁿ/(n + 1)!, J_l(X) = Σ ad_Xⁿ/(n + 1)! and Ad_{exp X} = Σ ad_Xⁿ/n!, with
//! ad the Lie bracket (ω̂ on so(3), the motion cross product on se(3)). All of them are sums of
//! one sequence of powers ad_Xⁿ/n! with scalar weights, taken to round-off: a step turns a joint
//! by far less than a radian, so a few terms suffice, and one formula serves both groups without
//! the cancellations of the closed forms at small angles.

use nalgebra::{DVector, Matrix6, SMatrix, Translation3, UnitQuaternion, Vector3, Vector6};

use crate::dynamics::joint::{quaternion, JointType};
use crate::dynamics::model::Model;
use crate::spatial::{self, Pose};

/// A joint that moves on a group: where its positions and velocities start, and which group.
#[derive(Clone, Copy, Debug)]
struct GroupJoint {
    free: bool,
    q_offset: usize,
    v_offset: usize,
}

impl GroupJoint {
    fn nv(&self) -> usize {
        if self.free {
            6
        } else {
            3
        }
    }

    fn velocities(&self) -> std::ops::Range<usize> {
        self.v_offset..self.v_offset + self.nv()
    }

    /// The bracket ad_X in a 6 × 6 matrix: a spherical joint's ω̂ in the leading 3 × 3 block
    /// (the series below then keep the identity or zero in the rest, and act on velocities
    /// padded with zeros as they would on the three), a free joint's motion cross product
    /// [ω̂ 0; v̂ ω̂].
    fn bracket(&self, x: &[f64]) -> Matrix6<f64> {
        let mut ad = Matrix6::zeros();
        let spin = spatial::skew(&Vector3::new(x[0], x[1], x[2]));
        ad.fixed_view_mut::<3, 3>(0, 0).copy_from(&spin);
        if self.free {
            ad.fixed_view_mut::<3, 3>(3, 3).copy_from(&spin);
            let drift = spatial::skew(&Vector3::new(x[3], x[4], x[5]));
            ad.fixed_view_mut::<3, 3>(3, 0).copy_from(&drift);
        }
        ad
    }

    /// The joint's entries of a vector over the velocities, padded with zeros to six.
    fn padded(&self, v: &DVector<f64>) -> Vector6<f64> {
        let mut out = Vector6::zeros();
        out.rows_mut(0, self.nv())
            .copy_from(&v.rows(self.v_offset, self.nv()));
        out
    }

    /// q0 · exp(X) for this joint's positions.
    fn advance(&self, q0: &[f64], x: &[f64], q: &mut [f64]) {
        let turn = UnitQuaternion::from_scaled_axis(Vector3::new(x[0], x[1], x[2]));
        if !self.free {
            let end = quaternion(&q0[self.q_offset..self.q_offset + 4]) * turn;
            write_quaternion(&end, &mut q[self.q_offset..self.q_offset + 4]);
            return;
        }
        let start = Pose::from_parts(
            Translation3::new(
                q0[self.q_offset],
                q0[self.q_offset + 1],
                q0[self.q_offset + 2],
            ),
            quaternion(&q0[self.q_offset + 3..self.q_offset + 7]),
        );
        // SE(3)'s exponential: the rotation exp(ω̂), the translation J_l(ω) v.
        let spin = spatial::skew(&Vector3::new(x[0], x[1], x[2]));
        let shift =
            weighted(&powers(&spin), |n| 1.0 / (n + 1) as f64) * Vector3::new(x[3], x[4], x[5]);
        let step = Pose::from_parts(Translation3::from(shift), turn);
        let end = start * step;
        q[self.q_offset..self.q_offset + 3].copy_from_slice(end.translation.vector.as_slice());
        write_quaternion(&end.rotation, &mut q[self.q_offset + 3..self.q_offset + 7]);
    }
}

fn write_quaternion(rotation: &UnitQuaternion<f64>, out: &mut [f64]) {
    let q = rotation.quaternion();
    out.copy_from_slice(&[q.w, q.i, q.j, q.k]);
}

/// adⁿ/n! for n = 0, 1, … until they fall below round-off (the exponential's series; a step
/// turns a joint by far less than a radian, so a few terms).
fn powers<const N: usize>(ad: &SMatrix<f64, N, N>) -> Vec<SMatrix<f64, N, N>> {
    let mut powers = vec![SMatrix::<f64, N, N>::identity()];
    for n in 1..60 {
        let next = ad * powers[n - 1] / n as f64;
        let small = next.amax() < 1e-18;
        powers.push(next);
        if small {
            break;
        }
    }
    powers
}

/// Σ weight(n) · adⁿ/n! over the powers: weight 1/(n + 1) gives J_l, (−1)ⁿ/(n + 1) J_r,
/// sⁿ/(n + 1) and sⁿ those at sX (J_l(sX), Ad_{exp(sX)}).
fn weighted<const N: usize>(
    powers: &[SMatrix<f64, N, N>],
    weight: impl Fn(usize) -> f64,
) -> SMatrix<f64, N, N> {
    powers
        .iter()
        .enumerate()
        .fold(SMatrix::zeros(), |sum, (n, power)| sum + power * weight(n))
}

/// The inverse of an exponential's Jacobian, invertible for turns below 2π. A step that turns
/// further has diverged: NaN then makes it fail as not finite.
fn inverse(matrix: Matrix6<f64>) -> Matrix6<f64> {
    matrix
        .try_inverse()
        .unwrap_or_else(|| Matrix6::from_element(f64::NAN))
}

/// The operators of one group joint's discrete Euler–Lagrange equations at increment X.
struct StepOperators {
    /// J_l(X)⁻ᵀ, which carries the step's momentum to its start.
    start_transport: Matrix6<f64>,
    /// J_r(X)⁻ᵀ, which carries it to its end.
    end_transport: Matrix6<f64>,
    /// J_r(X/2)ᵀ and Ad_{exp(−X/2)}ᵀ, which carry the midpoint's forces to the increment and to
    /// the step's start.
    midpoint_to_increment: Matrix6<f64>,
    midpoint_to_start: Matrix6<f64>,
}

impl StepOperators {
    /// The four from one series of powers of ad_X.
    fn at(joint: &GroupJoint, x: &[f64]) -> StepOperators {
        let powers = powers(&joint.bracket(x));
        let jacobian = |scale: f64| weighted(&powers, |n| scale.powi(n as i32) / (n + 1) as f64);
        StepOperators {
            start_transport: inverse(jacobian(1.0)).transpose(),
            end_transport: inverse(jacobian(-1.0)).transpose(),
            midpoint_to_increment: jacobian(-0.5).transpose(),
            midpoint_to_start: weighted(&powers, |n| (-0.5f64).powi(n as i32)).transpose(),
        }
    }

    /// Π = M v̄ + h/2 J_r(X/2)ᵀ g: the derivative of the discrete Lagrangian along X.
    fn mean_momentum(&self, mass_mean: Vector6<f64>, forces: Vector6<f64>, h: f64) -> Vector6<f64> {
        mass_mean + self.midpoint_to_increment * forces * (0.5 * h)
    }
}

/// How a state's positions move with its velocities (see the module's documentation).
pub struct Configuration {
    /// (position, velocity) indices of the coordinates that move by their rates.
    coordinates: Vec<(usize, usize)>,
    groups: Vec<GroupJoint>,
    positions: usize,
    velocities: usize,
}

/// A step's end while its equations are solved: the positions, and the increment X that
/// reaches them on the group joints (its other entries are unused: the coordinates' ends are
/// kept themselves, so that a mechanism without group joints steps exactly as before).
pub struct StepEnd {
    pub positions: DVector<f64>,
    increment: DVector<f64>,
}

impl Configuration {
    pub fn of(model: &Model) -> Configuration {
        let mut coordinates = Vec::new();
        let mut groups = Vec::new();
        for joint in &model.joints {
            match joint.kind {
                JointType::Chain => coordinates
                    .extend((0..joint.nv()).map(|k| (joint.q_offset + k, joint.v_offset + k))),
                JointType::Spherical { .. } | JointType::Free { .. } => groups.push(GroupJoint {
                    free: matches!(joint.kind, JointType::Free { .. }),
                    q_offset: joint.q_offset,
                    v_offset: joint.v_offset,
                }),
            }
        }
        coordinates.extend((0..model.nc).map(|k| (model.nq + k, model.nv + k)));
        Configuration {
            coordinates,
            groups,
            positions: model.positions(),
            velocities: model.velocities(),
        }
    }

    /// The first guess of a step's end: q ⊕ h v.
    pub fn first_guess(&self, q: &DVector<f64>, v: &DVector<f64>, h: f64) -> StepEnd {
        let mut positions = DVector::zeros(self.positions);
        for &(i, j) in &self.coordinates {
            positions[i] = q[i] + v[j] * h;
        }
        let increment = v * h;
        for joint in &self.groups {
            joint.advance(
                q.as_slice(),
                &increment.as_slice()[joint.velocities()],
                positions.as_mut_slice(),
            );
        }
        StepEnd {
            positions,
            increment,
        }
    }

    /// The step's midpoint: (q0 + q1)/2 on the coordinates, q0 · exp(X/2) on the groups.
    pub fn midpoint(&self, q0: &DVector<f64>, end: &StepEnd) -> DVector<f64> {
        let mut mid = DVector::zeros(self.positions);
        for &(i, _) in &self.coordinates {
            mid[i] = (q0[i] + end.positions[i]) * 0.5;
        }
        for joint in &self.groups {
            let half = &end.increment.as_slice()[joint.velocities()];
            let half: Vec<f64> = half.iter().map(|x| x * 0.5).collect();
            joint.advance(q0.as_slice(), &half, mid.as_mut_slice());
        }
        mid
    }

    /// The step's mean velocity: (q1 − q0)/h on the coordinates, X/h on the groups (the body
    /// velocity all along q0 · exp(t X/h)).
    pub fn mean_velocity(&self, q0: &DVector<f64>, end: &StepEnd, h: f64) -> DVector<f64> {
        let mut mean = DVector::zeros(self.velocities);
        for &(i, j) in &self.coordinates {
            mean[j] = (end.positions[i] - q0[i]) / h;
        }
        for joint in &self.groups {
            for j in joint.velocities() {
                mean[j] = end.increment[j] / h;
            }
        }
        mean
    }

    /// Moves the step's end by `correction`, a motion of the end in the velocities (as the
    /// loops' Jacobian there sees it): added to the coordinates, and on the groups turned into
    /// the change J_r(X)⁻¹ δ of the increment.
    pub fn correct(&self, q0: &DVector<f64>, end: &mut StepEnd, correction: &DVector<f64>) {
        for &(i, j) in &self.coordinates {
            end.positions[i] += correction[j];
        }
        for joint in &self.groups {
            let range = joint.velocities();
            let powers = powers(&joint.bracket(&end.increment.as_slice()[range.clone()]));
            let end_to_increment = inverse(weighted(&powers, |n| {
                (-1.0f64).powi(n as i32) / (n + 1) as f64
            }));
            let change = end_to_increment * joint.padded(correction);
            let mut increment = end.increment.rows_mut(range.start, range.len());
            increment += change.rows(0, range.len());
            joint.advance(
                q0.as_slice(),
                &end.increment.as_slice()[range],
                end.positions.as_mut_slice(),
            );
        }
    }

    /// Rewrites on the group joints the residual of the step's momentum balance, which the
    /// coordinates' formula gave as M v̄ − h/2 g − p_k: there it is
    /// J_l(X)⁻ᵀ Π − h Ad_{exp(−X/2)}ᵀ g − p_k, with Π = M v̄ + h/2 J_r(X/2)ᵀ g, g the midpoint's
    /// forces (∂T/∂q and the efforts, left-trivialised) and `mass_mean` = M v̄.
    pub fn start_balance(
        &self,
        end: &StepEnd,
        (mass_mean, forces): (&DVector<f64>, &DVector<f64>),
        start_momentum: &DVector<f64>,
        h: f64,
        balance: &mut DVector<f64>,
    ) {
        for joint in &self.groups {
            let operators = StepOperators::at(joint, &end.increment.as_slice()[joint.velocities()]);
            let g = joint.padded(forces);
            let pi = operators.mean_momentum(joint.padded(mass_mean), g, h);
            let start = operators.start_transport * pi
                - operators.midpoint_to_start * g * h
                - joint.padded(start_momentum);
            let n = joint.nv();
            balance
                .rows_mut(joint.v_offset, n)
                .copy_from(&start.rows(0, n));
        }
    }

    /// Rewrites on the group joints the momentum at the step's end, which the coordinates'
    /// formula gave as M v̄ + h/2 g: there it is J_r(X)⁻ᵀ Π (see `start_balance`).
    pub fn end_momentum(
        &self,
        end: &StepEnd,
        (mass_mean, forces): (&DVector<f64>, &DVector<f64>),
        h: f64,
        momentum: &mut DVector<f64>,
    ) {
        for joint in &self.groups {
            let operators = StepOperators::at(joint, &end.increment.as_slice()[joint.velocities()]);
            let pi = operators.mean_momentum(joint.padded(mass_mean), joint.padded(forces), h);
            let n = joint.nv();
            let end_momentum = operators.end_transport * pi;
            momentum
                .rows_mut(joint.v_offset, n)
                .copy_from(&end_momentum.rows(0, n));
        }
    }

    /// Cubic Hermite interpolation within the step at fraction s (positions, then velocities):
    /// on the coordinates as usual; on the groups the increment from q0 is interpolated,
    /// Y(s) = h00·0 + h10·h v0 + h01·X + h11·h v1, and q(s) = q0 · exp(Y(s)), exact at both ends.
    pub fn interpolate(
        &self,
        (q0, v0): (&DVector<f64>, &DVector<f64>),
        (end, v1): (&StepEnd, &DVector<f64>),
        s: f64,
        h: f64,
    ) -> Vec<f64> {
        let [h00, h10, h01, h11] = hermite_weights(s);
        let [d00, d10, d01, d11] = hermite_slopes(s);
        let q1 = &end.positions;
        let mut q = DVector::zeros(self.positions);
        let mut v = DVector::zeros(self.velocities);
        for &(i, j) in &self.coordinates {
            q[i] = q0[i] * h00 + v0[j] * (h10 * h) + q1[i] * h01 + v1[j] * (h11 * h);
            v[j] = (q0[i] * d00 + q1[i] * d01) / h + v0[j] * d10 + v1[j] * d11;
        }
        for joint in &self.groups {
            let range = joint.velocities();
            let x = end.increment.rows(range.start, range.len());
            let (v0, v1) = (
                v0.rows(range.start, range.len()),
                v1.rows(range.start, range.len()),
            );
            let y = v0 * (h10 * h) + x * h01 + v1 * (h11 * h);
            joint.advance(q0.as_slice(), y.as_slice(), q.as_mut_slice());
            let rate = x * (d01 / h) + v0 * d10 + v1 * d11;
            v.rows_mut(range.start, range.len()).copy_from(&rate);
        }
        let mut y = q.as_slice().to_vec();
        y.extend_from_slice(v.as_slice());
        y
    }
}

/// The cubic Hermite basis at s: h00, h10, h01, h11.
pub fn hermite_weights(s: f64) -> [f64; 4] {
    [
        2.0 * s * s * s - 3.0 * s * s + 1.0,
        s * s * s - 2.0 * s * s + s,
        -2.0 * s * s * s + 3.0 * s * s,
        s * s * s - s * s,
    ]
}

/// The derivatives of the cubic Hermite basis at s.
pub fn hermite_slopes(s: f64) -> [f64; 4] {
    [
        6.0 * s * s - 6.0 * s,
        3.0 * s * s - 4.0 * s + 1.0,
        -6.0 * s * s + 6.0 * s,
        3.0 * s * s - 2.0 * s,
    ]
}
