//! Spatial algebra, for the kinematics and the dynamics alike, in Featherstone's convention with
//! the angular part first: motions (twists) `[ω; v]`, the angular velocity and the velocity of
//! the point at the origin of the frame they are expressed in; forces `[n; f]`, the moment about
//! the frame's origin then the force; spatial inertias as 6×6 matrices; and rigid transforms
//! acting on them.
//!
//! The motions, forces and transforms are generic over their scalar (`Real`), as Pinocchio
//! templates its algorithms on the scalar: `f64` everywhere the program computes, and a dual
//! number where a test differentiates the recursive algorithms by forward-mode automatic
//! differentiation. The aliases default to `f64`.

use nalgebra::{
    Isometry3, Matrix3, Matrix6, Quaternion, RealField, Translation3, UnitQuaternion, Vector3,
    Vector6,
};
use wide::f64x2;

/// A scalar the spatial algebra and the recursive algorithms compute in: `f64`, or a dual
/// number (`dynamics::dual`) that carries derivatives along with values.
pub trait Real: RealField + Copy {}

impl<T: RealField + Copy> Real for T {}

/// The model's constant `x` (a length, a mass) as a scalar of the computation.
#[inline(always)]
pub fn constant<T: Real>(x: f64) -> T {
    T::from_subset(&x)
}

/// A rigid transform with its rotation as a matrix: the form the recursive algorithms use,
/// where rotating a vector costs 9 products instead of the quaternion's 18.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Transform<T: Real = f64> {
    pub rotation: Matrix3<T>,
    pub translation: Vector3<T>,
}

pub type Motion<T = f64> = Vector6<T>;
pub type Force<T = f64> = Vector6<T>;
pub type Inertia<T = f64> = Matrix6<T>;
pub type Pose<T = f64> = Isometry3<T>;
/// A motion, as the kinematics names it: `[ω; v]`.
pub type Twist<T = f64> = Motion<T>;

pub fn skew<T: Real>(v: &Vector3<T>) -> Matrix3<T> {
    let zero = T::zero();
    Matrix3::new(zero, -v.z, v.y, v.z, zero, -v.x, -v.y, v.x, zero)
}

/// Motion given in the frame of `pose` (a child), expressed in the frame `pose` is relative to.
pub fn motion_to_parent<T: Real>(pose: &Pose<T>, m: &Motion<T>) -> Motion<T> {
    let w = pose.rotation * angular(m);
    twist(
        w,
        pose.rotation * linear(m) + pose.translation.vector.cross(&w),
    )
}

/// A motion given in fixed axes about the origin, taken about the point `point` (same axes):
/// `motion_to_child` for a pure translation, without its rotations.
pub fn shifted<T: Real>(point: &Vector3<T>, m: &Motion<T>) -> Motion<T> {
    let w = angular(m);
    twist(w, linear(m) - point.cross(&w))
}

/// Motion given in the parent frame, expressed in the frame of `pose` (the child).
pub fn motion_to_child<T: Real>(pose: &Pose<T>, m: &Motion<T>) -> Motion<T> {
    let inverse = pose.rotation.inverse();
    let w = angular(m);
    twist(
        inverse * w,
        inverse * (linear(m) - pose.translation.vector.cross(&w)),
    )
}

/// Force given in the child frame, expressed in the parent frame.
pub fn force_to_parent<T: Real>(pose: &Pose<T>, f: &Force<T>) -> Force<T> {
    let force = pose.rotation * linear(f);
    twist(
        pose.rotation * angular(f) + pose.translation.vector.cross(&force),
        force,
    )
}

/// Force given in the parent frame, expressed in the child frame.
pub fn force_to_child<T: Real>(pose: &Pose<T>, f: &Force<T>) -> Force<T> {
    let inverse = pose.rotation.inverse();
    let force = linear(f);
    twist(
        inverse * (angular(f) - pose.translation.vector.cross(&force)),
        inverse * force,
    )
}

