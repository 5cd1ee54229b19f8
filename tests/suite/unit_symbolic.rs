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
