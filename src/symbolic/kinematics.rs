//! Frames moving with the mechanism, as expressions in the fixed axes (the thesis's R0): the
//! rotation and origin of a frame, its angular velocity and the velocity of its origin (the
//! thesis's kinematic vector 𝐪ᵢ = Ψᵢ q), the columns of Ψᵢ (one per coordinate rate), and the
//! accelerations when every coordinate has zero second derivative (Ψ̇ᵢ q).
//!
//! A frame is carried along a chain of steps: each translation or rotation may depend on the
//! coordinates of one link. Starting from a body's frame and walking the join frame, the link's
//! dof chain and the child's join frame back gives the child body's frame: the product form
//! Ψ = Ψₙ⋯Ψ₁ of the thesis (§3.3.2, step 6), parent first thanks to the breadth-first numbering.

use std::collections::HashMap;

use super::expr::{ExprId, Pool};
use super::quaternion_joints;
use super::vector::{self as v, Mat3, Vec3};

/// One step of a chain, as expressions.
#[derive(Clone, Debug)]
pub enum Step {
    /// A translation by a vector of the current frame.
    Translation(Vec3),
    /// A rotation by `angle` about a unit axis of the current frame.
    Rotation { axis: Vec3, angle: ExprId },
    /// A spherical or free joint in the simulator's state (`quaternion_joints`): a translation
    /// by `translation` (a free joint), then the rotation of `quaternion`; its link's rates
    /// are the body twist of that motion, in the axes after it.
    Ball {
        translation: Option<Vec3>,
        quaternion: [ExprId; 4],
    },
}

impl Step {
    /// The inverse step (a chain is inverted by inverting its steps in reverse order). A ball's
    /// step has none here (its body twist would be another's): it is returned as it is, and
    /// nothing inverts it, its quaternion being the motion of the child already whichever side
    /// the join's first frame is on (`Generator::place_bodies`).
    pub fn inverse(&self, pool: &mut Pool) -> Step {
        match self {
            Step::Ball { .. } => self.clone(),
            Step::Translation(t) => Step::Translation(v::neg(pool, t)),
            Step::Rotation { axis, angle } => Step::Rotation {
                axis: *axis,
                angle: pool.neg(*angle),
            },
        }
    }
}

/// The coordinates a step may depend on: those of one link, with the columns of its rates in
/// Ψ. A link in its declared coordinates has one rate per position, each position's time
/// derivative; a ball in the simulator's state has its body twist as rates, and its
/// positions' time derivatives are functions of both (`position_rates`).
#[derive(Clone, Debug, Default)]
pub struct LinkCoordinates {
    pub positions: Vec<ExprId>,
    pub rates: Vec<ExprId>,
    pub columns: Vec<usize>,
    /// Each position's time derivative.
    pub position_rates: Vec<ExprId>,
}

/// Partial derivatives, remembered per variable so that shared subexpressions are
/// differentiated once.
#[derive(Default)]
pub struct Derivatives {
    memo: HashMap<ExprId, HashMap<ExprId, ExprId>>,
}

impl Derivatives {
    pub fn of(&mut self, pool: &mut Pool, e: ExprId, x: ExprId) -> ExprId {
        let memo = self.memo.entry(x).or_default();
        pool.derivative(e, x, memo)
    }

    /// ∂e/∂pₖ for each coordinate, ė = Σ ∂e/∂pₖ ṗₖ, and ë at zero derivatives of the rates,
    /// Σₗ ∂ė/∂pₗ ṗₗ (ṗ the positions' rates: the link's rates for declared coordinates).
    fn rates(
        &mut self,
        pool: &mut Pool,
        e: ExprId,
        link: &LinkCoordinates,
    ) -> (Vec<ExprId>, ExprId, ExprId) {
        let partials: Vec<ExprId> = link
            .positions
            .iter()
            .map(|&p| self.of(pool, e, p))
            .collect();
        let terms: Vec<ExprId> = partials
            .iter()
            .zip(&link.position_rates)
            .map(|(&d, &q)| pool.mul(d, q))
            .collect();
        let rate = pool.sum(terms);
        let bias_terms: Vec<ExprId> = link
            .positions
            .iter()
            .zip(&link.position_rates)
            .map(|(&p, &q)| {
                let d = self.of(pool, rate, p);
                pool.mul(d, q)
            })
            .collect();
        let bias = pool.sum(bias_terms);
        (partials, rate, bias)
    }
}