/// `a × b` for two motions.
pub fn cross_motion<T: Real>(a: &Motion<T>, b: &Motion<T>) -> Motion<T> {
    let (w, v) = (angular(a), linear(a));
    twist(
        w.cross(&angular(b)),
        w.cross(&linear(b)) + v.cross(&angular(b)),
    )
}

/// `a ×* f`: a motion acting on a force.
pub fn cross_force<T: Real>(a: &Motion<T>, f: &Force<T>) -> Force<T> {
    let (w, v) = (angular(a), linear(a));
    twist(
        w.cross(&angular(f)) + v.cross(&linear(f)),
        w.cross(&linear(f)),
    )
}

/// The 6×6 matrix of `motion_to_child(pose, ·)`.
pub fn motion_matrix_to_child(pose: &Pose) -> Matrix6<f64> {
    let r_t = pose.rotation.to_rotation_matrix().matrix().transpose();
    let mut x = Matrix6::zeros();
    x.fixed_view_mut::<3, 3>(0, 0).copy_from(&r_t);
    x.fixed_view_mut::<3, 3>(3, 3).copy_from(&r_t);
    x.fixed_view_mut::<3, 3>(3, 0)
        .copy_from(&(-r_t * skew(&pose.translation.vector)));
    x
}

impl<T: Real> Transform<T> {
    /// `self * b` into `out`, formed where it stays: a product returned from a call and copied
    /// to where it stays is read back before its stores have landed.
    pub fn compose_into(&self, b: &Transform<T>, out: &mut Transform<T>) {
        out.rotation = self.rotation * b.rotation;
        out.translation = self.rotation * b.translation + self.translation;
    }

    pub fn identity() -> Transform<T> {
        Transform {
            rotation: Matrix3::identity(),
            translation: Vector3::zeros(),
        }
    }

    pub fn inverse(&self) -> Transform<T> {
        let rt = self.rotation.transpose();
        Transform {
            rotation: rt,
            translation: -(rt * self.translation),
        }
    }

    pub fn from_pose(pose: &Pose<T>) -> Transform<T> {
        Transform {
            rotation: *pose.rotation.to_rotation_matrix().matrix(),
            translation: pose.translation.vector,
        }
    }

    /// Motion given in the parent frame, expressed in this (child) frame.
    #[inline]
    pub fn motion_to_child(&self, m: &Motion<T>) -> Motion<T> {
        let w = angular(m);
        let rt = self.rotation.transpose();
        twist(rt * w, rt * (linear(m) - self.translation.cross(&w)))
    }

    /// Force given in this (child) frame, expressed in the parent frame.
    #[inline]
    pub fn force_to_parent(&self, f: &Force<T>) -> Force<T> {
        let force = self.rotation * linear(f);
        twist(
            self.rotation * angular(f) + self.translation.cross(&force),
            force,
        )
    }

    /// Motion given in this (child) frame, expressed in the parent frame.
    #[inline]
    pub fn motion_to_parent(&self, m: &Motion<T>) -> Motion<T> {
        let w = self.rotation * angular(m);
        twist(w, self.rotation * linear(m) + self.translation.cross(&w))
    }

    /// `motion_to_parent` of a turn about the child's axis e_k at rate `scale`, [s e_k; 0]:
    /// [s r_k; p × s r_k] with r_k the k-th column of the rotation, without the products by the
    /// column's zeros (9 products instead of 24).
    #[inline]
    pub fn axis_motion_to_parent(&self, axis: usize, scale: T) -> Motion<T> {
        let w = self.rotation.column(axis) * scale;
        twist(w, self.translation.cross(&w))
    }

