//! Forward dynamics of a tree as expressions: the articulated-body recursion. Solving
//! M q̇ = S + F costs O(n³) at each evaluation; this recursion costs O(n), so its generated code
//! stays ahead of the numeric algorithms however many bodies the mechanism has.
//!
//! Each body's quantities are spatial vectors (linear part first) at its origin in its own axes,
//! where its inertia and its joint's columns are mostly the program's constants. A child c of p
//! sits at `arm` in p's axes, turned by `rotation` (c's axes in p's); X takes p's motions to c's.
//! A child moves as a_c = X a_p + S_c q̇_c + c_c, and obeys I a + p = reactions with the bias
//! force p (velocity products minus applied efforts).
//! - From the leaves: I^A = I + Σ Xᵀ Iᵃ X, p^A = p + Σ Xᵀ pᵃ, U = I^A S, D = Sᵀ U,
//!   u = τ − Sᵀ p^A, Iᵃ = I^A − U D⁻¹ Uᵀ, pᵃ = p^A + Iᵃ c + U D⁻¹ u.
//! - From the root: a = X a_p + c, q̇ = D⁻¹ (u − Uᵀ a), a += S q̇.

use super::expr::{ExprId, Pool};
use super::vector::{self as v, Mat3, Vec3};

/// A 6-vector (linear part, then angular): a kinematic vector or a wrench (force, moment).
pub type Spatial = [ExprId; 6];
/// Row-major 6 × 6.
pub type Matrix6 = [[ExprId; 6]; 6];

/// What the recursion needs of one body (index 0 is the fixed base, unused).
pub struct Body {
    pub parent: usize,
    /// The body's origin in its parent's axes, from the parent's origin.
    pub arm: Vec3,
    /// The body's axes in its parent's (`None`: the same axes).
    pub rotation: Option<Mat3>,
    /// Its joint's columns (motion per unit rate), with their coordinates' indices.
    pub columns: Vec<(usize, Spatial)>,
    /// c: the body's acceleration at zero second derivatives, less its parent's moved to it.
    pub bias: Spatial,
    /// I, or `None` for a body without mass or inertia.
    pub inertia: Option<Matrix6>,
    /// p.
    pub bias_force: Spatial,
}

