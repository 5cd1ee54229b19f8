//! The products by the constant 0 folded in the generated forward dynamics, where the
//! articulated-body recursion leaves them: its spatial quantities are 6-vectors and 6 × 6
//! matrices whose entries are mostly the program's constants, and the entries a joint's columns
//! and a body's inertia leave at 0 still multiply the others (about a third of a double
//! pendulum's forward dynamics). The pool folds 0 · x only where x is surely finite
//! (`Pool::mul`); the quotients by the articulated inertias are not, so C and Rust compilers
//! keep those products (0 · ∞ is NaN, not 0).
//!
//! Here every 0 · x is folded to 0, and the sums and products it reaches fold after it. Why that
//! is right: in exact arithmetic 0 · x = 0, and where x is finite the floating-point product is
//! ±0 as well, which added to anything leaves it unchanged; so wherever every x is finite the
//! folded accelerations are the unfolded ones to the bit (but for the sign of a zero). Where an
//! x is not finite, the unfolded code gave NaN, and the evaluation failed: the generated
//! `forward_dynamics` returns its status "not finite", and the simulator's native result check
//! (`NativeDynamics::accelerations`) then evaluates the state otherwise and says why. Folding
//! must not turn that failure into a finite answer, so what each folded x's finiteness rests on
//! is kept as a guard, which `forward_dynamics` checks with the accelerations: the nodes below
//! x, through sums, products, negations, sines and cosines and the like, and quotients by a
//! nonzero constant, that may be infinite or NaN with finite operands (a quotient by an
//! articulated inertia, a root, a power). Those are x's only ways not to be finite, overflow of
//! a sum or product aside, as the pool's own 0 · x = 0 sets it aside (`Pool::surely_finite`).
//! A guard that is itself an acceleration is checked there already; the others are
//! temporaries the code computes for their other uses. On the double pendulum every such
//! quotient is an acceleration: the check is the accelerations' alone. The failure is the same,
//! and so is every result.

use rustc_hash::FxHashMap;

use crate::symbolic::expr::{topological_order, ExprId, Function, Node, Pool};
use crate::symbolic::Equations;

/// `equations` with the accelerations' products by 0 folded (the rest as it was), and the
/// guards: the folded operands that may not be finite, which the generated code checks.
pub fn folded(equations: &Equations) -> (Equations, Vec<ExprId>) {
    let mut equations = equations.clone();
    let Some(accelerations) = equations.accelerations.take() else {
        return (equations, Vec::new());
    };
    let (accelerations, guards) = fold(&mut equations.pool, &accelerations);
    equations.accelerations = Some(accelerations);
    (equations, guards)
}

/// `roots` rebuilt in `pool` with every 0 · x folded to 0, and what the x's folded rest on to
/// be finite (`sources`) but the roots themselves, each once, in the order met.
fn fold(pool: &mut Pool, roots: &[ExprId]) -> (Vec<ExprId>, Vec<ExprId>) {
    let order = topological_order(roots, |id| pool.operands(id));
    let mut rebuilt: FxHashMap<ExprId, ExprId> = FxHashMap::default();
    let mut folded: Vec<ExprId> = Vec::new();
    for id in order {
        let o: Vec<ExprId> = pool.operands(id).iter().map(|x| rebuilt[x]).collect();
        let new = match pool.node(id) {
            Node::Mul(..) => match (pool.is_zero(o[0]), pool.is_zero(o[1])) {
                (true, _) => {
                    folded.push(o[1]);
                    o[0]
                }
                (_, true) => {
                    folded.push(o[0]);
                    o[1]
                }
                _ => pool.mul(o[0], o[1]),
            },
            shape => pool.rebuild(shape, &o),
        };
        rebuilt.insert(id, new);
    }
    let roots: Vec<ExprId> = roots.iter().map(|r| rebuilt[r]).collect();
    let mut guards: Vec<ExprId> = Vec::new();
    for source in sources(pool, &folded) {
        if !roots.contains(&source) {
            guards.push(source);
        }
    }
    (roots, guards)
}

/// The nodes that `values` are finite when they are (overflow aside): below each value, through
/// the operations that give a finite result of finite operands (as `Pool::surely_finite`
/// takes them, and the quotient by a nonzero finite constant), the nodes not surely finite
/// that may not be finite with finite operands. Each once, in the order met.
fn sources(pool: &Pool, values: &[ExprId]) -> Vec<ExprId> {
    let mut seen: rustc_hash::FxHashSet<ExprId> = rustc_hash::FxHashSet::default();
    let mut found = Vec::new();
    let mut stack: Vec<ExprId> = values.iter().rev().copied().collect();
    while let Some(id) = stack.pop() {
        if pool.surely_finite(id) || !seen.insert(id) {
            continue;
        }
        let through: Vec<ExprId> = match pool.node(id) {
            Node::Add(a, b) | Node::Mul(a, b) | Node::Atan2(a, b) => vec![a, b],
            Node::Neg(a)
            | Node::Apply(
                Function::Sin | Function::Cos | Function::Atan | Function::Abs | Function::Floor,
                a,
            ) => vec![a],
            // Only the value taken matters, whatever the test.
            Node::Select {
                when_nonnegative,
                otherwise,
                ..
            } => vec![when_nonnegative, otherwise],
            Node::Div(a, b)
                if pool
                    .as_constant(b)
                    .is_some_and(|c| c != 0.0 && c.is_finite()) =>
            {
                vec![a]
            }
            _ => {
                found.push(id);
                continue;
            }
        };
        stack.extend(through.into_iter().rev());
    }
    found
}
