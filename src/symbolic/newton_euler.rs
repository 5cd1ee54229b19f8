//! The recursive Newton–Euler form (Luh, Walker and Paul 1980; Llibre 2009, ch. 3, §3.2):
//!
//! - forward, parent first: each body's angular velocity ω, angular acceleration α and its
//!   origin's acceleration a (the composition of velocities and accelerations, `kinematics`);
//! - each body's own Newton and Euler equations at its own centre of mass G, with its own
//!   declared mass and central inertia (a body welded to another keeps its own: nothing is
//!   merged, unlike the Lagrange form), moved to the body's origin O:
//!
//!   ```text
//!   f = μ (a + α ∧ OG + ω ∧ (ω ∧ OG)),   n(O) = I(G) α + ω ∧ I(G) ω + OG ∧ f;
//!   ```
//!
//! - backward, children first: the reaction a body receives from its parent is its own inertia
//!   wrench minus the efforts applied to it plus its children's reactions moved to its origin;
//!   its projection on the body's columns (the twist a unit rate gives) is the effort its joint
//!   must supply, τ(p, q, q').
//!
//! So τ = M q' − S − F: M[·, j] is τ for q' = e_j at rest without efforts (Walker and Orin 1982,
//! method 1; every entry of M is formed, not its upper triangle only), S is −τ for q' = 0 without
//! efforts, F the applied efforts carried down the same way.

use super::expr::ExprId;
use super::generator::Generator;
use super::lower::LowerError;
use super::vector::{self as v, Mat3, Vec3, Wrench};

/// M (row-major), S and the applied efforts' part of F.
pub(super) type MassSecondMemberForces = (Vec<ExprId>, Vec<ExprId>, Vec<ExprId>);

/// A body's mass properties at its centre of mass, in the fixed axes.
#[derive(Clone, Copy)]
struct Central {
    mass: ExprId,
    /// OG.
    centre: Vec3,
    /// I(G).
    inertia: Mat3,
}

impl Generator<'_> {
    /// M, S and the applied efforts' part of F by the recursive Newton–Euler algorithm, for the
    /// `tree` first coordinates.
    pub(super) fn newton_euler(
        &mut self,
        tree: usize,
        applied: &[Option<Wrench>],
    ) -> Result<MassSecondMemberForces, LowerError> {
        let count = self.topology.body_count();
        let mut centrals = vec![None];
        for b in 1..=count {
            centrals.push(self.central(b)?);
        }
        let n = self.columns();
        let zero = self.pool.constant(0.0);
        let mut mass = vec![zero; n * n];
        let still = v::zero(&mut self.pool);
        for j in 0..tree {
            let wrenches: Vec<Option<Wrench>> = (0..=count)
                .map(|b| {
                    let central = centrals[b]?;
                    let [alpha, a] = *self.bodies[b].column(j)?;
                    Some(self.inertia_wrench(&central, &still, &alpha, &a))
                })
                .collect();
            let tau = self.carried_down(wrenches);
            for (row, value) in tau.into_iter().enumerate().take(tree) {
                mass[row * n + j] = value;
            }
        }
        let wrenches: Vec<Option<Wrench>> = (0..=count)
            .map(|b| {
                let central = centrals[b]?;
                let body = &self.bodies[b];
                let (w, alpha, a) = (body.angular_velocity, body.angular_bias, body.bias);
                Some(self.inertia_wrench(&central, &w, &alpha, &a))
            })
            .collect();
        let tau = self.carried_down(wrenches);
        let second_member = tau.into_iter().map(|t| self.pool.neg(t)).collect();
        let forces = self.carried_down(applied.to_vec());
        Ok((mass, second_member, forces))
    }

    /// Body b's own mass and central inertia in the fixed axes (`None` when it has neither).
    fn central(&mut self, b: usize) -> Result<Option<Central>, LowerError> {
        let body = self.mechanism.body(self.topology.bodies[b - 1]);
        self.context = Some(body.span);
        let mass = (self.lowering).scalar(&mut self.pool, body.mass.value(), None)?;
        let moments = (self.lowering).vector(&mut self.pool, body.inertia.value(), None)?;
        if self.pool.is_zero(mass) && v::is_zero(&self.pool, &moments) {
            return Ok(None);
        }
        let (principal, centre) = self.pose(body.iframe.value())?;
        let pool = &mut self.pool;
        let rotation = self.bodies[b].rotation;
        let axes = v::mat_mul(pool, &rotation, &principal);
        let zero = pool.constant(0.0);
        let mut diagonal = [[zero; 3]; 3];
        for k in 0..3 {
            diagonal[k][k] = moments[k];
        }
        let half = v::mat_mul(pool, &axes, &diagonal);
        Ok(Some(Central {
            mass,
            centre: v::mat_vec(pool, &rotation, &centre),
            inertia: v::mat_mul(pool, &half, &v::transpose(&axes)),
        }))
    }

    /// The inertia wrench (force, moment at the origin) of a body turning at ω with angular
    /// acceleration α, its origin accelerating at a.
    fn inertia_wrench(&mut self, body: &Central, w: &Vec3, alpha: &Vec3, a: &Vec3) -> Wrench {
        let pool = &mut self.pool;
        let c = body.centre;
        let tangential = v::cross(pool, alpha, &c);
        let spin = v::cross(pool, w, &c);
        let centripetal = v::cross(pool, w, &spin);
        let at_centre = v::add(pool, a, &tangential);
        let at_centre = v::add(pool, &at_centre, &centripetal);
        let force = v::scale(pool, body.mass, &at_centre);
        let turning = v::mat_vec(pool, &body.inertia, w);
        let gyroscopic = v::cross(pool, w, &turning);
        let euler = v::mat_vec(pool, &body.inertia, alpha);
        let lever = v::cross(pool, &c, &force);
        let moment = v::add(pool, &euler, &gyroscopic);
        [force, v::add(pool, &moment, &lever)]
    }

    /// Every body's wrench carried from the leaves to the root through the physical parents
    /// (welded bodies included), projected on each body's own columns on the way.
    fn carried_down(&mut self, mut wrenches: Vec<Option<Wrench>>) -> Vec<ExprId> {
        let zero = self.pool.constant(0.0);
        let mut generalised = vec![zero; self.columns()];
        for b in (1..=self.topology.body_count()).rev() {
            let Some([force, moment]) = wrenches[b] else {
                continue;
            };
            for column in self.own_columns(b) {
                if let Some([angular, linear]) = self.bodies[b].column(column).copied() {
                    let along = v::dot(&mut self.pool, &linear, &force);
                    let about = v::dot(&mut self.pool, &angular, &moment);
                    generalised[column] = self.pool.add(along, about);
                }
            }
            let parent = self.topology.parent(b);
            if parent == 0 {
                continue;
            }
            let pool = &mut self.pool;
            let arm = v::sub(pool, &self.bodies[b].origin, &self.bodies[parent].origin);
            let lever = v::cross(pool, &arm, &force);
            let moved = v::add(pool, &moment, &lever);
            wrenches[parent] = Some(match wrenches[parent] {
                Some([f, m]) => [v::add(pool, &f, &force), v::add(pool, &m, &moved)],
                None => [force, moved],
            });
        }
        generalised
    }
}
