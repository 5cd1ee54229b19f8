//! Twists and the adjoint action of rigid transforms. A twist is `[ω; v]`: angular velocity and
//! the velocity of the point at the origin of the frame it is expressed in.

use nalgebra::{Isometry3, Matrix3, Translation3, UnitQuaternion, Vector3, Vector6};

pub type Twist = Vector6<f64>;
pub type Pose = Isometry3<f64>;

pub fn twist(angular: Vector3<f64>, linear: Vector3<f64>) -> Twist {
    Twist::new(
        angular.x, angular.y, angular.z, linear.x, linear.y, linear.z,
    )
}

pub fn angular(t: &Twist) -> Vector3<f64> {
    Vector3::new(t[0], t[1], t[2])
}

pub fn linear(t: &Twist) -> Vector3<f64> {
    Vector3::new(t[3], t[4], t[5])
}

/// Re-expresses a twist given in the frame `pose` describes into the frame `pose` is relative to.
pub fn transform_twist(pose: &Pose, t: &Twist) -> Twist {
    let rotation = pose.rotation;
    let w = rotation * angular(t);
    let v = rotation * linear(t) + pose.translation.vector.cross(&w);
    twist(w, v)
}

/// Velocity of the point `p` of a body moving with (spatial) twist `t`.
pub fn point_velocity(t: &Twist, p: &Vector3<f64>) -> Vector3<f64> {
    linear(t) + angular(t).cross(p)
}

pub fn translation(v: Vector3<f64>) -> Pose {
    Isometry3::from_parts(Translation3::from(v), UnitQuaternion::identity())
}

/// Rotation by `angle` about the unit vector `axis`.
pub fn rotation(axis: &Vector3<f64>, angle: f64) -> Pose {
    Isometry3::from_parts(
        Translation3::identity(),
        UnitQuaternion::from_scaled_axis(axis * angle),
    )
}

/// The vector of the skew-symmetric part of `m`: `vee((m - mᵀ)/2)`.
pub fn skew_vector(m: &Matrix3<f64>) -> Vector3<f64> {
    Vector3::new(
        m[(2, 1)] - m[(1, 2)],
        m[(0, 2)] - m[(2, 0)],
        m[(1, 0)] - m[(0, 1)],
    ) * 0.5
}

pub fn hat(v: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -v.z, v.y, v.z, 0.0, -v.x, -v.y, v.x, 0.0)
}