    /// Inertia given in this (child) frame, expressed in the parent frame, by 3 × 3 blocks:
    /// with I = [A B; Bᵀ D], rotating gives A₁ = RARᵀ, B₁ = RBRᵀ, D₁ = RDRᵀ, and moving the
    /// origin by p gives B' = B₁ + p̂D₁ and A' = A₁ − B₁p̂ − (B'p̂)ᵀ (= A₁ − B₁p̂ + p̂B₁ᵀ − p̂D₁p̂),
    /// D' = D₁. A and D are symmetric (every inertia the algorithms move is: a body's, an
    /// articulated one), so A₁, D₁ and A' are computed on and above the diagonal only and
    /// mirrored (`rotate_symmetric`); the products by p̂ are cross products (row i of M p̂ is
    /// mᵢ × p). About 200 products where X*ᵀ I X by 6 × 6 matrices takes over 400 (Pinocchio's
    /// `SE3actOn` in its ABA works by the same blocks, without the symmetry).
    pub fn inertia_to_parent(&self, i: &Inertia<T>) -> Inertia<T> {
        let r = &self.rotation;
        let p = self.translation;
        let a = rotate_symmetric(r, &i.fixed_view::<3, 3>(0, 0).into_owned());
        let d = rotate_symmetric(r, &i.fixed_view::<3, 3>(3, 3).into_owned());
        let b = r * i.fixed_view::<3, 3>(0, 3) * r.transpose();
        // B' = B₁ + p̂D₁, column by column: p × (column j of D₁).
        let mut top_right = b;
        for j in 0..3 {
            let shift = p.cross(&d.column(j).into_owned());
            top_right.set_column(j, &(b.column(j) + shift));
        }
        // Rows of B₁p̂ and of B'p̂.
        let row_cross = |m: &Matrix3<T>, k: usize| -> Vector3<T> {
            Vector3::new(m[(k, 0)], m[(k, 1)], m[(k, 2)]).cross(&p)
        };
        let rotated = [row_cross(&b, 0), row_cross(&b, 1), row_cross(&b, 2)];
        let shifted = [
            row_cross(&top_right, 0),
            row_cross(&top_right, 1),
            row_cross(&top_right, 2),
        ];
        let mut out = Matrix6::zeros();
        for row in 0..3 {
            for column in row..3 {
                let value = a[(row, column)] - rotated[row][column] - shifted[column][row];
                out[(row, column)] = value;
                out[(column, row)] = value;
            }
            for column in 0..3 {
                out[(row, column + 3)] = top_right[(row, column)];
                out[(column + 3, row)] = top_right[(row, column)];
                out[(row + 3, column + 3)] = d[(row, column)];
            }
        }
        out
    }
}

/// R S Rᵀ for a symmetric S: R S in full, then the entries of (R S) Rᵀ on and above the
/// diagonal, mirrored below (45 products where the two full products take 54).
fn rotate_symmetric<T: Real>(r: &Matrix3<T>, s: &Matrix3<T>) -> Matrix3<T> {
    let rs = r * s;
    let mut out = Matrix3::zeros();
    for row in 0..3 {
        for column in row..3 {
            let value = rs.row(row).dot(&r.row(column));
            out[(row, column)] = value;
            out[(column, row)] = value;
        }
    }
    out
}

impl<T: Real> std::ops::Mul for Transform<T> {
    type Output = Transform<T>;

    /// Composition: `a * b` maps b's frame through a's.
    fn mul(self, b: Transform<T>) -> Transform<T> {
        let mut out = Transform {
            rotation: Matrix3::zeros(),
            translation: Vector3::zeros(),
        };
        self.compose_into(&b, &mut out);
        out
    }
}

/// The inertia of a rigid body (or a rigid set of bodies) about a frame's origin in compact
/// form: mass m, first moment h = m c and rotational inertia J about the origin. The 6 × 6
/// matrix is [J ĥ; ĥᵀ m·1]. Sums of inertias about one origin are plain sums of the three.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RigidInertia {
    pub mass: f64,
    pub first: Vector3<f64>,
    pub rotational: Matrix3<f64>,
}

