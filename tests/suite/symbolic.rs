//! The expression DAG against plain floating point: random expressions over three symbols,
//! built in a pool (interned, locally simplified) and computed directly, agree at random points;
//! building the same expression twice adds no node.

use lsdc::symbolic::expr::{ExprId, Pool, Tape};
use proptest::prelude::*;

/// A small expression language: leaves are symbols 0..3 or constants, inner nodes operations.
#[derive(Clone, Debug)]
enum Tree {
    Symbol(usize),
    Constant(f64),
    Add(Box<Tree>, Box<Tree>),
    Sub(Box<Tree>, Box<Tree>),
    Mul(Box<Tree>, Box<Tree>),
    Neg(Box<Tree>),
    Sin(Box<Tree>),
    Cos(Box<Tree>),
}

fn tree() -> impl Strategy<Value = Tree> {
    let leaf = prop_oneof![
        (0usize..3).prop_map(Tree::Symbol),
        prop_oneof![Just(0.0), Just(1.0), Just(-1.0), -3.0..3.0f64].prop_map(Tree::Constant)
    ];
    leaf.prop_recursive(6, 64, 2, |inner| {
        prop_oneof![
            (inner.clone(), inner.clone()).prop_map(|(a, b)| Tree::Add(Box::new(a), Box::new(b))),
            (inner.clone(), inner.clone()).prop_map(|(a, b)| Tree::Sub(Box::new(a), Box::new(b))),
            (inner.clone(), inner.clone()).prop_map(|(a, b)| Tree::Mul(Box::new(a), Box::new(b))),
            inner.clone().prop_map(|a| Tree::Neg(Box::new(a))),
            inner.clone().prop_map(|a| Tree::Sin(Box::new(a))),
            inner.prop_map(|a| Tree::Cos(Box::new(a))),
        ]
    })
}

fn direct(t: &Tree, x: &[f64]) -> f64 {
    match t {
        Tree::Symbol(i) => x[*i],
        Tree::Constant(c) => *c,
        Tree::Add(a, b) => direct(a, x) + direct(b, x),
        Tree::Sub(a, b) => direct(a, x) - direct(b, x),
        Tree::Mul(a, b) => direct(a, x) * direct(b, x),
        Tree::Neg(a) => -direct(a, x),
        Tree::Sin(a) => direct(a, x).sin(),
        Tree::Cos(a) => direct(a, x).cos(),
    }
}

fn build(t: &Tree, pool: &mut Pool) -> ExprId {
    match t {
        Tree::Symbol(i) => pool.symbol(["x", "y", "z"][*i]),
        Tree::Constant(c) => pool.constant(*c),
        Tree::Add(a, b) => {
            let (a, b) = (build(a, pool), build(b, pool));
            pool.add(a, b)
        }
        Tree::Sub(a, b) => {
            let (a, b) = (build(a, pool), build(b, pool));
            pool.sub(a, b)
        }
        Tree::Mul(a, b) => {
            let (a, b) = (build(a, pool), build(b, pool));
            pool.mul(a, b)
        }
        Tree::Neg(a) => {
            let a = build(a, pool);
            pool.neg(a)
        }
        Tree::Sin(a) => {
            let a = build(a, pool);
            pool.sin(a)
        }
        Tree::Cos(a) => {
            let a = build(a, pool);
            pool.cos(a)
        }
    }
}

proptest! {
    #[test]
    fn pooled_expressions_evaluate_as_written(t in tree(), x in prop::array::uniform3(-2.0..2.0f64)) {
        let mut pool = Pool::new();
        // Symbols in a fixed order, so that value i is symbol i.
        for name in ["x", "y", "z"] {
            pool.symbol(name);
        }
        let root = build(&t, &mut pool);
        let size = pool.len();
        prop_assert_eq!(build(&t, &mut pool), root);
        prop_assert_eq!(pool.len(), size);
        let value = Tape::new(&pool, &[root]).eval(&x)[0];
        let expected = direct(&t, &x);
        prop_assert!((value - expected).abs() <= 1e-12 * (1.0 + expected.abs()), "{} vs {}", value, expected);
    }
}
