//! The planar form of a model: its joints, bodies and loops in planar vectors, built once from
//! the spatial model when `decide` finds the mechanism planar.
//!
//! Every body gets a *planar frame*: its own origin, with the axes (e₁, e₂, n) of the plane's
//! basis `W` when every coordinate is zero. Its joints turning about n only, the body's planar
//! frame keeps its z axis along n in every configuration, so each joint's transform between
//! the planar frames of its parent and child is a turn about the normal and a translation in
//! the plane (the offset along n, constant, moves nothing in the plane).

use nalgebra::{Matrix3, Vector2, Vector3};

use super::algebra::{PlanarForce, PlanarInertia, PlanarMotion, PlanarTransform};

/// How a joint moves its child in the plane, between the planar frames of its dynamic parent
/// and its child.
#[derive(Clone, Debug, PartialEq)]
pub enum PlanarJointKind {
    /// A turn by `rate` · q about the point `pivot_parent` of the parent, which is the point
    /// `pivot_child` of the child: the child's origin is at pivot_parent − R(θ) pivot_child.
    Revolute {
        rate: f64,
        pivot_parent: Vector2<f64>,
        pivot_child: Vector2<f64>,
    },
    /// A translation by q · `direction` (parent's axes) from `origin`, without turning.
    Prismatic {
        origin: Vector2<f64>,
        direction: Vector2<f64>,
    },
    /// No coordinate: the child's constant translation in the parent.
    Weld { origin: Vector2<f64> },
}

/// A tree joint in the plane.
#[derive(Clone, Debug, PartialEq)]
pub struct PlanarJoint {
    /// The joint's index in `Model::joints`.
    pub index: usize,
    pub parent: usize,
    pub child: usize,
    pub q_offset: usize,
    pub v_offset: usize,
    pub kind: PlanarJointKind,
    /// The motion of a unit rate, in the child's planar frame (zero for a weld).
    pub column: PlanarMotion,
}

impl PlanarJoint {
    /// The number of velocities: one, none for a weld.
    pub fn nv(&self) -> usize {
        match self.kind {
            PlanarJointKind::Weld { .. } => 0,
            _ => 1,
        }
    }

    /// The child's planar frame in the parent's at coordinate q.
    #[inline]
    pub fn transform(&self, q: f64) -> PlanarTransform {
        match &self.kind {
            PlanarJointKind::Revolute {
                rate,
                pivot_parent,
                pivot_child,
            } => {
                let turned = PlanarTransform::new(rate * q, Vector2::zeros());
                PlanarTransform {
                    translation: pivot_parent - turned.rotate(pivot_child),
                    ..turned
                }
            }
            PlanarJointKind::Prismatic { origin, direction } => {
                PlanarTransform::new(0.0, origin + direction * q)
            }
            PlanarJointKind::Weld { origin } => PlanarTransform::new(0.0, *origin),
        }
    }
}

/// How a complementary link closes its loop in the plane.
#[derive(Clone, Debug, PartialEq)]
pub enum PlanarLoopKind {
    /// A turn about the first frame's origin, at `rate` per unit of the coordinate about n.
    Revolute { rate: f64 },
    /// A translation along `direction` (the first body's planar axes) per unit of the
    /// coordinate.
    Prismatic { direction: Vector2<f64> },
}

/// A complementary link in the plane: its chain starts at the point `first` of the first body
/// (planar frame); the loop point is where the chain ends.
#[derive(Clone, Debug, PartialEq)]
pub struct PlanarLoop {
    pub first_body: usize,
    pub second_body: usize,
    pub first: Vector2<f64>,
    pub kind: PlanarLoopKind,
}

/// A model's planar form (see the module's documentation).
#[derive(Clone, Debug, PartialEq)]
pub struct PlanarModel {
    /// The plane's basis in the fixed axes: columns e₁, e₂ and the normal n.
    pub basis: Matrix3<f64>,
    /// When each of n, e₁ and e₂ is a fixed axis or its opposite, the rows of a spatial motion
    /// (`spatial_motion`) that its three planar components give, with their signs: ω n is
    /// row k of the angular part, v₁ e₁ and v₂ e₂ rows 3 + k of the linear one.
    pub rows: Option<[(usize, f64); 3]>,
    /// The dynamic joints (the model's `dynamic_joints`, in their order).
    pub joints: Vec<PlanarJoint>,
    /// Per body number (0 is earth), the rotation from its frame's axes to its planar frame's:
    /// a vector of the body, written in the planar frame.
    pub to_planar: Vec<Matrix3<f64>>,
    /// Per body (body j at j − 1), its inertia as the recursions see it (merged welds added)
    /// about its origin in its planar frame, and whether it has none.
    pub bodies: Vec<PlanarInertia>,
    pub massless: Vec<bool>,
    /// The base's acceleration that stands for the gravity field (`Model::gravity`): −g in
    /// the plane.
    pub base_acceleration: PlanarMotion,
    pub loops: Vec<PlanarLoop>,
}

impl PlanarModel {
    pub fn normal(&self) -> Vector3<f64> {
        self.basis.column(2).into_owned()
    }

    /// A spatial force of body `body` (its frame's axes, about its origin) as a planar force:
    /// its moment about the normal and its force in the plane.
    #[inline]
    pub fn planar_force(&self, body: usize, f: &crate::spatial::Force) -> PlanarForce {
        let r = &self.to_planar[body];
        let moment = r.row(2).transpose().dot(&f.fixed_rows::<3>(0));
        let force = r.fixed_rows::<2>(0) * f.fixed_rows::<3>(3);
        PlanarForce::new(moment, force.x, force.y)
    }

    /// Writes the planar motion `m` of the fixed plane into `column` as a spatial motion in the
    /// fixed axes, ω n and v₁ e₁ + v₂ e₂: where the basis is made of fixed axes, its three
    /// rows alone (the others are left as they are: zero wherever the motion is planar).
    #[inline]
    pub fn write_spatial<S>(&self, m: &PlanarMotion, column: &mut S)
    where
        S: std::ops::IndexMut<usize, Output = f64>,
    {
        match &self.rows {
            Some(rows) => {
                for (&(row, sign), value) in rows.iter().zip(m.iter()) {
                    column[row] = sign * value;
                }
            }
            None => {
                let spatial = self.spatial_motion(m);
                for (row, value) in spatial.iter().enumerate() {
                    column[row] = *value;
                }
            }
        }
    }

    /// A planar motion of the fixed plane as a spatial motion in the fixed axes: ω n and
    /// v₁ e₁ + v₂ e₂.
    #[inline]
    pub fn spatial_motion(&self, m: &PlanarMotion) -> crate::spatial::Motion {
        let b = &self.basis;
        crate::spatial::twist(b.column(2) * m[0], b.column(0) * m[1] + b.column(1) * m[2])
    }
}
