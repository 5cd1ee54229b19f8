//! Forward dynamics of a tree as expressions: the articulated-body recursion written on the
//! thesis's kinematic vectors 𝐪ᵢ = (v(Oᵢ), ωᵢ) in the fixed axes. Solving M q̇ = S + F costs
//! O(n³) at each evaluation; this recursion costs O(n), so its generated code stays ahead of the
//! numeric algorithms however many bodies the mechanism has.
//!
//! With T the transport from a parent's origin to its child's (v ↦ v + ω ∧ r), a child moves as
//! 𝐪̇_c = T 𝐪̇_p + S_c q̇_c + c_c, where S_c holds its joint's columns of Ψ and
//! c_c = Ψ̇_c q − T Ψ̇_p q. Each body obeys 𝔐 𝐪̇ + p = reactions with the bias force
//! p = −(𝔖 + 𝔉).
//! - From the leaves: I^A = 𝔐 + Σ Tᵀ Iᵃ T, p^A = p + Σ Tᵀ pᵃ, U = I^A S, D = Sᵀ U,
//!   u = τ − Sᵀ p^A, Iᵃ = I^A − U D⁻¹ Uᵀ, pᵃ = p^A + Iᵃ c + U D⁻¹ u.
//! - From the root: a = T 𝐪̇_p + c, q̇ = D⁻¹ (u − Uᵀ a), 𝐪̇ = a + S q̇.

use super::expr::{ExprId, Pool};
use super::vector::Vec3;

/// A 6-vector (linear part, then angular): a kinematic vector or a wrench (force, moment).
pub type Spatial = [ExprId; 6];
/// Row-major 6 × 6.
pub type Matrix6 = [[ExprId; 6]; 6];

/// What the recursion needs of one body (index = body number, 0 = earth, unused).
pub struct Body {
    pub parent: usize,
    /// Origin in the fixed axes, to transport between bodies.
    pub origin: Vec3,
    /// The body's own joint's columns of Ψ, as (linear, angular) 6-vectors, and their
    /// coordinates' indices.
    pub columns: Vec<(usize, Spatial)>,
    /// Ψ̇ q of the body: (acceleration of the origin, angular acceleration) at q̇ = 0.
    pub bias: Spatial,
    /// 𝔐, or `None` for a body without mass or inertia.
    pub inertia: Option<Matrix6>,
    /// p = −(𝔖 + 𝔉).
    pub bias_force: Spatial,
}

/// The coordinates' second derivatives, given the link efforts' generalised forces `tau`.
pub fn accelerations(pool: &mut Pool, bodies: &[Body], tau: &[ExprId]) -> Vec<ExprId> {
    let n = bodies.len() - 1;
    let zero = pool.constant(0.0);
    let mut articulated: Vec<Option<Matrix6>> = bodies.iter().map(|b| b.inertia).collect();
    let mut bias_forces: Vec<Spatial> = bodies.iter().map(|b| b.bias_force).collect();
    let mut joints: Vec<Option<Joint>> = (0..=n).map(|_| None).collect();
    let mut local_bias: Vec<Spatial> = vec![[zero; 6]; n + 1];
    for b in (1..=n).rev() {
        let body = &bodies[b];
        let parent = &bodies[body.parent];
        let arm = super::vector::sub(pool, &body.origin, &parent.origin);
        let moved_bias = if body.parent == 0 { [zero; 6] } else { transport_motion(pool, &arm, &parent.bias) };
        local_bias[b] = sub(pool, &body.bias, &moved_bias);
        let inertia = articulated[b].unwrap_or([[zero; 6]; 6]);
        let joint = Joint::new(pool, &inertia, &body.columns, &bias_forces[b], tau);
        // What the parent feels: Iᵃ = I^A − U D⁻¹ Uᵀ and pᵃ = p^A + Iᵃ c + U D⁻¹ u.
        let reduced = joint.reduce(pool, &inertia);
        let carried = mat_vec(pool, &reduced, &local_bias[b]);
        let mut force = add(pool, &bias_forces[b], &carried);
        force = add(pool, &force, &joint.u_d_inverse_u);
        if body.parent != 0 {
            let moved = transport_inertia(pool, &arm, &reduced);
            articulated[body.parent] = Some(match articulated[body.parent] {
                Some(existing) => add_matrix(pool, &existing, &moved),
                None => moved,
            });
            let moved_force = transport_force(pool, &arm, &force);
            bias_forces[body.parent] = add(pool, &bias_forces[body.parent], &moved_force);
        }
        joints[b] = Some(joint);
    }
    let mut result = vec![zero; tau.len()];
    let mut motion: Vec<Spatial> = vec![[zero; 6]; n + 1];
    for b in 1..=n {
        let body = &bodies[b];
        let arm = super::vector::sub(pool, &body.origin, &bodies[body.parent].origin);
        let moved = if body.parent == 0 { [zero; 6] } else { transport_motion(pool, &arm, &motion[body.parent]) };
        let mut a = add(pool, &moved, &local_bias[b]);
        let Some(joint) = &joints[b] else { continue };
        let rates = joint.rates(pool, &a);
        for ((column, s), rate) in body.columns.iter().zip(&rates) {
            result[*column] = *rate;
            let contribution = s.map(|x| pool.mul(x, *rate));
            a = add(pool, &a, &contribution);
        }
        motion[b] = a;
    }
    result
}