/// The coordinates' second derivatives, given the link efforts' generalised forces `tau`.
pub fn accelerations(pool: &mut Pool, bodies: &[Body], tau: &[ExprId]) -> Vec<ExprId> {
    let n = bodies.len() - 1;
    let zero = pool.constant(0.0);
    let mut articulated: Vec<Option<Matrix6>> = bodies.iter().map(|b| b.inertia).collect();
    let mut bias_forces: Vec<Spatial> = bodies.iter().map(|b| b.bias_force).collect();
    let mut joints: Vec<Option<Joint>> = (0..=n).map(|_| None).collect();
    for b in (1..=n).rev() {
        let body = &bodies[b];
        let inertia = articulated[b].unwrap_or([[zero; 6]; 6]);
        let joint = Joint::new(pool, &inertia, &body.columns, &bias_forces[b], tau);
        // What the parent feels: Iᵃ = I^A − U D⁻¹ Uᵀ and pᵃ = p^A + Iᵃ c + U D⁻¹ u.
        let reduced = joint.reduce(pool, &inertia);
        let carried = mat_vec(pool, &reduced, &body.bias);
        let mut force = add(pool, &bias_forces[b], &carried);
        force = add(pool, &force, &joint.u_d_inverse_u);
        if body.parent != 0 {
            let turned = match &body.rotation {
                Some(r) => rotate_inertia(pool, r, &reduced),
                None => reduced,
            };
            let moved = transport_inertia(pool, &body.arm, &turned);
            articulated[body.parent] = Some(match articulated[body.parent] {
                Some(existing) => add_matrix(pool, &existing, &moved),
                None => moved,
            });
            let turned = match &body.rotation {
                Some(r) => rotate(pool, r, &force),
                None => force,
            };
            let moved_force = transport_force(pool, &body.arm, &turned);
            bias_forces[body.parent] = add(pool, &bias_forces[body.parent], &moved_force);
        }
        joints[b] = Some(joint);
    }
    let mut result = vec![zero; tau.len()];
    let mut motion: Vec<Spatial> = vec![[zero; 6]; n + 1];
    for b in 1..=n {
        let body = &bodies[b];
        let moved = if body.parent == 0 {
            [zero; 6]
        } else {
            motion_to_child(pool, body, &motion[body.parent])
        };
        let mut a = add(pool, &moved, &body.bias);
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

/// X x: a motion of the parent, seen at the child's origin in the child's axes.
pub fn motion_to_child(pool: &mut Pool, body: &Body, x: &Spatial) -> Spatial {
    let moved = transport_motion(pool, &body.arm, x);
    match &body.rotation {
        Some(r) => rotate(pool, &v::transpose(r), &moved),
        None => moved,
    }
}

/// Both 3-vector parts of a spatial vector turned by `r`.
fn rotate(pool: &mut Pool, r: &Mat3, x: &Spatial) -> Spatial {
    let linear = v::mat_vec(pool, r, &[x[0], x[1], x[2]]);
    let angular = v::mat_vec(pool, r, &[x[3], x[4], x[5]]);
    [
        linear[0], linear[1], linear[2], angular[0], angular[1], angular[2],
    ]
}

/// blockdiag(r, r) I blockdiag(r, r)ᵀ: an inertia turned from the child's axes to the parent's.
fn rotate_inertia(pool: &mut Pool, r: &Mat3, inertia: &Matrix6) -> Matrix6 {
    let block = |i: usize, j: usize| -> Mat3 {
        std::array::from_fn(|a| std::array::from_fn(|b| inertia[3 * i + a][3 * j + b]))
    };
    let rt = v::transpose(r);
    let mut turned = *inertia;
    for (i, j) in [(0, 0), (0, 1), (1, 1)] {
        let half = v::mat_mul(pool, r, &block(i, j));
        let full = v::mat_mul(pool, &half, &rt);
        for a in 0..3 {
            for b in 0..3 {
                turned[3 * i + a][3 * j + b] = full[a][b];
                turned[3 * j + b][3 * i + a] = full[a][b];
            }
        }
    }
    turned
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
    fn new(
        pool: &mut Pool,
        inertia: &Matrix6,
        columns: &[(usize, Spatial)],
        bias_force: &Spatial,
        tau: &[ExprId],
    ) -> Joint {
        let u: Vec<Spatial> = columns
            .iter()
            .map(|(_, s)| mat_vec(pool, inertia, s))
            .collect();
        let d: Vec<Vec<ExprId>> = columns
            .iter()
            .map(|(_, s)| u.iter().map(|ui| dot(pool, s, ui)).collect())
            .collect();
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
        Joint {
            u,
            factors,
            small_u,
            u_d_inverse_u,
        }
    }

    /// I^A − U D⁻¹ Uᵀ, symmetric by construction (upper triangle mirrored).
    fn reduce(&self, pool: &mut Pool, inertia: &Matrix6) -> Matrix6 {
        let mut reduced = *inertia;
        if self.u.is_empty() {
            return reduced;
        }
        // D⁻¹ Uᵀ, one 6-vector per joint coordinate: W = D⁻¹ [U rows].
        let rows: Vec<Vec<ExprId>> = (0..6)
            .map(|r| self.u.iter().map(|ui| ui[r]).collect())
            .collect();
        let solved: Vec<Vec<ExprId>> = rows
            .iter()
            .map(|row| self.factors.solve(pool, row))
            .collect();
        for i in 0..6 {
            for j in i..6 {
                let terms: Vec<ExprId> = self
                    .u
                    .iter()
                    .zip(&solved[j])
                    .map(|(ui, w)| pool.mul(ui[i], *w))
                    .collect();
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

pub fn add(pool: &mut Pool, a: &Spatial, b: &Spatial) -> Spatial {
    std::array::from_fn(|i| pool.add(a[i], b[i]))
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
pub fn transport_motion(pool: &mut Pool, arm: &Vec3, x: &Spatial) -> Spatial {
    let angular = [x[3], x[4], x[5]];
    let spin = super::vector::cross(pool, &angular, arm);
    [
        pool.add(x[0], spin[0]),
        pool.add(x[1], spin[1]),
        pool.add(x[2], spin[2]),
        x[3],
        x[4],
        x[5],
    ]
}

/// Tᵀ f: a wrench at the child's origin moved to the parent's (f, m + arm ∧ f).
fn transport_force(pool: &mut Pool, arm: &Vec3, f: &Spatial) -> Spatial {
    let force = [f[0], f[1], f[2]];
    let lever = super::vector::cross(pool, arm, &force);
    [
        f[0],
        f[1],
        f[2],
        pool.add(f[3], lever[0]),
        pool.add(f[4], lever[1]),
        pool.add(f[5], lever[2]),
    ]
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
    let skew = [
        [zero, arm[2], minus[1]],
        [minus[2], zero, arm[0]],
        [arm[1], minus[0], zero],
    ];
    for i in 0..3 {
        for j in 0..3 {
            t[i][3 + j] = skew[i][j];
        }
    }
    let mut moved = [[zero; 6]; 6];
    let it: Matrix6 = std::array::from_fn(|i| {
        std::array::from_fn(|j| {
            let terms: Vec<ExprId> = (0..6).map(|k| pool.mul(inertia[i][k], t[k][j])).collect();
            pool.sum(terms)
        })
    });
    for i in 0..6 {
        for j in i..6 {
            let terms: Vec<ExprId> = (0..6).map(|k| pool.mul(t[k][i], it[k][j])).collect();
            moved[i][j] = pool.sum(terms);
            moved[j][i] = moved[i][j];
        }
    }
    moved
}
