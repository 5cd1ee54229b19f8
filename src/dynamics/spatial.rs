//! Spatial algebra for the dynamics, in body coordinates (Featherstone's convention with the
//! angular part first): motions `[ω; v]`, forces `[n; f]` (moment about the frame's origin, then
//! force), spatial inertias as 6×6 matrices, and rigid transforms acting on them.

use nalgebra::{Isometry3, Matrix3, Matrix6, Vector3, Vector6};

/// A rigid transform with its rotation as a matrix: the form the recursive algorithms use,
/// where rotating a vector costs 9 products instead of the quaternion's 18.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Transform {
    pub rotation: Matrix3<f64>,
    pub translation: Vector3<f64>,
}

pub type Motion = Vector6<f64>;
pub type Force = Vector6<f64>;
pub type Inertia = Matrix6<f64>;
pub type Pose = Isometry3<f64>;

fn top(x: &Vector6<f64>) -> Vector3<f64> {
    Vector3::new(x[0], x[1], x[2])
}

fn bottom(x: &Vector6<f64>) -> Vector3<f64> {
    Vector3::new(x[3], x[4], x[5])
}

fn join(a: Vector3<f64>, b: Vector3<f64>) -> Vector6<f64> {
    Vector6::new(a.x, a.y, a.z, b.x, b.y, b.z)
}

pub fn skew(v: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -v.z, v.y, v.z, 0.0, -v.x, -v.y, v.x, 0.0)
}

/// Motion given in the frame of `pose` (a child), expressed in the frame `pose` is relative to.
pub fn motion_to_parent(pose: &Pose, m: &Motion) -> Motion {
    let w = pose.rotation * top(m);
    join(
        w,
        pose.rotation * bottom(m) + pose.translation.vector.cross(&w),
    )
}

/// Motion given in the parent frame, expressed in the frame of `pose` (the child).
pub fn motion_to_child(pose: &Pose, m: &Motion) -> Motion {
    let inverse = pose.rotation.inverse();
    let w = top(m);
    join(
        inverse * w,
        inverse * (bottom(m) - pose.translation.vector.cross(&w)),
    )
}

/// Force given in the child frame, expressed in the parent frame.
pub fn force_to_parent(pose: &Pose, f: &Force) -> Force {
    let force = pose.rotation * bottom(f);
    join(
        pose.rotation * top(f) + pose.translation.vector.cross(&force),
        force,
    )
}

/// Force given in the parent frame, expressed in the child frame.
pub fn force_to_child(pose: &Pose, f: &Force) -> Force {
    let inverse = pose.rotation.inverse();
    let force = bottom(f);
    join(
        inverse * (top(f) - pose.translation.vector.cross(&force)),
        inverse * force,
    )
}

/// `a × b` for two motions.
pub fn cross_motion(a: &Motion, b: &Motion) -> Motion {
    let (w, v) = (top(a), bottom(a));
    join(w.cross(&top(b)), w.cross(&bottom(b)) + v.cross(&top(b)))
}

/// `a ×* f`: a motion acting on a force.
pub fn cross_force(a: &Motion, f: &Force) -> Force {
    let (w, v) = (top(a), bottom(a));
    join(w.cross(&top(f)) + v.cross(&bottom(f)), w.cross(&bottom(f)))
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

impl Transform {
    pub fn identity() -> Transform {
        Transform {
            rotation: Matrix3::identity(),
            translation: Vector3::zeros(),
        }
    }

    pub fn inverse(&self) -> Transform {
        let rt = self.rotation.transpose();
        Transform {
            rotation: rt,
            translation: -(rt * self.translation),
        }
    }

    pub fn from_pose(pose: &Pose) -> Transform {
        Transform {
            rotation: *pose.rotation.to_rotation_matrix().matrix(),
            translation: pose.translation.vector,
        }
    }

    /// Motion given in the parent frame, expressed in this (child) frame.
    #[inline]
    pub fn motion_to_child(&self, m: &Motion) -> Motion {
        let w = top(m);
        let rt = self.rotation.transpose();
        join(rt * w, rt * (bottom(m) - self.translation.cross(&w)))
    }

    /// Force given in this (child) frame, expressed in the parent frame.
    #[inline]
    pub fn force_to_parent(&self, f: &Force) -> Force {
        let force = self.rotation * bottom(f);
        join(
            self.rotation * top(f) + self.translation.cross(&force),
            force,
        )
    }

    /// Motion given in this (child) frame, expressed in the parent frame.
    #[inline]
    pub fn motion_to_parent(&self, m: &Motion) -> Motion {
        let w = self.rotation * top(m);
        join(w, self.rotation * bottom(m) + self.translation.cross(&w))
    }

    /// Inertia given in this (child) frame, expressed in the parent frame, by 3 × 3 blocks:
    /// with I = [A B; Bᵀ D], rotating gives A₁ = RARᵀ, B₁ = RBRᵀ, D₁ = RDRᵀ, and moving the
    /// origin by p gives [A₁ − B₁p̂ + p̂B₁ᵀ − p̂D₁p̂, B₁ + p̂D₁; ·, D₁]. About half the products
    /// of X*ᵀ I X with 6 × 6 matrices.
    pub fn inertia_to_parent(&self, i: &Inertia) -> Inertia {
        let r = &self.rotation;
        let rotate = |block: Matrix3<f64>| r * block * r.transpose();
        let a = rotate(i.fixed_view::<3, 3>(0, 0).into_owned());
        let b = rotate(i.fixed_view::<3, 3>(0, 3).into_owned());
        let d = rotate(i.fixed_view::<3, 3>(3, 3).into_owned());
        let p = skew(&self.translation);
        let pd = p * d;
        let b_p = b * p;
        let top_left = a - b_p - b_p.transpose() - pd * p;
        let top_right = b + pd;
        let mut out = Matrix6::zeros();
        out.fixed_view_mut::<3, 3>(0, 0).copy_from(&top_left);
        out.fixed_view_mut::<3, 3>(0, 3).copy_from(&top_right);
        out.fixed_view_mut::<3, 3>(3, 0)
            .copy_from(&top_right.transpose());
        out.fixed_view_mut::<3, 3>(3, 3).copy_from(&d);
        out
    }
}

impl std::ops::Mul for Transform {
    type Output = Transform;

    /// Composition: `a * b` maps b's frame through a's.
    fn mul(self, b: Transform) -> Transform {
        Transform {
            rotation: self.rotation * b.rotation,
            translation: self.rotation * b.translation + self.translation,
        }
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
        let rj = r * self.rotational;
        let diagonal = 2.0 * h1.dot(&p) + m * p.norm_squared();
        // (R J) Rᵀ is symmetric: compute the upper triangle only.
        let mut rotational = Matrix3::zeros();
        for i in 0..3 {
            for j in i..3 {
                let rotated = rj.row(i).dot(&r.row(j));
                let value = rotated - p[i] * h1[j] - h1[i] * p[j] - m * p[i] * p[j]
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

    /// The momentum of motion m: [J ω + h × v; m v − h × ω].
    #[inline]
    pub fn times(&self, m: &Motion) -> Force {
        let (w, v) = (top(m), bottom(m));
        join(
            self.rotational * w + self.first.cross(&v),
            self.mass * v - self.first.cross(&w),
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