/// A frame moving with the mechanism, in the fixed axes.
#[derive(Clone, Debug)]
pub struct Moving {
    pub rotation: Mat3,
    pub origin: Vec3,
    pub angular_velocity: Vec3,
    /// Velocity of the origin.
    pub velocity: Vec3,
    /// Angular acceleration and acceleration of the origin when the coordinates have zero
    /// second derivatives.
    pub angular_bias: Vec3,
    pub bias: Vec3,
    /// Per coordinate rate: ∂ω/∂qₖ and ∂v/∂qₖ (`None` when both are zero).
    pub columns: Vec<Option<[Vec3; 2]>>,
}

impl Moving {
    /// The fixed frame (`earth`), with `columns` coordinate rates in the mechanism.
    pub fn fixed(pool: &mut Pool, columns: usize) -> Moving {
        let zero = v::zero(pool);
        Moving {
            rotation: v::identity(pool),
            origin: zero,
            angular_velocity: zero,
            velocity: zero,
            angular_bias: zero,
            bias: zero,
            columns: vec![None; columns],
        }
    }

    /// Carries the frame along `step`, whose parameters depend on `link`'s coordinates.
    pub fn walk(
        &mut self,
        pool: &mut Pool,
        d: &mut Derivatives,
        step: &Step,
        link: &LinkCoordinates,
    ) {
        match step {
            Step::Translation(t) => self.translate(pool, d, t, link),
            Step::Rotation { axis, angle } => self.rotate(pool, d, axis, *angle, link),
            Step::Ball {
                translation,
                quaternion,
            } => self.ball(pool, translation.as_ref(), quaternion, link),
        }
    }

    /// Carries the frame along a ball's motion Trans(p)·Rot(Q) (p for a free joint only), whose
    /// rates are its body twist (ω_b, v_b) in the axes after it, R₁ = R R(Q): the origin moves
    /// by d = R p at ṗ = R(Q) v_b, so ḋ = ω × d + u with u = R₁ v_b, and ω gains R₁ ω_b. At zero
    /// derivatives of the rates, d̈ = α × d + ω × (ω × d) + 2 ω × u + (R₁ ω_b) × u and α gains
    /// ω × R₁ ω_b (R₁'s columns turn with the frame after the step).
    fn ball(
        &mut self,
        pool: &mut Pool,
        translation: Option<&Vec3>,
        quaternion: &[ExprId; 4],
        link: &LinkCoordinates,
    ) {
        let turn = quaternion_joints::rotation(pool, quaternion);
        let after = v::mat_mul(pool, &self.rotation, &turn);
        let (w, alpha) = (self.angular_velocity, self.angular_bias);
        let angular_rates = [link.rates[0], link.rates[1], link.rates[2]];
        let relative = v::mat_vec(pool, &after, &angular_rates);
        if let Some(p) = translation {
            let offset = v::mat_vec(pool, &self.rotation, p);
            let linear_rates = [link.rates[3], link.rates[4], link.rates[5]];
            let moved_rate = v::mat_vec(pool, &after, &linear_rates);
            let spin = v::cross(pool, &w, &offset);
            let tangential = v::cross(pool, &alpha, &offset);
            let centripetal = v::cross(pool, &w, &spin);
            let coriolis = v::cross(pool, &w, &moved_rate);
            let two = pool.constant(2.0);
            let coriolis = v::scale(pool, two, &coriolis);
            let turning = v::cross(pool, &relative, &moved_rate);
            for term in [tangential, centripetal, coriolis, turning] {
                self.bias = v::add(pool, &self.bias, &term);
            }
            for term in [spin, moved_rate] {
                self.velocity = v::add(pool, &self.velocity, &term);
            }
            for column in self.columns.iter_mut().flatten() {
                let lever = v::cross(pool, &column[0], &offset);
                column[1] = v::add(pool, &column[1], &lever);
            }
            for (k, &c) in link.columns[3..6].iter().enumerate() {
                let axis = [after[0][k], after[1][k], after[2][k]];
                let zero = v::zero(pool);
                let column = self.columns[c].get_or_insert([zero, zero]);
                column[1] = v::add(pool, &column[1], &axis);
            }
            self.origin = v::add(pool, &self.origin, &offset);
        }
        let transport = v::cross(pool, &w, &relative);
        self.angular_bias = v::add(pool, &alpha, &transport);
        self.angular_velocity = v::add(pool, &w, &relative);
        for (k, &c) in link.columns[..3].iter().enumerate() {
            let axis = [after[0][k], after[1][k], after[2][k]];
            let zero = v::zero(pool);
            let column = self.columns[c].get_or_insert([zero, zero]);
            column[0] = v::add(pool, &column[0], &axis);
        }
        self.rotation = after;
    }

