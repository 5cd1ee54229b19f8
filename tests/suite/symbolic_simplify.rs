//! The simplifier of the symbolic equations: identities it must find, its values against the
//! unsimplified equations' at random points (every example, random trees), the closed form of
//! the double pendulum's mass matrix, and its output's size against SymPy's `simplify` of the
//! same equations (fixture `tests/fixtures/sympy_simplified_sizes.json`, written by
//! `bench/sympy_simplified_sizes.py`).

use lsdc::driver::compile_text;
use lsdc::load::LoadOptions;
use lsdc::symbolic::expr::{ExprId, Pool, Tape};
use lsdc::symbolic::simplify::{simplify, simplify_equations, simplify_groups};
use lsdc::symbolic::{self, Equations};
use proptest::prelude::*;

use crate::common::symbolic::{equations_of, written_equations, Sequence};
use crate::common::trees::tree_program;

/// The operations `roots` take to evaluate (see `Tape::operation_count`).
fn operations(pool: &Pool, roots: &[ExprId]) -> usize {
    Tape::new(pool, roots).operation_count()
}

#[test]
fn like_terms_collect_and_cancel() {
    let mut pool = Pool::new();
    let (x, z) = (pool.symbol("x1"), pool.symbol("z12"));
    // z12 + x1 − z12 = x1; 2 x + 3 x = 5 x; x · x / x = x.
    let sum = pool.add(z, x);
    let cancelled = pool.sub(sum, z);
    let (two, three) = (pool.constant(2.0), pool.constant(3.0));
    let (twice, thrice) = (pool.mul(two, x), pool.mul(three, x));
    let collected = pool.add(twice, thrice);
    let square = pool.mul(x, x);
    let quotient = pool.div(square, x);
    let (out, roots) = simplify(&pool, &[cancelled, collected, quotient]);
    assert_eq!(out.name_of(roots[0]), Some("x1"));
    assert_eq!(operations(&out, &roots[1..2]), 1, "5 x is one product");
    assert_eq!(out.name_of(roots[2]), Some("x1"));
}

/// `Pool::operation_count`, which the simplifier compares its candidate forms by, counts what
/// the tape it does not build would: negations only subtractions read are not operations, one
/// that something else reads (or a root) is.
#[test]
fn the_operation_count_is_the_tapes() {
    let mut pool = Pool::new();
    let (x, y) = (pool.symbol("x"), pool.symbol("y"));
    let (nx, ny) = (pool.neg(x), pool.neg(y));
    let difference = pool.add(x, ny); // x − y
    let both = pool.add(nx, ny); // −x − y: −x is read, −y is subtracted
    let product = pool.mul(ny, x); // −y read by a product too
    let sine = pool.sin(x);
    let nsine = pool.neg(sine);
    for roots in [
        vec![difference],
        vec![both],
        vec![difference, product],
        vec![nx],
        vec![both, nsine, nx],
        vec![x],
    ] {
        assert_eq!(
            pool.operation_count(&roots),
            Tape::new(&pool, &roots).operation_count(),
            "{roots:?}"
        );
    }
    for path in ["examples/satellite.lsd", "examples/double_pendulum.lsd"] {
        let equations = equations_of(path);
        let roots = equations.roots();
        let (simplified, simplified_roots) = simplify(&equations.pool, &roots);
        for (pool, roots) in [(&equations.pool, &roots), (&simplified, &simplified_roots)] {
            assert_eq!(
                pool.operation_count(roots),
                Tape::new(pool, roots).operation_count(),
                "{path}"
            );
        }
    }
}

