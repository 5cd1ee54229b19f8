//! Kane's equations (Kane and Levinson 1985, *Dynamics: Theory and Applications*, ch. 6;
//! Llibre 2009, §2.3): for each generalised speed r,
//!
//! ```text
//! F_r + F*_r = 0,   F_r = Σᵢ fᵢ·vᵢ,ᵣ + mᵢ·ωᵢ,ᵣ,   F*_r = −Σᵢ (inertia force)·vᵢ,ᵣ + (inertia torque)·ωᵢ,ᵣ
//! ```
//!
//! with vᵢ,ᵣ and ωᵢ,ᵣ the partial velocity of body i's origin and its partial angular velocity.
//! Nothing here reads the velocities the composition of velocities built (`kinematics`): each
//! body's velocity is the time derivative of its origin's position, v = Σₖ ∂r/∂pₖ qₖ, its angular
//! velocity in its own axes the axial vector of Rᵀ Ṙ with Ṙ = Σₖ ∂R/∂pₖ qₖ; the partial velocities
//! are their derivatives with respect to the rates (Kane's definition), and the accelerations at
//! zero q' their derivatives in time along the positions. The inertia forces are written at the
//! body's origin in its own axes, where its mass properties are the program's constants:
//! with h = μ OG and I = I(O),
//!
//! ```text
//! force  = μ a + α ∧ h + ω ∧ (ω ∧ h),   torque = h ∧ a + I α + ω ∧ (I ω).
//! ```
//!
//! M[r, s] is the coefficient of q'_s in −F*_r, S[r] the rest of F*_r, F[r] = F_r.

use super::expr::ExprId;
use super::generator::Generator;
use super::inertia::Inertia;
use super::newton_euler::MassSecondMemberForces;
use super::vector::{self as v, Mat3, Vec3, Wrench};

/// A body's motion as Kane's method reads it, in the body's own axes.
struct BodyRates {
    /// Rᵀ, to bring fixed-axes vectors into the body's axes.
    to_body: Mat3,
    /// ω.
    angular_velocity: Vec3,
    /// Per tree coordinate, the partial angular velocity and the origin's partial velocity
    /// (`None` when both are zero).
    partials: Vec<Option<[Vec3; 2]>>,
    /// α and the origin's acceleration when q' = 0.
    angular_bias: Vec3,
    bias: Vec3,
}

