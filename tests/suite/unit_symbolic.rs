//! Unit tests of `src/symbolic/`: the expression pool and the symbolic rotations.
//! Each module holds the tests of the file of `src/` it is named after, kept out of the library
//! so that `cargo test` compiles the library once (`test = false` in Cargo.toml).

mod expr {
    use lsdc::symbolic::expr::*;

    #[test]
    fn equal_expressions_are_one_node() {
        let mut p = Pool::new();
        let (x, y) = (p.symbol("x"), p.symbol("y"));
        let a = p.add(x, y);
        let b = p.add(y, x);
        assert_eq!(a, b);
        let (s1, s2) = (p.sin(a), p.sin(b));
        assert_eq!(s1, s2);
        assert_eq!(p.symbol("x"), x);
    }

    /// Folding keeps IEEE 754's meaning: 0 · x, x − x, 0 / x and x / x are constants only where
    /// x is surely finite (and, for a quotient, a nonzero constant), since each is NaN at an
    /// infinite or vanishing x.
    #[test]
    fn folding_keeps_nan_and_infinity() {
        let mut p = Pool::new();
        let t = p.symbol("time");
        let (zero, one) = (p.constant(0.0), p.constant(1.0));
        let inverse = p.div(one, t);
        let root = p.sqrt(t);
        for maybe_infinite in [inverse, root] {
            assert!(!p.surely_finite(maybe_infinite));
            let product = p.mul(zero, maybe_infinite);
            assert!(
                !p.is_zero(product),
                "0 · x folded for an x that may be infinite"
            );
            let minus = p.neg(maybe_infinite);
            let difference = p.add(maybe_infinite, minus);
            assert!(
                !p.is_zero(difference),
                "x − x folded for an x that may be NaN"
            );
        }
        // Quotients by a value that may vanish are kept.
        let quotient = p.div(t, t);
        assert!(p.as_constant(quotient).is_none(), "t / t folded to 1");
        let zero_over = p.div(zero, t);
        assert!(p.as_constant(zero_over).is_none(), "0 / t folded to 0");
        let zero_over_zero = p.div(zero, zero);
        assert!(p.as_constant(zero_over_zero).is_none(), "0 / 0 folded");
        // Where x is surely finite, the folds stay.
        let s = p.sin(t);
        let product = p.mul(s, zero);
        assert!(p.is_zero(product));
        let minus_t = p.neg(t);
        let difference = p.add(t, minus_t);
        assert!(p.is_zero(difference));
        let two = p.constant(2.0);
        let half = p.div(one, two);
        assert_eq!(p.as_constant(half), Some(0.5));
    }

    #[test]
    fn neutral_and_absorbing_constants_vanish() {
        let mut p = Pool::new();
        let x = p.symbol("x");
        let (zero, one, minus_one) = (p.constant(0.0), p.constant(1.0), p.constant(-1.0));
        assert_eq!(p.add(x, zero), x);
        assert_eq!(p.mul(one, x), x);
        let absorbed = p.mul(x, zero);
        assert!(p.is_zero(absorbed));
        let minus_x = p.mul(minus_one, x);
        assert_eq!(p.neg(minus_x), x);
        let cancelled = p.sub(x, x);
        assert!(p.is_zero(cancelled));
        let two = p.constant(2.0);
        let three = p.constant(3.0);
        let five = p.add(two, three);
        assert_eq!(p.as_constant(five), Some(5.0));
        assert_eq!(p.constant(-0.0), zero);
    }

    #[test]
    fn shared_subexpressions_are_counted_once() {
        let mut p = Pool::new();
        let q = p.symbol("q");
        let (s, c) = (p.sin(q), p.cos(q));
        let sc = p.mul(s, c);
        let e1 = p.add(sc, s);
        let e2 = p.sub(sc, c);
        let tape = Tape::new(&p, &[e1, e2]);
        // q, sin q, cos q, sin q cos q, e1, −cos q, e2.
        assert_eq!(tape.size(), 7);
        let values = tape.eval(&[0.3]);
        let (sv, cv) = (0.3f64.sin(), 0.3f64.cos());
        assert!((values[0] - (sv * cv + sv)).abs() < 1e-15);
        assert!((values[1] - (sv * cv - cv)).abs() < 1e-15);
    }
}

mod vector {
    use lsdc::symbolic::expr::{ExprId, Pool, Tape};
    use lsdc::symbolic::vector::*;

    #[test]
    fn rotation_about_x_folds_to_the_textbook_matrix() {
        let mut p = Pool::new();
        let q = p.symbol("q");
        let x = constant(&mut p, [1.0, 0.0, 0.0]);
        let r = rotation(&mut p, &x, q);
        let (zero, one) = (p.constant(0.0), p.constant(1.0));
        let (c, s) = (p.cos(q), p.sin(q));
        let minus_s = p.neg(s);
        assert_eq!(r, [[one, zero, zero], [zero, c, minus_s], [zero, s, c]]);
    }

    #[test]
    fn rotation_about_an_oblique_axis_matches_nalgebra() {
        let mut p = Pool::new();
        let q = p.symbol("q");
        let axis = nalgebra::Vector3::new(1.0, -2.0, 0.5).normalize();
        let u = constant(&mut p, [axis.x, axis.y, axis.z]);
        let r = rotation(&mut p, &u, q);
        let roots: Vec<ExprId> = r.iter().flatten().copied().collect();
        let values = Tape::new(&p, &roots).eval(&[0.7]);
        let expected =
            nalgebra::Rotation3::from_axis_angle(&nalgebra::Unit::new_normalize(axis), 0.7);
        for i in 0..3 {
            for j in 0..3 {
                assert!((values[3 * i + j] - expected[(i, j)]).abs() < 1e-15);
            }
        }
    }
}