#[test]
fn pythagoras_and_the_angle_sums_hold() {
    let mut pool = Pool::new();
    let (a, b) = (pool.symbol("a"), pool.symbol("b"));
    let (sa, ca, sb, cb) = (pool.sin(a), pool.cos(a), pool.sin(b), pool.cos(b));
    let (ss, cc) = (pool.mul(sa, sa), pool.mul(ca, ca));
    let one = pool.add(ss, cc);
    // cos a cos b − sin a sin b = cos(a + b); sin a cos b + cos a sin b = sin(a + b).
    let (cacb, sasb) = (pool.mul(ca, cb), pool.mul(sa, sb));
    let cosine = pool.sub(cacb, sasb);
    let (sacb, casb) = (pool.mul(sa, cb), pool.mul(ca, sb));
    let sine = pool.add(sacb, casb);
    // sin a · sin(a + b) + cos a · cos(a + b) = cos b.
    let (ssum, csum) = (pool.mul(sa, sine), pool.mul(ca, cosine));
    let difference = pool.add(ssum, csum);
    let (out, roots) = simplify(&pool, &[one, cosine, sine, difference]);
    assert_eq!(out.as_constant(roots[0]), Some(1.0));
    // cos(a + b): a sum and a cosine.
    assert_eq!(operations(&out, &roots[1..2]), 2);
    assert_eq!(operations(&out, &roots[2..3]), 2);
    let mut expected = out;
    let b = expected.symbol("b");
    assert_eq!(roots[3], expected.cos(b));
}

/// The largest difference between the equations and their simplified form at `points` random
/// points, relative to 1 + |value|; entries that are not finite before are left out (the
/// simplifier may give a value where the input divided by zero).
fn worst_difference(equations: &Equations, points: usize, seed: u64) -> f64 {
    worst_difference_at(equations, points, seed).0
}

/// `worst_difference`, with the root where it is and the two values there.
fn worst_difference_at(equations: &Equations, points: usize, seed: u64) -> (f64, usize, f64, f64) {
    let simplified = simplify_equations(equations);
    let (before, after) = (equations.tape(), simplified.tape());
    let mut random = Sequence(seed);
    let mut worst = (0.0f64, 0, 0.0, 0.0);
    for _ in 0..points {
        let symbols: Vec<f64> = (0..equations.pool.symbol_count())
            .map(|_| 2.0 * random.next())
            .collect();
        let (x, y) = (before.eval(&symbols), after.eval(&symbols));
        for (root, (x, y)) in x.iter().zip(&y).enumerate() {
            let difference = (x - y).abs() / (1.0 + x.abs());
            if x.is_finite() && difference > worst.0 {
                worst = (difference, root, *x, *y);
            }
        }
    }
    worst
}

/// The largest residual of M q̈ = S + F for the equations' own accelerations at random points,
/// relative to |M| |q̈| + |S + F| (the backward error of a solve).
fn acceleration_residual(equations: &Equations, seed: u64) -> f64 {
    let tape = equations.tape();
    let mut random = Sequence(seed);
    let mut worst = 0.0f64;
    for _ in 0..4 {
        let symbols: Vec<f64> = (0..equations.pool.symbol_count())
            .map(|_| 2.0 * random.next())
            .collect();
        let at = equations.evaluate(&tape, &symbols);
        let Some(accelerations) = at.accelerations else {
            return 0.0;
        };
        let forcing = &at.second_member + &at.forces;
        let residual = &at.mass * &accelerations - &forcing;
        // Relative to the terms, with M times an acceleration of 1 as a floor: the symbols
        // (coordinates, rates, masses, lengths) are of order 1, and where the exact forcing is
        // zero (one body turning about a fixed axis, no efforts) both sides are round-off, whose
        // ratio says nothing (q'' = -1.8e-17 q'^2 simplified against S + F of 1e-17).
        let scale = at.mass.norm() * accelerations.norm().max(1.0) + forcing.norm();
        if scale.is_finite() && scale > 0.0 {
            worst = worst.max(residual.norm() / scale);
        }
    }
    worst
}

#[test]
fn every_example_keeps_its_values() {
    let mut checked = 0;
    for entry in std::fs::read_dir(concat!(env!("CARGO_MANIFEST_DIR"), "/examples")).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_none_or(|e| e != "lsd") {
            continue;
        }
        let relative = format!("examples/{}", path.file_name().unwrap().to_string_lossy());
        let Some(equations) = written_equations(&relative) else {
            continue;
        };
        let worst = worst_difference(&equations, 5, 11);
        assert!(
            worst < 1e-9,
            "{relative}: simplified equations differ by {worst:e}"
        );
        checked += 1;
    }
    assert!(checked > 20, "only {checked} examples have equations");
}

