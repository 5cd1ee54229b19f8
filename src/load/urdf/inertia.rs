//! Mass properties: a URDF inertia tensor as LSD's principal moments and axes.

use nalgebra::{Matrix3, Rotation3, SymmetricEigen, UnitQuaternion, Vector3};
use urdf_rs::Inertial;

pub(super) fn is_massless(inertial: &Inertial) -> bool {
    let i = &inertial.inertia;
    inertial.mass.value == 0.0 && [i.ixx, i.ixy, i.ixz, i.iyy, i.iyz, i.izz] == [0.0; 6]
}

/// The inertia tensor about the centre of mass, in the inertial origin's frame.
pub(super) fn tensor(inertial: &Inertial) -> Matrix3<f64> {
    let i = &inertial.inertia;
    Matrix3::new(
        i.ixx, i.ixy, i.ixz, i.ixy, i.iyy, i.iyz, i.ixz, i.iyz, i.izz,
    )
}

/// Principal moments, and the rotation from the tensor's frame to the principal axes (its
/// columns), `None` when the tensor is already diagonal.
pub struct Principal {
    /// The principal moments of inertia.
    pub moments: Vector3<f64>,
    /// The principal axes as the columns of a rotation, `None` for a diagonal tensor.
    pub axes: Option<Rotation3<f64>>,
}

/// The principal moments and axes of an inertia tensor.
pub fn principal(tensor: &Matrix3<f64>) -> Principal {
    let off_diagonal = [tensor[(0, 1)], tensor[(0, 2)], tensor[(1, 2)]];
    if off_diagonal == [0.0; 3] {
        return Principal {
            moments: tensor.diagonal(),
            axes: None,
        };
    }
    let eigen = SymmetricEigen::new(*tensor);
    let (axes, moments) = closest_frame(&eigen.eigenvectors, &eigen.eigenvalues);
    Principal {
        moments,
        axes: Some(axes),
    }
}

/// Among the orders and directions of the eigenvectors that make a proper rotation, the one
/// closest to the identity (largest trace): each principal axis goes with the nearest axis of the
/// tensor's frame, so a nearly diagonal tensor gets a small rotation and its moments keep their
/// order.
fn closest_frame(vectors: &Matrix3<f64>, values: &Vector3<f64>) -> (Rotation3<f64>, Vector3<f64>) {
    const ORDERS: [[usize; 3]; 6] = [
        [0, 1, 2],
        [0, 2, 1],
        [1, 0, 2],
        [1, 2, 0],
        [2, 0, 1],
        [2, 1, 0],
    ];
    let candidates = ORDERS.iter().flat_map(|order| {
        (0..8).map(move |signs: usize| {
            let mut frame = Matrix3::zeros();
            for (k, &column) in order.iter().enumerate() {
                let sign = if signs >> k & 1 == 1 { -1.0 } else { 1.0 };
                frame.set_column(k, &(vectors.column(column) * sign));
            }
            (
                frame,
                Vector3::new(values[order[0]], values[order[1]], values[order[2]]),
            )
        })
    });
    let best = candidates
        .filter(|(frame, _)| frame.determinant() > 0.0)
        .max_by(|a, b| a.0.trace().total_cmp(&b.0.trace()));
    let (frame, moments) = best.unwrap_or((Matrix3::identity(), *values));
    (Rotation3::from_matrix_unchecked(frame), moments)
}

/// `angle || axis` of a rotation, through its quaternion: `atan2` keeps every digit of the angle,
/// small or near a half turn (the `acos` of the trace would lose half of them).
pub fn axis_angle(rotation: &Rotation3<f64>) -> Option<(f64, Vector3<f64>)> {
    let q = UnitQuaternion::from_rotation_matrix(rotation).into_inner();
    let (w, v) = if q.w < 0.0 {
        (-q.w, -q.imag())
    } else {
        (q.w, q.imag())
    };
    let s = v.norm();
    (s > 0.0).then(|| (2.0 * s.atan2(w), v / s))
}
