//! Planar vectors (Featherstone, *Rigid Body Dynamics Algorithms*, 2008, §2.16; spatial_v2's
//! `plnr`, `crmp`, `crfp`, `mcI` with three rows): in a frame whose z axis is the plane's
//! normal, a motion is `[ω; vx; vy]` (the rate of turn about the normal and the velocity of the
//! frame's origin in the plane), a force `[n; fx; fy]` (the moment about the normal through the
//! origin, and the force in the plane), a rigid inertia the mass, the first moment in the plane
//! and the moment of inertia about the normal through the origin. They are the three rows of
//! the spatial vectors (`spatial`) that a motion in the plane and a force in the plane leave
//! non-zero; the other three are zero for the motion, and are reactions for the forces.

use nalgebra::{Matrix3, Vector2, Vector3};

pub type PlanarMotion = Vector3<f64>;
pub type PlanarForce = Vector3<f64>;
/// An articulated inertia in the plane: a symmetric 3 × 3 matrix acting on planar motions.
pub type PlanarArticulated = Matrix3<f64>;

/// The cross product in the plane: the normal component of a × b.
#[inline]
pub fn cross2(a: &Vector2<f64>, b: &Vector2<f64>) -> f64 {
    a.x * b.y - a.y * b.x
}

/// ω n̂ × p for a rate ω about the normal: p turned a quarter turn, scaled.
#[inline]
fn turn(omega: f64, p: &Vector2<f64>) -> Vector2<f64> {
    Vector2::new(-omega * p.y, omega * p.x)
}

/// A frame's pose in another, both with their z axis along the normal: a turn by an angle
/// (kept as its cosine and sine) and a translation in the plane.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlanarTransform {
    pub cos: f64,
    pub sin: f64,
    pub translation: Vector2<f64>,
}

impl PlanarTransform {
    pub fn identity() -> PlanarTransform {
        PlanarTransform::new(0.0, Vector2::zeros())
    }

    pub fn new(angle: f64, translation: Vector2<f64>) -> PlanarTransform {
        let (sin, cos) = angle.sin_cos();
        PlanarTransform {
            cos,
            sin,
            translation,
        }
    }

    /// The turn applied to a vector of the child's axes: in the parent's axes.
    #[inline]
    pub fn rotate(&self, v: &Vector2<f64>) -> Vector2<f64> {
        Vector2::new(
            self.cos * v.x - self.sin * v.y,
            self.sin * v.x + self.cos * v.y,
        )
    }

    /// The inverse turn: a vector of the parent's axes in the child's.
    #[inline]
    pub fn rotate_back(&self, v: &Vector2<f64>) -> Vector2<f64> {
        Vector2::new(
            self.cos * v.x + self.sin * v.y,
            -self.sin * v.x + self.cos * v.y,
        )
    }

    /// The angle of the turn.
    pub fn angle(&self) -> f64 {
        self.sin.atan2(self.cos)
    }

    /// A point of the child frame in the parent frame.
    #[inline]
    pub fn point_to_parent(&self, p: &Vector2<f64>) -> Vector2<f64> {
        self.rotate(p) + self.translation
    }

    /// Motion given in the parent frame, expressed in this (child) frame:
    /// v' = Rᵀ(v − p × ω n̂) = Rᵀ(v + ω n̂ × p).
    #[inline]
    pub fn motion_to_child(&self, m: &PlanarMotion) -> PlanarMotion {
        let v = Vector2::new(m[1], m[2]) + turn(m[0], &self.translation);
        let v = self.rotate_back(&v);
        PlanarMotion::new(m[0], v.x, v.y)
    }

    /// Motion given in this (child) frame, expressed in the parent frame:
    /// v' = R v + p × ω n̂ = R v − ω n̂ × p.
    #[inline]
    pub fn motion_to_parent(&self, m: &PlanarMotion) -> PlanarMotion {
        let v = self.rotate(&Vector2::new(m[1], m[2])) - turn(m[0], &self.translation);
        PlanarMotion::new(m[0], v.x, v.y)
    }

    /// Force given in this (child) frame, expressed in the parent frame: f' = R f,
    /// n' = n + p × f'.
    #[inline]
    pub fn force_to_parent(&self, f: &PlanarForce) -> PlanarForce {
        let force = self.rotate(&Vector2::new(f[1], f[2]));
        PlanarForce::new(f[0] + cross2(&self.translation, &force), force.x, force.y)
    }