    fn translate(
        &mut self,
        pool: &mut Pool,
        d: &mut Derivatives,
        t: &Vec3,
        link: &LinkCoordinates,
    ) {
        let offset = v::mat_vec(pool, &self.rotation, t);
        if v::is_zero(pool, &offset) && link.positions.is_empty() {
            return;
        }
        // d = R t moves with the frame: ḋ = ω × d + R ṫ, d̈ = α × d + ω × (ω × d) + 2 ω × R ṫ + R ẗ.
        let (w, alpha) = (self.angular_velocity, self.angular_bias);
        let spin = v::cross(pool, &w, &offset);
        let (mut own_rate, mut own_bias) = (v::zero(pool), v::zero(pool));
        let mut partials = vec![v::zero(pool); link.positions.len()];
        for i in 0..3 {
            let (p, rate, bias) = d.rates(pool, t[i], link);
            own_rate[i] = rate;
            own_bias[i] = bias;
            for (k, &pk) in p.iter().enumerate() {
                partials[k][i] = pk;
            }
        }
        let moved_rate = v::mat_vec(pool, &self.rotation, &own_rate);
        let moved_bias = v::mat_vec(pool, &self.rotation, &own_bias);
        let tangential = v::cross(pool, &alpha, &offset);
        let centripetal = v::cross(pool, &w, &spin);
        let coriolis = v::cross(pool, &w, &moved_rate);
        let two = pool.constant(2.0);
        let coriolis = v::scale(pool, two, &coriolis);
        for term in [tangential, centripetal, coriolis, moved_bias] {
            self.bias = v::add(pool, &self.bias, &term);
        }
        for term in [spin, moved_rate] {
            self.velocity = v::add(pool, &self.velocity, &term);
        }
        for column in self.columns.iter_mut().flatten() {
            let lever = v::cross(pool, &column[0], &offset);
            column[1] = v::add(pool, &column[1], &lever);
        }
        for (k, partial) in partials.iter().enumerate() {
            let moved = v::mat_vec(pool, &self.rotation, partial);
            let zero = v::zero(pool);
            let column = self.columns[link.columns[k]].get_or_insert([zero, zero]);
            column[1] = v::add(pool, &column[1], &moved);
        }
        self.origin = v::add(pool, &self.origin, &offset);
    }

    fn rotate(
        &mut self,
        pool: &mut Pool,
        d: &mut Derivatives,
        axis: &Vec3,
        angle: ExprId,
        link: &LinkCoordinates,
    ) {
        if !link.positions.is_empty() {
            // The axis w = R u turns with the frame: d/dt (w θ̇) = ω × w θ̇ + w θ̈.
            let w = v::mat_vec(pool, &self.rotation, axis);
            let (partials, rate, bias) = d.rates(pool, angle, link);
            let relative = v::scale(pool, rate, &w);
            let transport = v::cross(pool, &self.angular_velocity, &relative);
            let own = v::scale(pool, bias, &w);
            let alpha = v::add(pool, &self.angular_bias, &transport);
            self.angular_bias = v::add(pool, &alpha, &own);
            self.angular_velocity = v::add(pool, &self.angular_velocity, &relative);
            for (k, &partial) in partials.iter().enumerate() {
                let turned = v::scale(pool, partial, &w);
                let zero = v::zero(pool);
                let column = self.columns[link.columns[k]].get_or_insert([zero, zero]);
                column[0] = v::add(pool, &column[0], &turned);
            }
        }
        if !pool.is_zero(angle) {
            let turn = v::rotation(pool, axis, angle);
            self.rotation = v::mat_mul(pool, &self.rotation, &turn);
        }
    }

    /// The velocity of this frame's origin and its angular velocity, `column`-wise: the twist a
    /// unit rate of coordinate k gives it (angular, linear).
    pub fn column(&self, k: usize) -> Option<&[Vec3; 2]> {
        self.columns[k].as_ref()
    }
}