impl RigidInertia {
    pub fn zeros() -> RigidInertia {
        RigidInertia {
            mass: 0.0,
            first: Vector3::zeros(),
            rotational: Matrix3::zeros(),
        }
    }

    /// From the 6 × 6 matrix of a rigid body's inertia.
    pub fn from_matrix(i: &Inertia) -> RigidInertia {
        RigidInertia {
            mass: i[(3, 3)],
            first: Vector3::new(i[(2, 4)], i[(0, 5)], i[(1, 3)]),
            rotational: i.fixed_view::<3, 3>(0, 0).into_owned(),
        }
    }

    /// The inertia expressed in the parent frame of `t`: h' = R h + m p and
    /// J' = R J Rᵀ − ĥ₁p̂ − p̂ĥ₁ − m p̂p̂ with h₁ = R h (the 3 × 3 form of `inertia_to_parent`).
    ///
    /// With â b̂ = b aᵀ − (a·b) 1 the skew products are outer products:
    /// J' = R J Rᵀ + (2 h₁·p + m |p|²) 1 − p h₁ᵀ − h₁ pᵀ − m p pᵀ.
    pub fn to_parent(&self, t: &Transform) -> RigidInertia {
        let r = &t.rotation;
        let p = t.translation;
        let h1 = r * self.first;
        let m = self.mass;
        let rotated = rotate_symmetric(r, &self.rotational);
        let diagonal = 2.0 * h1.dot(&p) + m * p.norm_squared();
        // Symmetric: the upper triangle only, mirrored.
        let mut rotational = Matrix3::zeros();
        for i in 0..3 {
            for j in i..3 {
                let value = rotated[(i, j)] - p[i] * h1[j] - h1[i] * p[j] - m * p[i] * p[j]
                    + if i == j { diagonal } else { 0.0 };
                rotational[(i, j)] = value;
                rotational[(j, i)] = value;
            }
        }
        RigidInertia {
            mass: m,
            first: h1 + m * p,
            rotational,
        }
    }

    /// `to_parent` in fewer products, for the mass matrix's pass over every body. With
    /// J = J₂₂ 1 + U Vᵀ + V Uᵀ, U the first two columns of the identity and V = [(J₀₀ − J₂₂)/2,
    /// J₀₁; 0, (J₁₁ − J₂₂)/2; J₀₂, J₁₂] (the split Pinocchio's `Symmetric3::rotate` uses), the
    /// rotated R J Rᵀ = J₂₂ 1 + (RU)(RV)ᵀ + (RV)(RU)ᵀ, where RU is two columns of R; and with
    /// g = h₁ + m p / 2 the parallel-axis terms of `to_parent` are (2 g·p) 1 − p gᵀ − g pᵀ. So
    /// J' = X Yᵀ + Y Xᵀ + (J₂₂ + 2 g·p) 1 with X = [r₀ r₁ p] and Y = [RV₀ RV₁ −g]: about 70
    /// products where `to_parent` takes about 85. Equal to it to round-off (the sums differ).
    pub fn to_parent_by_split(&self, t: &Transform) -> RigidInertia {
        let (r, p, j, m) = (&t.rotation, t.translation, &self.rotational, self.mass);
        let (r0, r1, r2) = (r.column(0), r.column(1), r.column(2));
        let j22 = j[(2, 2)];
        let v0 = r0 * (0.5 * (j[(0, 0)] - j22)) + r2 * j[(0, 2)];
        let v1 = r0 * j[(0, 1)] + r1 * (0.5 * (j[(1, 1)] - j22)) + r2 * j[(1, 2)];
        let half_mass = 0.5 * m;
        let g = r * self.first + p * half_mass;
        let diagonal = j22 + 2.0 * g.dot(&p);
        let mut rotational = Matrix3::zeros();
        for a in 0..3 {
            for b in a..3 {
                let value = r0[a] * v0[b] + v0[a] * r0[b] + r1[a] * v1[b] + v1[a] * r1[b]
                    - p[a] * g[b]
                    - g[a] * p[b];
                rotational[(a, b)] = value;
                rotational[(b, a)] = value;
            }
            rotational[(a, a)] += diagonal;
        }
        RigidInertia {
            mass: m,
            first: g + p * half_mass,
            rotational,
        }
    }

