//! Unit tests of `src/kinematics/`: constants evaluated through the pool, and the derivatives
//! of a compiled dof chain against finite differences.
//! Each module holds the tests of the file of `src/` it is named after, kept out of the library
//! so that `cargo test` compiles the library once (`test = false` in Cargo.toml).

mod eval {
    use lsdc::elab::value::SExpr;
    use lsdc::elab::value::{arith, num};
    use lsdc::kinematics::chain::{ChainScratch, CompiledChain};
    use lsdc::kinematics::eval::*;
    use std::sync::Arc;

    fn expression() -> Arc<SExpr> {
        let q0 = Arc::new(SExpr::Coordinate { index: 0, order: 0 });
        let q1 = Arc::new(SExpr::Coordinate { index: 1, order: 0 });
        let e = arith(
            '*',
            &Arc::new(SExpr::call("sin", vec![arith('*', &num(2.0), &q0)])),
            &arith('^', &q1, &num(3.0)),
        );
        let e = arith(
            '+',
            &e,
            &Arc::new(SExpr::call("atan2", vec![q1.clone(), q0.clone()])),
        );
        arith(
            '/',
            &e,
            &Arc::new(SExpr::call("sqrt", vec![arith('+', &q0, &num(4.0))])),
        )
    }

    /// A chain whose one parameter is `expression()`.
    fn chain() -> CompiledChain {
        CompiledChain::new(&[&expression()], 2, &UnknownValues::new()).expect("compiles")
    }

    fn value(chain: &CompiledChain, q: [f64; 2]) -> f64 {
        let mut scratch = ChainScratch::default();
        chain.eval(&q, None, &mut scratch);
        chain.value(&scratch, 0)
    }

    /// An elaborated mechanism holds several scalar nodes per body (BENCHMARKS.md, "Toward
    /// 2 KiB per body"): a node and its `Arc` counts take a 48-byte block of glibc's malloc
    /// while the node is 24 bytes.
    #[test]
    fn a_scalar_node_takes_24_bytes() {
        assert_eq!(std::mem::size_of::<SExpr>(), 24);
    }

    #[test]
    fn constants_fold_and_evaluate() {
        let unknowns = UnknownValues::new();
        let e = arith('+', &num(2.0), &arith('*', &num(3.0), &num(0.5)));
        assert_eq!(eval(&e, &unknowns), Ok(3.5));
        let log = Arc::new(SExpr::call("log", vec![num(0.0)]));
        assert_eq!(eval(&log, &unknowns), Ok(f64::NEG_INFINITY));
        let q0 = Arc::new(SExpr::Coordinate { index: 0, order: 0 });
        assert!(eval(&q0, &unknowns).is_err());
    }

    #[test]
    fn partials_match_finite_differences() {
        let chain = chain();
        let q = [0.3, 1.7];
        let mut scratch = ChainScratch::default();
        chain.eval(&q, None, &mut scratch);
        for k in 0..2 {
            let d = chain.partial(&scratch, 0, k);
            let h = 1e-6;
            let mut plus = q;
            plus[k] += h;
            let mut minus = q;
            minus[k] -= h;
            let fd = (value(&chain, plus) - value(&chain, minus)) / (2.0 * h);
            assert!((d - fd).abs() < 1e-8, "{d} vs {fd}");
        }
    }

    #[test]
    fn second_directional_derivative_matches_finite_differences() {
        let chain = chain();
        let (q, direction) = ([0.3, 1.7], [0.8, -0.5]);
        let at = |t: f64| value(&chain, [q[0] + t * direction[0], q[1] + t * direction[1]]);
        let mut scratch = ChainScratch::default();
        chain.eval(&q, Some(&direction), &mut scratch);
        let along = |f: &dyn Fn(usize) -> f64| f(0) * direction[0] + f(1) * direction[1];
        let first = along(&|k| chain.partial(&scratch, 0, k));
        let second = along(&|l| chain.mixed(&scratch, 0, l));
        let h = 1e-4;
        let fd = (at(h) - 2.0 * at(0.0) + at(-h)) / (h * h);
        assert!((second - fd).abs() < 1e-5, "{second} vs {fd}");
        assert!((first - (at(1e-6) - at(-1e-6)) / 2e-6).abs() < 1e-8);
    }
}