impl Generator<'_> {
    /// M, S and the applied efforts' part of F (the links' efforts are added by the caller) by
    /// Kane's equations, for the `tree` first coordinates.
    pub(super) fn kane(
        &mut self,
        tree: usize,
        applied: &[Option<Wrench>],
    ) -> MassSecondMemberForces {
        let n = self.columns();
        let zero = self.pool.constant(0.0);
        let (mut mass, mut second_member, mut forces) =
            (vec![zero; n * n], vec![zero; n], vec![zero; n]);
        for (b, wrench) in applied.iter().enumerate().skip(1) {
            let inertia = self.local_inertias[b];
            if inertia.is_none() && wrench.is_none() {
                continue;
            }
            let rates = self.body_rates(b, tree);
            if let Some(inertia) = inertia {
                self.add_inertia_forces(&inertia, &rates, &mut mass, &mut second_member);
            }
            if let Some([force, moment]) = *wrench {
                let pool = &mut self.pool;
                let force = v::mat_vec(pool, &rates.to_body, &force);
                let moment = v::mat_vec(pool, &rates.to_body, &moment);
                for (r, partial) in rates.partials.iter().enumerate() {
                    let Some([angular, linear]) = partial else {
                        continue;
                    };
                    let along = v::dot(pool, &force, linear);
                    let about = v::dot(pool, &moment, angular);
                    let power = pool.add(along, about);
                    forces[r] = pool.add(forces[r], power);
                }
            }
        }
        (mass, second_member, forces)
    }

    /// Adds body's generalised inertia forces: its M entries (on and above the diagonal, then
    /// mirrored) and its part of S.
    fn add_inertia_forces(
        &mut self,
        inertia: &Inertia,
        rates: &BodyRates,
        mass: &mut [ExprId],
        second_member: &mut [ExprId],
    ) {
        let n = second_member.len();
        let pool = &mut self.pool;
        let w = rates.angular_velocity;
        let [force, torque] = inertia.times(pool, &rates.angular_bias, &rates.bias);
        let spin = v::cross(pool, &w, &inertia.first_moment);
        let centripetal = v::cross(pool, &w, &spin);
        let turning = v::mat_vec(pool, &inertia.at_origin, &w);
        let gyroscopic = v::cross(pool, &w, &turning);
        let force = v::add(pool, &force, &centripetal);
        let torque = v::add(pool, &torque, &gyroscopic);
        for (r, partial) in rates.partials.iter().enumerate() {
            let Some([angular, linear]) = partial else {
                continue;
            };
            let along = v::dot(pool, &force, linear);
            let about = v::dot(pool, &torque, angular);
            let power = pool.add(along, about);
            second_member[r] = pool.sub(second_member[r], power);
        }
        for (s, column) in rates.partials.iter().enumerate() {
            let Some([angular_s, linear_s]) = column else {
                continue;
            };
            let [momentum, moment] = inertia.times(pool, angular_s, linear_s);
            for (r, row) in rates.partials.iter().enumerate().take(s + 1) {
                let Some([angular_r, linear_r]) = row else {
                    continue;
                };
                let along = v::dot(pool, &momentum, linear_r);
                let about = v::dot(pool, &moment, angular_r);
                let entry = pool.add(along, about);
                let sum = pool.add(mass[r * n + s], entry);
                mass[r * n + s] = sum;
                mass[s * n + r] = sum;
            }
        }
    }

    /// Body b's velocities from its position and orientation alone, by differentiation.
    fn body_rates(&mut self, b: usize, tree: usize) -> BodyRates {
        let variables = &self.lowering.variables;
        let positions: Vec<ExprId> = variables.positions[..tree]
            .iter()
            .map(|p| p.symbol)
            .collect();
        let rates: Vec<ExprId> = variables.rates[..tree].iter().map(|p| p.symbol).collect();
        let (rotation, origin) = (self.bodies[b].rotation, self.bodies[b].origin);
        let to_body = v::transpose(&rotation);
        // d/dt along the positions: Σₖ ∂e/∂pₖ qₖ.
        let in_time = |generator: &mut Generator, e: ExprId| {
            let terms: Vec<ExprId> = positions
                .iter()
                .zip(&rates)
                .map(|(&p, &q)| {
                    let d = generator.derivatives.of(&mut generator.pool, e, p);
                    generator.pool.mul(d, q)
                })
                .collect();
            generator.pool.sum(terms)
        };
        let velocity = origin.map(|x| in_time(self, x));
        let turning = rotation.map(|row| row.map(|x| in_time(self, x)));
        let pool = &mut self.pool;
        let body_velocity = v::mat_vec(pool, &to_body, &velocity);
        // Rᵀ Ṙ = ω̃ in the body's axes.
        let spin = v::mat_mul(pool, &to_body, &turning);
        let angular_velocity = [spin[2][1], spin[0][2], spin[1][0]];
        let partials = rates
            .iter()
            .map(|&q| {
                let angular = angular_velocity.map(|x| self.derivatives.of(&mut self.pool, x, q));
                let linear = body_velocity.map(|x| self.derivatives.of(&mut self.pool, x, q));
                let zero = v::is_zero(&self.pool, &angular) && v::is_zero(&self.pool, &linear);
                (!zero).then_some([angular, linear])
            })
            .collect();
        let angular_bias = angular_velocity.map(|x| in_time(self, x));
        // The origin's acceleration in the fixed axes, then in the body's.
        let acceleration = velocity.map(|x| in_time(self, x));
        let bias = v::mat_vec(&mut self.pool, &to_body, &acceleration);
        BodyRates {
            to_body,
            angular_velocity,
            partials,
            angular_bias,
            bias,
        }
    }
}
