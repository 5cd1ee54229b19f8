//! Spherical and free joints of the tree in the simulator's state (`dynamics::joint`): the
//! joint's motion M, the part that moves with the child, is Rot(Q) for a spherical joint and
//! Trans(p)·Rot(Q) for a free one, with Q a quaternion (w, x, y, z) read as the position and
//! the body twist of M as the rates (angular velocity first, in the axes after M, then the
//! velocity of the translation in those axes). The equations written in these variables take
//! the simulator's state as it is, so native code needs no change of variables at each
//! evaluation; the declared angles, which the simulator recovers from Q for its outputs, are
//! not variables of them.
//!
//! Q need not have unit length: its rotation is that of Q/|Q| (the simulator normalises it
//! before each evaluation), R(Q) = I + (2/|Q|²)(w [v]× + [v]×²) with v = (x, y, z)
//! (Shuster, "A survey of attitude representations", J. Astronaut. Sci. 41, 1993, §5).

use std::collections::HashMap;

use super::expr::{ExprId, Pool};
use super::vector::Mat3;
use crate::elab::value::JoinId;

/// How a join of the tree is integrated by the simulator when it is not in its declared
/// coordinates.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BallKind {
    /// Three rotations: the quaternion Q, the angular velocity ω (3 rates).
    Spherical,
    /// A translation then three rotations: p then Q, ω then the velocity v (6 rates).
    Free,
}

impl BallKind {
    /// The names of its positions, in the simulator's order.
    pub fn position_names(self) -> &'static [&'static str] {
        match self {
            BallKind::Spherical => &["Qw", "Qx", "Qy", "Qz"],
            BallKind::Free => &["px", "py", "pz", "Qw", "Qx", "Qy", "Qz"],
        }
    }

    /// The names of its rates, in the simulator's order.
    pub fn rate_names(self) -> &'static [&'static str] {
        match self {
            BallKind::Spherical => &["wx", "wy", "wz"],
            BallKind::Free => &["wx", "wy", "wz", "vx", "vy", "vz"],
        }
    }

    /// Where the quaternion starts among its positions.
    pub fn quaternion_offset(self) -> usize {
        match self {
            BallKind::Spherical => 0,
            BallKind::Free => 3,
        }
    }
}

/// The tree's joins that the equations write in the simulator's state (`BallKind`); every
/// other join in its declared coordinates.
pub type QuaternionJoins = HashMap<JoinId, BallKind>;

/// The rotation of Q/|Q|, as expressions of Q's components (w, x, y, z).
pub fn rotation(pool: &mut Pool, q: &[ExprId; 4]) -> Mat3 {
    let [w, x, y, z] = *q;
    let square = |pool: &mut Pool, a: ExprId| pool.mul(a, a);
    let (ww, xx, yy, zz) = (
        square(pool, w),
        square(pool, x),
        square(pool, y),
        square(pool, z),
    );
    let norm = pool.sum([ww, xx, yy, zz]);
    let two = pool.constant(2.0);
    let scale = pool.div(two, norm);
    let product = |pool: &mut Pool, a: ExprId, b: ExprId| pool.mul(a, b);
    let (xy, xz, yz) = (
        product(pool, x, y),
        product(pool, x, z),
        product(pool, y, z),
    );
    let (wx, wy, wz) = (
        product(pool, w, x),
        product(pool, w, y),
        product(pool, w, z),
    );
    // 1 − (2/|Q|²)(b² + c²) on the diagonal, (2/|Q|²)(ab ∓ wc) off it.
    let one = pool.constant(1.0);
    let diagonal = |pool: &mut Pool, a: ExprId, b: ExprId| {
        let sum = pool.add(a, b);
        let scaled = pool.mul(scale, sum);
        pool.sub(one, scaled)
    };
    let off = |pool: &mut Pool, a: ExprId, b: ExprId, plus: bool| {
        let sum = if plus { pool.add(a, b) } else { pool.sub(a, b) };
        pool.mul(scale, sum)
    };
    [
        [
            diagonal(pool, yy, zz),
            off(pool, xy, wz, false),
            off(pool, xz, wy, true),
        ],
        [
            off(pool, xy, wz, true),
            diagonal(pool, xx, zz),
            off(pool, yz, wx, false),
        ],
        [
            off(pool, xz, wy, false),
            off(pool, yz, wx, true),
            diagonal(pool, xx, yy),
        ],
    ]
}

/// dQ/dt = ½ Q ⊗ (0, ω) for the body angular velocity ω: the simulator's
/// `joint::quaternion_rate`, as expressions.
pub fn quaternion_rate(pool: &mut Pool, q: &[ExprId; 4], w: &[ExprId; 3]) -> [ExprId; 4] {
    let [qw, qx, qy, qz] = *q;
    let [wx, wy, wz] = *w;
    let half = pool.constant(0.5);
    let mut term = |pairs: [(ExprId, ExprId, f64); 3]| {
        let products: Vec<ExprId> = pairs
            .iter()
            .map(|&(a, b, sign)| {
                let p = pool.mul(a, b);
                if sign < 0.0 {
                    pool.neg(p)
                } else {
                    p
                }
            })
            .collect();
        let sum = pool.sum(products);
        pool.mul(half, sum)
    };
    [
        term([(qx, wx, -1.0), (qy, wy, -1.0), (qz, wz, -1.0)]),
        term([(qw, wx, 1.0), (qy, wz, 1.0), (qz, wy, -1.0)]),
        term([(qw, wy, 1.0), (qx, wz, -1.0), (qz, wx, 1.0)]),
        term([(qw, wz, 1.0), (qx, wy, 1.0), (qy, wx, -1.0)]),
    ]
}