/// One joint's articulated quantities: U = I^A S (columns), D⁻¹ through its LDLᵀ factors,
/// u = τ − Sᵀ p^A.
struct Joint {
    u: Vec<Spatial>,
    factors: Ldl,
    small_u: Vec<ExprId>,
    /// U D⁻¹ u.
    u_d_inverse_u: Spatial,
}

impl Joint {
    fn new(pool: &mut Pool, inertia: &Matrix6, columns: &[(usize, Spatial)], bias_force: &Spatial, tau: &[ExprId]) -> Joint {
        let u: Vec<Spatial> = columns.iter().map(|(_, s)| mat_vec(pool, inertia, s)).collect();
        let d: Vec<Vec<ExprId>> = columns.iter().map(|(_, s)| u.iter().map(|ui| dot(pool, s, ui)).collect()).collect();
        let small_u: Vec<ExprId> = columns
            .iter()
            .map(|(k, s)| {
                let along = dot(pool, s, bias_force);
                pool.sub(tau[*k], along)
            })
            .collect();
        let factors = Ldl::new(pool, &d);
        let solved = factors.solve(pool, &small_u);
        let u_d_inverse_u = combine(pool, &u, &solved);
        Joint { u, factors, small_u, u_d_inverse_u }
    }

    /// I^A − U D⁻¹ Uᵀ, symmetric by construction (upper triangle mirrored).
    fn reduce(&self, pool: &mut Pool, inertia: &Matrix6) -> Matrix6 {
        let mut reduced = *inertia;
        if self.u.is_empty() {
            return reduced;
        }
        // D⁻¹ Uᵀ, one 6-vector per joint coordinate: W = D⁻¹ [U rows].
        let rows: Vec<Vec<ExprId>> = (0..6).map(|r| self.u.iter().map(|ui| ui[r]).collect()).collect();
        let solved: Vec<Vec<ExprId>> = rows.iter().map(|row| self.factors.solve(pool, row)).collect();
        for i in 0..6 {
            for j in i..6 {
                let terms: Vec<ExprId> = self.u.iter().zip(&solved[j]).map(|(ui, w)| pool.mul(ui[i], *w)).collect();
                let correction = pool.sum(terms);
                reduced[i][j] = pool.sub(inertia[i][j], correction);
                reduced[j][i] = reduced[i][j];
            }
        }
        reduced
    }

    /// q̇ = D⁻¹ (u − Uᵀ a).
    fn rates(&self, pool: &mut Pool, a: &Spatial) -> Vec<ExprId> {
        let rhs: Vec<ExprId> = self
            .u
            .iter()
            .zip(&self.small_u)
            .map(|(ui, &uk)| {
                let along = dot(pool, ui, a);
                pool.sub(uk, along)
            })
            .collect();
        self.factors.solve(pool, &rhs)
    }
}

/// D = L diag(d) Lᵀ, for the small symmetric D of one joint (no square roots, no pivoting: D is
/// positive definite whenever the joint moves some mass).
struct Ldl {
    lower: Vec<Vec<ExprId>>,
    diagonal: Vec<ExprId>,
}

impl Ldl {
    fn new(pool: &mut Pool, d: &[Vec<ExprId>]) -> Ldl {
        let k = d.len();
        let zero = pool.constant(0.0);
        let mut lower = vec![vec![zero; k]; k];
        let mut diagonal = vec![zero; k];
        for j in 0..k {
            let terms: Vec<ExprId> = (0..j)
                .map(|m| {
                    let l = pool.mul(lower[j][m], lower[j][m]);
                    pool.mul(l, diagonal[m])
                })
                .collect();
            let sum = pool.sum(terms);
            diagonal[j] = pool.sub(d[j][j], sum);
            for i in j + 1..k {
                let terms: Vec<ExprId> = (0..j)
                    .map(|m| {
                        let l = pool.mul(lower[i][m], lower[j][m]);
                        pool.mul(l, diagonal[m])
                    })
                    .collect();
                let sum = pool.sum(terms);
                let rest = pool.sub(d[i][j], sum);
                lower[i][j] = pool.div(rest, diagonal[j]);
            }
        }
        Ldl { lower, diagonal }
    }