    /// The 6 × 6 matrix [J ĥ; ĥᵀ m·1].
    pub fn matrix(&self) -> Inertia {
        let h = skew(&self.first);
        let mut i = Matrix6::zeros();
        i.fixed_view_mut::<3, 3>(0, 0).copy_from(&self.rotational);
        i.fixed_view_mut::<3, 3>(0, 3).copy_from(&h);
        i.fixed_view_mut::<3, 3>(3, 0).copy_from(&h.transpose());
        i.fixed_view_mut::<3, 3>(3, 3)
            .copy_from(&(Matrix3::identity() * self.mass));
        i
    }

    /// `times` of two motions at once, side by side in two lanes (`paired`): the same products
    /// and sums, each lane's in `times`'s order, done two wide.
    #[inline]
    pub fn times_paired(&self, m: &Paired) -> Paired {
        let [w0, w1, w2, v0, v1, v2] = *m;
        let (w, v) = ([w0, w1, w2], [v0, v1, v2]);
        let turned = matrix_times_paired(&self.rotational, &w);
        let (first_v, first_w) = (cross_paired(&self.first, &v), cross_paired(&self.first, &w));
        let mass = f64x2::splat(self.mass);
        [
            turned[0] + first_v[0],
            turned[1] + first_v[1],
            turned[2] + first_v[2],
            v0 * mass - first_w[0],
            v1 * mass - first_w[1],
            v2 * mass - first_w[2],
        ]
    }

    /// The momentum of motion m: [J ω + h × v; m v − h × ω], in the scalar of m (the body's
    /// numbers are constants of the model): 24 products where the 6 × 6 matrix takes 36.
    #[inline]
    pub fn times<T: Real>(&self, m: &Motion<T>) -> Force<T> {
        let (w, v) = (angular(m), linear(m));
        let first: Vector3<T> = self.first.cast();
        twist(
            self.rotational.cast::<T>() * w + first.cross(&v),
            v * constant::<T>(self.mass) - first.cross(&w),
        )
    }
}

impl std::ops::AddAssign for RigidInertia {
    fn add_assign(&mut self, other: RigidInertia) {
        self.mass += other.mass;
        self.first += other.first;
        self.rotational += other.rotational;
    }
}

/// Spatial inertia about a frame's origin, of a body with mass `mass`, centre of mass `com` and
/// rotational inertia `central` about the centre of mass (both in that frame).
pub fn inertia(mass: f64, com: &Vector3<f64>, central: &Matrix3<f64>) -> Inertia {
    let c = skew(com);
    let mut i = Matrix6::zeros();
    i.fixed_view_mut::<3, 3>(0, 0)
        .copy_from(&(central - mass * c * c));
    i.fixed_view_mut::<3, 3>(0, 3).copy_from(&(mass * c));
    i.fixed_view_mut::<3, 3>(3, 0).copy_from(&(-mass * c));
    i.fixed_view_mut::<3, 3>(3, 3)
        .copy_from(&(Matrix3::identity() * mass));
    i
}

/// Inertia given in the child frame, expressed in the parent frame: X* I X⁻¹.
pub fn inertia_to_parent(pose: &Pose, i: &Inertia) -> Inertia {
    let x = motion_matrix_to_child(pose);
    x.transpose() * i * x
}

/// Two spatial vectors side by side, the first in lane 0 and the second in lane 1 of each
/// entry, for products of one operator with both at once (`RigidInertia::times_paired`).
pub type Paired = [f64x2; 6];