    /// The 3 × 3 matrix of `motion_to_child`.
    fn motion_matrix_to_child(&self) -> Matrix3<f64> {
        let (c, s) = (self.cos, self.sin);
        let (px, py) = (self.translation.x, self.translation.y);
        // v + ω n̂ × p = (vx − ω py, vy + ω px), then turned back.
        Matrix3::new(1.0, 0.0, 0.0, s * px - c * py, c, s, s * py + c * px, -s, c)
    }

    /// An articulated inertia given in this (child) frame, in the parent frame: Xᵀ I X with X
    /// the motion transform to the child.
    pub fn inertia_to_parent(&self, i: &PlanarArticulated) -> PlanarArticulated {
        let x = self.motion_matrix_to_child();
        x.transpose() * i * x
    }
}

impl std::ops::Mul for PlanarTransform {
    type Output = PlanarTransform;

    /// Composition: `a * b` maps b's frame through a's.
    fn mul(self, b: PlanarTransform) -> PlanarTransform {
        PlanarTransform {
            cos: self.cos * b.cos - self.sin * b.sin,
            sin: self.sin * b.cos + self.cos * b.sin,
            translation: self.rotate(&b.translation) + self.translation,
        }
    }
}

/// `a × b` for two planar motions (the rows of the spatial `cross_motion` in the plane).
#[inline]
pub fn cross_motion(a: &PlanarMotion, b: &PlanarMotion) -> PlanarMotion {
    // ω_a n̂ × v_b + v_a × ω_b n̂; the angular part (n̂ × n̂) vanishes.
    let (wa, wb) = (a[0], b[0]);
    PlanarMotion::new(0.0, -wa * b[2] + wb * a[2], wa * b[1] - wb * a[1])
}

/// `a ×* f`: a planar motion acting on a planar force.
#[inline]
pub fn cross_force(a: &PlanarMotion, f: &PlanarForce) -> PlanarForce {
    // [ω × n + v × f; ω × f]: only v × f has a normal moment.
    let w = a[0];
    PlanarForce::new(a[1] * f[2] - a[2] * f[1], -w * f[2], w * f[1])
}

/// A rigid body's inertia about a frame's origin in the plane: mass m, first moment h = m c
/// in the plane and moment of inertia j about the normal through the origin.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlanarInertia {
    pub mass: f64,
    pub first: Vector2<f64>,
    pub rotational: f64,
}

impl PlanarInertia {
    pub fn zeros() -> PlanarInertia {
        PlanarInertia {
            mass: 0.0,
            first: Vector2::zeros(),
            rotational: 0.0,
        }
    }

    /// The momentum of motion m: [j ω + h × v; m v − h × ω n̂].
    #[inline]
    pub fn times(&self, m: &PlanarMotion) -> PlanarForce {
        let (w, v) = (m[0], Vector2::new(m[1], m[2]));
        // −h × ω n̂ = ω n̂ × h.
        let linear = self.mass * v + turn(w, &self.first);
        PlanarForce::new(
            self.rotational * w + cross2(&self.first, &v),
            linear.x,
            linear.y,
        )
    }

    /// The inertia in the parent frame of `t`: h' = R h + m p, j' = j + 2 (R h)·p + m |p|².
    pub fn to_parent(self, t: &PlanarTransform) -> PlanarInertia {
        let p = t.translation;
        let h1 = t.rotate(&self.first);
        PlanarInertia {
            mass: self.mass,
            first: h1 + self.mass * p,
            rotational: self.rotational + 2.0 * h1.dot(&p) + self.mass * p.norm_squared(),
        }
    }

    /// The 3 × 3 matrix [j, −h_y, h_x; −h_y, m, 0; h_x, 0, m].
    pub fn matrix(&self) -> PlanarArticulated {
        let (m, h) = (self.mass, self.first);
        Matrix3::new(self.rotational, -h.y, h.x, -h.y, m, 0.0, h.x, 0.0, m)
    }
}

impl std::ops::AddAssign for PlanarInertia {
    fn add_assign(&mut self, other: PlanarInertia) {
        self.mass += other.mass;
        self.first += other.first;
        self.rotational += other.rotational;
    }
}