    fn solve(&self, pool: &mut Pool, b: &[ExprId]) -> Vec<ExprId> {
        let k = b.len();
        let mut y = b.to_vec();
        for i in 0..k {
            for m in 0..i {
                let t = pool.mul(self.lower[i][m], y[m]);
                y[i] = pool.sub(y[i], t);
            }
        }
        for (yi, &d) in y.iter_mut().zip(&self.diagonal) {
            *yi = pool.div(*yi, d);
        }
        for i in (0..k).rev() {
            for m in i + 1..k {
                let t = pool.mul(self.lower[m][i], y[m]);
                y[i] = pool.sub(y[i], t);
            }
        }
        y
    }
}

fn add(pool: &mut Pool, a: &Spatial, b: &Spatial) -> Spatial {
    std::array::from_fn(|i| pool.add(a[i], b[i]))
}

fn sub(pool: &mut Pool, a: &Spatial, b: &Spatial) -> Spatial {
    std::array::from_fn(|i| pool.sub(a[i], b[i]))
}

fn dot(pool: &mut Pool, a: &Spatial, b: &Spatial) -> ExprId {
    let terms: Vec<ExprId> = (0..6).map(|i| pool.mul(a[i], b[i])).collect();
    pool.sum(terms)
}

fn mat_vec(pool: &mut Pool, m: &Matrix6, x: &Spatial) -> Spatial {
    std::array::from_fn(|i| dot(pool, &m[i], x))
}

fn add_matrix(pool: &mut Pool, a: &Matrix6, b: &Matrix6) -> Matrix6 {
    std::array::from_fn(|i| std::array::from_fn(|j| pool.add(a[i][j], b[i][j])))
}

/// Σ columns[k] · weights[k].
fn combine(pool: &mut Pool, columns: &[Spatial], weights: &[ExprId]) -> Spatial {
    let zero = pool.constant(0.0);
    let mut sum = [zero; 6];
    for (c, &w) in columns.iter().zip(weights) {
        let scaled = c.map(|x| pool.mul(x, w));
        sum = add(pool, &sum, &scaled);
    }
    sum
}

/// T x: the parent's kinematic vector seen at the child's origin, `arm` away
/// (v + ω ∧ arm, ω).
fn transport_motion(pool: &mut Pool, arm: &Vec3, x: &Spatial) -> Spatial {
    let angular = [x[3], x[4], x[5]];
    let spin = super::vector::cross(pool, &angular, arm);
    [pool.add(x[0], spin[0]), pool.add(x[1], spin[1]), pool.add(x[2], spin[2]), x[3], x[4], x[5]]
}

/// Tᵀ f: a wrench at the child's origin moved to the parent's (f, m + arm ∧ f).
fn transport_force(pool: &mut Pool, arm: &Vec3, f: &Spatial) -> Spatial {
    let force = [f[0], f[1], f[2]];
    let lever = super::vector::cross(pool, arm, &force);
    [f[0], f[1], f[2], pool.add(f[3], lever[0]), pool.add(f[4], lever[1]), pool.add(f[5], lever[2])]
}

/// Tᵀ I T, as the upper triangle mirrored: with I = [[A, B], [Bᵀ, C]] and r̃ the cross-product
/// matrix of `arm`, it is [[A, B − A r̃], [·, C + r̃ B − Bᵀ r̃ − r̃ A r̃]].
fn transport_inertia(pool: &mut Pool, arm: &Vec3, inertia: &Matrix6) -> Matrix6 {
    let zero = pool.constant(0.0);
    // T as a 6 × 6 matrix; products with its zero and unit entries fold away.
    let mut t = [[zero; 6]; 6];
    let one = pool.constant(1.0);
    for (i, row) in t.iter_mut().enumerate() {
        row[i] = one;
    }
    let minus = arm.map(|a| pool.neg(a));
    // −r̃ in the top-right block: (v − r̃ ω) = v + ω ∧ r.
    let skew = [[zero, arm[2], minus[1]], [minus[2], zero, arm[0]], [arm[1], minus[0], zero]];
    for i in 0..3 {
        for j in 0..3 {
            t[i][3 + j] = skew[i][j];
        }
    }
    let mut moved = [[zero; 6]; 6];
    let it: Matrix6 = std::array::from_fn(|i| std::array::from_fn(|j| {
        let terms: Vec<ExprId> = (0..6).map(|k| pool.mul(inertia[i][k], t[k][j])).collect();
        pool.sum(terms)
    }));
    for i in 0..6 {
        for j in i..6 {
            let terms: Vec<ExprId> = (0..6).map(|k| pool.mul(t[k][i], it[k][j])).collect();
            moved[i][j] = pool.sum(terms);
            moved[j][i] = moved[i][j];
        }
    }
    moved
}
