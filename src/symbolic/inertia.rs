//! Bodies' mass properties: each body's in its own frame, merged into the body it is welded to,
//! then in the fixed axes at the body's origin (the thesis's 𝔐ᵢ and 𝔖ᵢ).
//!
//! A body welded to its parent has no coordinate of its own: it moves with the nearest ancestor
//! that has one, its anchor. Its mass properties are moved into the anchor's frame while they are
//! still constants of the program (so numbers fold), and the recursions skip it: welds cost
//! nothing, as in the numeric model (`dynamics::welds`).

use super::articulated::Matrix6;
use super::expr::{ExprId, Pool};
use super::kinematics::Moving;
use super::vector::{self as v, Mat3, Vec3, Wrench};

/// Mass properties about a frame's origin, in that frame's axes (or the fixed axes).
#[derive(Clone, Copy)]
pub(super) struct Inertia {
    pub mass: ExprId,
    /// h = μ OG.
    pub first_moment: Vec3,
    /// I(O) = I(G) + μ (|OG|² Id − OG OGᵀ).
    pub at_origin: Mat3,
}

impl Inertia {
    /// The same mass seen from a frame in which this one has `rotation` and `origin` p:
    /// h' = μ p + R h, I'(O') = R I(O) Rᵀ + μ (|p|² Id − p pᵀ) + 2 (p·h') Id − p h'ᵀ − h' pᵀ
    /// with h' = R h.
    pub(super) fn moved(&self, pool: &mut Pool, rotation: &Mat3, origin: &Vec3) -> Inertia {
        let turned = v::mat_vec(pool, rotation, &self.first_moment);
        let carried = v::scale(pool, self.mass, origin);
        let first_moment = v::add(pool, &carried, &turned);
        let half = v::mat_mul(pool, rotation, &self.at_origin);
        let rotated = v::mat_mul(pool, &half, &v::transpose(rotation));
        let squared = v::dot(pool, origin, origin);
        let lever = v::dot(pool, origin, &turned);
        let mut at_origin = rotated;
        for r in 0..3 {
            for c in 0..3 {
                let outer = pool.mul(origin[r], origin[c]);
                let point = if r == c {
                    pool.sub(squared, outer)
                } else {
                    pool.neg(outer)
                };
                let point = pool.mul(self.mass, point);
                let cross_terms = {
                    let (a, b) = (
                        pool.mul(origin[r], turned[c]),
                        pool.mul(turned[r], origin[c]),
                    );
                    let both = pool.add(a, b);
                    if r == c {
                        let two = pool.constant(2.0);
                        let twice = pool.mul(two, lever);
                        pool.sub(twice, both)
                    } else {
                        pool.neg(both)
                    }
                };
                let shift = pool.add(point, cross_terms);
                at_origin[r][c] = pool.add(rotated[r][c], shift);
            }
        }
        Inertia {
            mass: self.mass,
            first_moment,
            at_origin,
        }
    }

    pub(super) fn plus(&self, pool: &mut Pool, other: &Inertia) -> Inertia {
        let mut at_origin = self.at_origin;
        for (row, other_row) in at_origin.iter_mut().zip(&other.at_origin) {
            for (entry, o) in row.iter_mut().zip(other_row) {
                *entry = pool.add(*entry, *o);
            }
        }
        Inertia {
            mass: pool.add(self.mass, other.mass),
            first_moment: v::add(pool, &self.first_moment, &other.first_moment),
            at_origin,
        }
    }

    /// 𝔐 (v, ω): the momentum μ v + ω∧h and the angular momentum at O, h∧v + I(O) ω.
    pub fn times(&self, pool: &mut Pool, angular: &Vec3, linear: &Vec3) -> Wrench {
        let translating = v::scale(pool, self.mass, linear);
        let spin = v::cross(pool, angular, &self.first_moment);
        let lever = v::cross(pool, &self.first_moment, linear);
        let turning = v::mat_vec(pool, &self.at_origin, angular);
        [
            v::add(pool, &translating, &spin),
            v::add(pool, &lever, &turning),
        ]
    }

    /// 𝔖 = (−ω∧(ω∧h), −ω∧I(O)ω) for a body moving as `body`.
    pub fn velocity_products(&self, pool: &mut Pool, body: &Moving) -> Wrench {
        let w = body.angular_velocity;
        let spin = v::cross(pool, &w, &self.first_moment);
        let centripetal = v::cross(pool, &w, &spin);
        let turning = v::mat_vec(pool, &self.at_origin, &w);
        let gyroscopic = v::cross(pool, &w, &turning);
        [v::neg(pool, &centripetal), v::neg(pool, &gyroscopic)]
    }

    /// 𝔖 − 𝔐 Ψ̇q.
    pub fn velocity_terms(&self, pool: &mut Pool, body: &Moving) -> Wrench {
        let [force, moment] = self.velocity_products(pool, body);
        let [bias_force, bias_moment] = self.times(pool, &body.angular_bias, &body.bias);
        [
            v::sub(pool, &force, &bias_force),
            v::sub(pool, &moment, &bias_moment),
        ]
    }

    /// 𝔐 as a 6 × 6 matrix on (v, ω): [[μ Id, −h̃], [h̃, I(O)]].
    pub fn matrix(&self, pool: &mut Pool) -> Matrix6 {
        let zero = pool.constant(0.0);
        let mut m = [[zero; 6]; 6];
        let h = self.first_moment;
        let minus = v::neg(pool, &h);
        let skew = [
            [zero, minus[2], h[1]],
            [h[2], zero, minus[0]],
            [minus[1], h[0], zero],
        ];
        for i in 0..3 {
            m[i][i] = self.mass;
            for j in 0..3 {
                m[3 + i][j] = skew[i][j];
                m[j][3 + i] = skew[i][j];
                m[3 + i][3 + j] = self.at_origin[i][j];
            }
        }
        m
    }
}

/// One entry per body number (0 = earth).
pub(super) type PerBody = Vec<Option<Inertia>>;
