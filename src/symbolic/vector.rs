//! Vectors and 3 × 3 matrices of expressions, and the few operations the equations need, each
//! built in a `Pool` (so each result is simplified and shared like any expression).

use super::expr::{ExprId, Pool};

pub type Vec3 = [ExprId; 3];
/// Row-major.
pub type Mat3 = [[ExprId; 3]; 3];

pub fn constant(pool: &mut Pool, v: [f64; 3]) -> Vec3 {
    v.map(|x| pool.constant(x))
}

pub fn zero(pool: &mut Pool) -> Vec3 {
    constant(pool, [0.0; 3])
}

pub fn identity(pool: &mut Pool) -> Mat3 {
    let (zero, one) = (pool.constant(0.0), pool.constant(1.0));
    [[one, zero, zero], [zero, one, zero], [zero, zero, one]]
}

pub fn is_zero(pool: &Pool, v: &Vec3) -> bool {
    v.iter().all(|&x| pool.is_zero(x))
}

pub fn add(pool: &mut Pool, a: &Vec3, b: &Vec3) -> Vec3 {
    [
        pool.add(a[0], b[0]),
        pool.add(a[1], b[1]),
        pool.add(a[2], b[2]),
    ]
}

pub fn sub(pool: &mut Pool, a: &Vec3, b: &Vec3) -> Vec3 {
    [
        pool.sub(a[0], b[0]),
        pool.sub(a[1], b[1]),
        pool.sub(a[2], b[2]),
    ]
}

pub fn neg(pool: &mut Pool, a: &Vec3) -> Vec3 {
    a.map(|x| pool.neg(x))
}

pub fn scale(pool: &mut Pool, s: ExprId, a: &Vec3) -> Vec3 {
    a.map(|x| pool.mul(s, x))
}

pub fn dot(pool: &mut Pool, a: &Vec3, b: &Vec3) -> ExprId {
    let terms = [
        pool.mul(a[0], b[0]),
        pool.mul(a[1], b[1]),
        pool.mul(a[2], b[2]),
    ];
    pool.sum(terms)
}

pub fn cross(pool: &mut Pool, a: &Vec3, b: &Vec3) -> Vec3 {
    let component = |pool: &mut Pool, i: usize, j: usize| {
        let (l, r) = (pool.mul(a[i], b[j]), pool.mul(a[j], b[i]));
        pool.sub(l, r)
    };
    [
        component(pool, 1, 2),
        component(pool, 2, 0),
        component(pool, 0, 1),
    ]
}

pub fn mat_vec(pool: &mut Pool, m: &Mat3, v: &Vec3) -> Vec3 {
    [
        dot(pool, &m[0], v),
        dot(pool, &m[1], v),
        dot(pool, &m[2], v),
    ]
}

pub fn transpose(m: &Mat3) -> Mat3 {
    [
        [m[0][0], m[1][0], m[2][0]],
        [m[0][1], m[1][1], m[2][1]],
        [m[0][2], m[1][2], m[2][2]],
    ]
}

pub fn mat_mul(pool: &mut Pool, a: &Mat3, b: &Mat3) -> Mat3 {
    let bt = transpose(b);
    let row = |pool: &mut Pool, i: usize| {
        [
            dot(pool, &a[i], &bt[0]),
            dot(pool, &a[i], &bt[1]),
            dot(pool, &a[i], &bt[2]),
        ]
    };
    [row(pool, 0), row(pool, 1), row(pool, 2)]
}

/// The rotation by `angle` about the unit axis `axis` (Rodrigues). Written so that the entries
/// fold when the axis has zero or unit components: about x, the first row and column are exactly
/// (1, 0, 0).
pub fn rotation(pool: &mut Pool, axis: &Vec3, angle: ExprId) -> Mat3 {
    let (c, s) = (pool.cos(angle), pool.sin(angle));
    let one = pool.constant(1.0);
    let versine = pool.sub(one, c);
    let mut m = identity(pool);
    for i in 0..3 {
        for j in 0..3 {
            let uu = pool.mul(axis[i], axis[j]);
            m[i][j] = if i == j {
                // u² + c (1 − u²)
                let rest = pool.sub(one, uu);
                let turned = pool.mul(c, rest);
                pool.add(uu, turned)
            } else {
                // (1 − c) uᵢuⱼ ∓ s u_k
                let k = 3 - i - j;
                let sign = if (j + 3 - i) % 3 == 1 { -1.0 } else { 1.0 };
                let signed = pool.constant(sign);
                let su = pool.mul(s, axis[k]);
                let skew = pool.mul(signed, su);
                let symmetric = pool.mul(versine, uu);
                pool.add(symmetric, skew)
            };
        }
    }
    m
}

/// A force and a moment at a body's origin, fixed axes.
pub type Wrench = [Vec3; 2];