/// m x for a pair of 3-vectors x (lane by lane), each row's sum in nalgebra's order, (m₀ x₀ +
/// m₁ x₁) + m₂ x₂, as `m * x` forms it.
#[inline]
pub fn matrix_times_paired(m: &Matrix3<f64>, x: &[f64x2; 3]) -> [f64x2; 3] {
    let splat = f64x2::splat;
    std::array::from_fn(|i| {
        splat(m[(i, 0)]) * x[0] + splat(m[(i, 1)]) * x[1] + splat(m[(i, 2)]) * x[2]
    })
}

/// c × x for a pair of 3-vectors x (lane by lane), in `Vector3::cross`'s products.
#[inline]
pub fn cross_paired(c: &Vector3<f64>, x: &[f64x2; 3]) -> [f64x2; 3] {
    let (c0, c1, c2) = (f64x2::splat(c.x), f64x2::splat(c.y), f64x2::splat(c.z));
    [
        c1 * x[2] - c2 * x[1],
        c2 * x[0] - c0 * x[2],
        c0 * x[1] - c1 * x[0],
    ]
}

/// `a` and `b` side by side.
#[inline]
pub fn paired(a: &Twist, b: &Twist) -> Paired {
    std::array::from_fn(|k| f64x2::new([a[k], b[k]]))
}

/// The two vectors of a pair.
#[inline]
pub fn unpaired(pair: &Paired) -> [Twist; 2] {
    let lanes: [[f64; 2]; 6] = std::array::from_fn(|k| pair[k].to_array());
    [
        Twist::from_fn(|k, _| lanes[k][0]),
        Twist::from_fn(|k, _| lanes[k][1]),
    ]
}

/// The spatial vector with angular (upper) part `angular` and linear (lower) part `linear`.
pub fn twist<T: Real>(angular: Vector3<T>, linear: Vector3<T>) -> Twist<T> {
    Twist::new(
        angular.x, angular.y, angular.z, linear.x, linear.y, linear.z,
    )
}

/// The upper half of a spatial vector: a motion's angular velocity, a force's moment.
pub fn angular<T: Real>(t: &Twist<T>) -> Vector3<T> {
    Vector3::new(t[0], t[1], t[2])
}

/// The lower half of a spatial vector: a motion's linear velocity, a force's force.
pub fn linear<T: Real>(t: &Twist<T>) -> Vector3<T> {
    Vector3::new(t[3], t[4], t[5])
}

/// Velocity of the point `p` of a body moving with (spatial) twist `t`.
pub fn point_velocity<T: Real>(t: &Twist<T>, p: &Vector3<T>) -> Vector3<T> {
    linear(t) + angular(t).cross(p)
}

pub fn translation<T: Real>(v: Vector3<T>) -> Pose<T> {
    Isometry3::from_parts(Translation3::from(v), UnitQuaternion::identity())
}

/// Rotation by `angle` about the unit vector `axis`.
pub fn rotation<T: Real>(axis: &Vector3<T>, angle: T) -> Pose<T> {
    Isometry3::from_parts(
        Translation3::identity(),
        UnitQuaternion::from_scaled_axis(axis * angle),
    )
}

/// `rotation` by the half-angle formula, (cos ½θ, sin ½θ · n) for θ = |axis| · angle about
/// n = axis / |axis|: smooth at θ = 0, where nalgebra's exponential (`rotation`) returns the
/// identity for any |θ| up to 2ε, dropping the derivative part of a dual number there (a joint
/// at zero). The same rotation as `rotation`, not the same last bits.
pub fn smooth_rotation<T: Real>(axis: &Vector3<T>, angle: T) -> Pose<T> {
    let norm = axis.norm();
    let half = angle * norm * constant::<T>(0.5);
    let quaternion = Quaternion::from_parts(half.cos(), axis * (half.sin() / norm));
    Isometry3::from_parts(
        Translation3::identity(),
        UnitQuaternion::new_unchecked(quaternion),
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