#[test]
fn the_double_pendulum_mass_matrix_is_its_closed_form() {
    // Two uniform rods, l1 = 1, m1 = 1, l2 = 0.8, m2 = 0.8, hinged about parallel axes:
    // M11 = m1 l1²/3 + m2 (l1² + l2²/3 + l1 l2 cos q2), M12 = m2 (l2²/3 + l1 l2 cos q2 / 2),
    // M22 = m2 l2²/3; each a number plus a number times cos q2, or a number.
    let equations = simplify_equations(&equations_of("examples/double_pendulum.lsd"));
    let mass = &equations.mass;
    assert_eq!(operations(&equations.pool, &mass[0..1]), 3, "a + b cos(q2)");
    assert_eq!(operations(&equations.pool, &mass[1..2]), 3, "a + b cos(q2)");
    let m22 = equations
        .pool
        .as_constant(mass[3])
        .expect("M22 is a number");
    assert!((m22 - 0.8 * 0.64 / 3.0).abs() < 1e-15, "{m22}");
    let tape = Tape::new(&equations.pool, mass);
    let mut random = Sequence(3);
    for _ in 0..10 {
        let symbols: Vec<f64> = (0..equations.pool.symbol_count())
            .map(|_| 3.0 * random.next())
            .collect();
        let elbow = (0..equations.pool.symbol_count() as u32)
            .position(|i| equations.pool.symbol_name(i) == "elbow.q")
            .expect("the elbow's coordinate");
        let q2 = symbols[elbow];
        let m = tape.eval(&symbols);
        let (m1, l1, m2, l2) = (1.0, 1.0, 0.8, 0.8);
        let m11 = m1 * l1 * l1 / 3.0 + m2 * (l1 * l1 + l2 * l2 / 3.0 + l1 * l2 * q2.cos());
        let m12 = m2 * (l2 * l2 / 3.0 + l1 * l2 * q2.cos() / 2.0);
        assert!(
            (m[0] - m11).abs() < 1e-14 && (m[1] - m12).abs() < 1e-14,
            "{m:?}"
        );
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

    /// Random trees of mixed joints: the simplified equations (M, S, F and the articulated
    /// accelerations) equal the unsimplified ones at random points.
    #[test]
    fn simplification_keeps_the_values_of_random_trees(
        parents in prop::collection::vec(any::<prop::sample::Index>(), 1..10),
        kinds in prop::collection::vec(0usize..11, 10),
        numbers in prop::collection::vec(-1.5f64..1.5, 64),
        seed in 0u64..1000,
    ) {
        let parents: Vec<usize> = parents.iter().enumerate().map(|(i, p)| p.index(i + 1)).collect();
        let text = tree_program(&parents, &kinds, &numbers);
        let options = LoadOptions { library_dirs: Vec::new(), use_environment: false, scene: None };
        let compilation = compile_text("tree.lsd", &text, None, &options);
        prop_assert!(!compilation.has_errors(), "{:?}", compilation.diagnostics);
        let mechanism = compilation.mechanism.as_ref().expect("a mechanism");
        let topology = lsdc::topology::build(mechanism).expect("a topology");
        let equations = symbolic::generate(mechanism, &topology).expect("equations");
        // M, S, F against the unsimplified ones; the accelerations, a solve whose round-off
        // the mass matrix's condition amplifies, by their residual in M q̈ = S + F.
        let direct = equations.mass.len() + 2 * equations.dimension();
        let (worst, root, x, y) = worst_difference_at(&equations, 4, seed);
        prop_assert!(root >= direct || worst < 1e-9, "simplified equations differ by {worst:e} at root {root} ({x:e} against {y:e})\n{text}");
        let residual = acceleration_residual(&simplify_equations(&equations), seed);
        prop_assert!(residual < 1e-9, "simplified accelerations leave a residual of {residual:e}\n{text}");
    }
}

/// The planar n-link pendulum of `benches/symbolic.rs` and `bench/sympy_simplified_sizes.py`.
fn pendulum_program(n: usize) -> String {
    let mut text = String::from("let g = 9.81 ;\n");
    for i in 1..=n {
        text += &format!("let l{i} = body mass = 1, iframe = [0, 0, -0.5] ++ 1, inertia = [0.08, 0.08, 0.01] end ;\n");
        let parent = match i {
            1 => "earth".to_string(),
            _ => format!("[0, 0, -1] ++ 1 @ l{}", i - 1),
        };
        text += &format!(
            "join {parent} and l{i}.frame with link(q) dof = q || [0, 1, 0] end as j{i} ;\n"
        );
        text += &format!(
            "apply force value = [0, 0, -g * l{i}.mass], body = earth end on l{i}.iframe ;\n"
        );
    }
    text
}

/// The equations of a program's text.
fn equations_of_text(text: &str) -> Equations {
    let options = LoadOptions {
        library_dirs: Vec::new(),
        use_environment: false,
        scene: None,
    };
    let compilation = compile_text("program.lsd", text, None, &options);
    assert!(!compilation.has_errors(), "{:?}", compilation.diagnostics);
    let mechanism = compilation.mechanism.as_ref().expect("a mechanism");
    let topology = lsdc::topology::build(mechanism).expect("a topology");
    symbolic::generate(mechanism, &topology).expect("equations")
}

/// The entries SymPy's sizes are taken of: M[i, j] for i ≤ j and S[i] + F[i], simplified; their
/// distinct operations.
fn simplified_operations(mut equations: Equations) -> (usize, usize) {
    let n = equations.dimension();
    let upper: Vec<ExprId> = (0..n)
        .flat_map(|i| (i..n).map(move |j| (i, j)))
        .map(|(i, j)| equations.mass[i * n + j])
        .collect();
    let forcing: Vec<ExprId> = (0..n)
        .map(|i| {
            equations
                .pool
                .add(equations.second_member[i], equations.forces[i])
        })
        .collect();
    let before = operations(&equations.pool, &[upper.clone(), forcing.clone()].concat());
    let (pool, simplified) = simplify_groups(&equations.pool, &[&upper, &forcing]);
    (before, operations(&pool, &simplified.concat()))
}

/// The simplified pendulums (n ≤ 5) and satellite against SymPy's simplified forms of the same
/// entries (fixture written by `bench/sympy_simplified_sizes.py`, with SymPy's version and the
/// method that finished). The measure is the number of operations: lsdc's distinct operations
/// of the graph against `count_ops` of SymPy's entries after `cse` (each shared subexpression
/// once on both sides). The pendulums must be no longer; the satellite is reported.
#[test]
fn simplified_sizes_against_sympy() {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/fixtures/sympy_simplified_sizes.json"
    );
    let fixture: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(path).expect("the fixture")).expect("JSON");
    let sympy = |name: &str| fixture["mechanisms"][name]["cse_ops"].as_u64();
    for n in 1..=5 {
        let (before, after) = simplified_operations(equations_of_text(&pendulum_program(n)));
        println!(
            "pendulum{n}: {before} -> {after}, SymPy {:?}",
            sympy(&format!("pendulum{n}"))
        );
        assert!(
            after <= before,
            "pendulum{n}: {after} operations from {before}"
        );
        if let Some(theirs) = sympy(&format!("pendulum{n}")) {
            assert!(
                after as u64 <= theirs,
                "pendulum{n}: {after} operations, SymPy {theirs}"
            );
        }
    }
    let (before, after) = simplified_operations(equations_of("examples/satellite.lsd"));
    println!(
        "satellite: {before} -> {after}, SymPy {:?}",
        sympy("satellite")
    );
    assert!(
        after <= before,
        "satellite: {after} operations from {before}"
    );
}
