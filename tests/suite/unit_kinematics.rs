//! Unit tests of `src/kinematics/`: the derivatives of the expression evaluator.
//! Each module holds the tests of the file of `src/` it is named after, kept out of the library
//! so that `cargo test` compiles the library once (`test = false` in Cargo.toml).

mod eval {
    use lsdc::elab::value::SExpr;
    use lsdc::elab::value::{arith, num};
    use lsdc::kinematics::eval::*;
    use std::sync::Arc;

    fn expression() -> Arc<SExpr> {
        let q0 = Arc::new(SExpr::Coordinate { index: 0, order: 0 });
        let q1 = Arc::new(SExpr::Coordinate { index: 1, order: 0 });
        let e = arith(
            '*',
            &Arc::new(SExpr::Call("sin", vec![arith('*', &num(2.0), &q0)])),
            &arith('^', &q1, &num(3.0)),
        );
        let e = arith(
            '+',
            &e,
            &Arc::new(SExpr::Call("atan2", vec![q1.clone(), q0.clone()])),
        );
        arith(
            '/',
            &e,
            &Arc::new(SExpr::Call("sqrt", vec![arith('+', &q0, &num(4.0))])),
        )
    }

    #[test]
    fn derivatives_match_finite_differences() {
        let e = expression();
        let unknowns = UnknownValues::new();
        let q = [0.3, 1.7];
        for k in 0..2 {
            let d = eval_dual(&e, &unknowns, &q, Some(k))
                .expect("evaluates")
                .first;
            let h = 1e-6;
            let mut plus = q;
            plus[k] += h;
            let mut minus = q;
            minus[k] -= h;
            let fd = (eval_by_trees(&e, &unknowns, &plus).expect("")
                - eval_by_trees(&e, &unknowns, &minus).expect(""))
                / (2.0 * h);
            assert!((d - fd).abs() < 1e-8, "{d} vs {fd}");
        }
    }

    #[test]
    fn second_directional_derivative_matches_finite_differences() {
        let e = expression();
        let unknowns = UnknownValues::new();
        let (q, direction) = ([0.3, 1.7], [0.8, -0.5]);
        let at = |t: f64| {
            let point = [q[0] + t * direction[0], q[1] + t * direction[1]];
            eval_by_trees(&e, &unknowns, &point).expect("evaluates")
        };
        let jet = eval_jet(&e, &unknowns, &Env { coordinates: &q }, &direction).expect("evaluates");
        let h = 1e-4;
        let fd = (at(h) - 2.0 * at(0.0) + at(-h)) / (h * h);
        assert!((jet.second - fd).abs() < 1e-5, "{} vs {fd}", jet.second);
        assert!((jet.first - (at(1e-6) - at(-1e-6)) / 2e-6).abs() < 1e-8);
    }
}
