//! `tree --exact` against oracles that do not share its code: the antenna mesh's rank at the
//! flat and at a folded configuration (the independent rebuild `bench/loops_reference.py`,
//! `tests/fixtures/loops.json`: rank 4 folded), Bennett's closed form
//! tan(θ1/2) tan(θ2/2) = sin((α2+α1)/2) / sin((α2−α1)/2), the line-symmetric Bricard linkage's
//! rank from the twists of its axes written in the test, the homocinetic property
//! (Papegay 1992, L7218: the kernel (1, 0, 0, 1, 0) at β = γ = 0), and a configuration near a
//! singular one where the numeric rank's threshold is fooled.

use std::path::PathBuf;

use lsdc::driver::compile_files;
use lsdc::elab::mechanism::Mechanism;
use lsdc::kinematics::exact::elimination::rank;
use lsdc::kinematics::exact::rational::Rational;
use lsdc::kinematics::exact::{ExactMobility, Given, Number};
use lsdc::load::LoadOptions;
use lsdc::studies::exact_mobility::{exact_tree, ExactReport};

fn mechanism(path: &str) -> Mechanism {
    let options = LoadOptions {
        library_dirs: Vec::new(),
        use_environment: false,
        scene: None,
    };
    let compilation = compile_files(&[PathBuf::from(path)], &options).expect("readable");
    assert!(!compilation.has_errors(), "{path}");
    compilation.mechanism.expect("elaborates")
}

fn analyse(path: &str, at: &[&str]) -> ExactReport {
    let given: Vec<Given> = at.iter().map(|a| Given::parse(a).unwrap()).collect();
    exact_tree(&mechanism(path), &given).expect("analysed")
}

fn exact(report: &ExactReport) -> &ExactMobility {
    report.exact.as_ref().expect("an exact rank")
}

/// The coefficient of the independent rate `k` in the rate of `name`.
fn psi(e: &ExactMobility, name: &str, k: usize) -> String {
    let row = e.configuration.iter().position(|c| c.name == name).unwrap();
    e.kernel[row][k].to_string()
}

const MAILLE1_FOLDED: [&str; 5] = [
    "*=t:1/2",
    "j21.q=t:-4/3",
    "j54.q=t:-4/3",
    "j87.q=t:-4/3",
    "j80.q=t:-1/2",
];

#[test]
fn the_antenna_mesh_has_rank_2_flat_and_4_folded() {
    let flat = analyse("examples/maille1.lsd", &["*=0"]);
    assert_eq!((exact(&flat).rank, exact(&flat).tree_dof), (2, 8));
    let folded = analyse("examples/maille1.lsd", &MAILLE1_FOLDED);
    let e = exact(&folded);
    // Symmetric folding: each arm's knee at twice its ends' angle, t = 1/2 and tan(−φ) = −4/3.
    assert_eq!((e.rank, e.first_order_mobility()), (4, 4));
    assert_eq!(e.radicand, 3, "rotations by 120° need √3");
    assert_eq!(folded.numeric_rank, Ok(4));
}

#[test]
fn bennett_closes_on_its_closed_form_with_mobility_1() {
    let report = analyse("examples/hard/bennett.lsd", &["j1.q=t:1/2"]);
    let e = exact(&report);
    assert_eq!((e.rank, e.tree_dof, e.first_order_mobility()), (2, 3, 1));
    // K = sin 75° / sin 15° = 2 + √3, so t2 = K / t1 = 4 + 2√3, and θ3 = −θ1, θ4 = −θ2.
    let t = |name: &str| {
        let c = e.configuration.iter().find(|c| c.name == name).unwrap();
        c.describe()
    };
    assert_eq!(t("j2.q"), "t = 4 + 2·√3");
    assert_eq!(t("j3.q"), "t = -1/2");
    assert_eq!(t("j4.q"), "t = -4 - 2·√3");
    assert_eq!(psi(e, "j3.q", 0), "-1");
    // Differentiating t1 t2 = K: θ̇2/θ̇1 = −(K/t1²)(1 + t1²)/(1 + t2²) = −5K/(29 + 16√3)
    // = (−50 + 15√3)/73.
    assert_eq!(psi(e, "j2.q", 0), "-50/73 + 15/73·√3");
    assert_eq!(psi(e, "j4.q", 0), "50/73 - 15/73·√3");
}

/// The twist (u, p × u) of a revolute axis through p along u.
fn twist(p: [(i64, i64); 3], u: [(i64, i64); 3]) -> Vec<Number> {
    let r = |(n, d): (i64, i64)| Rational::fraction(n, d);
    let (p, u) = (p.map(r), u.map(r));
    let cross = |i: usize, j: usize| p[i].mul(&u[j]).sub(&p[j].mul(&u[i]));
    let moment = [cross(1, 2), cross(2, 0), cross(0, 1)];
    u.into_iter()
        .chain(moment)
        .map(|x| Number::rational(x, 1))
        .collect()
}

#[test]
fn the_line_symmetric_bricard_linkage_moves_with_rank_4() {
    // The axes of examples/hard/bricard_exact.lsd, written again here.
    let axes = [
        twist([(1, 1), (0, 1), (0, 1)], [(0, 1), (3, 5), (4, 5)]),
        twist([(1, 1), (1, 1), (1, 2)], [(2, 3), (1, 3), (2, 3)]),
        twist([(0, 1), (2, 1), (1, 1)], [(4, 5), (0, 1), (3, 5)]),
        twist([(-1, 1), (0, 1), (0, 1)], [(0, 1), (-3, 5), (4, 5)]),
        twist([(-1, 1), (-1, 1), (1, 2)], [(-2, 3), (-1, 3), (2, 3)]),
        twist([(0, 1), (-2, 1), (1, 1)], [(-4, 5), (0, 1), (3, 5)]),
    ];
    // Rows: the six components; columns: the six joints.
    let matrix: Vec<Vec<Number>> = (0..6)
        .map(|row| axes.iter().map(|t| t[row].clone()).collect())
        .collect();
    let oracle = rank(&matrix);
    assert_eq!(oracle, 5, "the six twists satisfy one relation");
    let report = analyse("examples/hard/bricard_exact.lsd", &[]);
    let e = exact(&report);
    assert_eq!(e.closure_rank, oracle);
    assert_eq!((e.rank, e.tree_dof, e.first_order_mobility()), (4, 5, 1));
    // The motion keeps the symmetry: θ̇_{i+3} = θ̇_i.
    for (a, b) in [("j1.q", "j4.q"), ("j2.q", "j5.q"), ("j3.q", "j6.q")] {
        assert_eq!(psi(e, a, 0), psi(e, b, 0));
    }
}

#[test]
fn the_homocinetic_joint_turns_its_shafts_at_one_speed() {
    let at = ["l1.q=t:1/2", "l4.q=t:1/2", "l2.a=0", "l2.b=0", "l5.q=1"];
    let report = analyse("examples/homocinetic.lsd", &at);
    let e = exact(&report);
    assert_eq!((e.rank, e.first_order_mobility()), (4, 1));
    assert_eq!(e.independent, vec!["l1.q"]);
    for (name, coefficient) in [
        ("l1.q", "1"),
        ("l4.q", "1"),
        ("l2.a", "0"),
        ("l2.b", "0"),
        ("l5.q", "0"),
    ] {
        assert_eq!(psi(e, name, 0), coefficient, "{name}");
    }
}

#[test]
fn the_saltcellar_has_rank_2_on_a_branch_and_1_at_a_crossing() {
    let branch = analyse(
        "examples/saliere.lsd",
        &["l1.q=0", "l2.q=t:1/2", "l4.q=t:1/2"],
    );
    assert_eq!(exact(&branch).rank, 2);
    let crossing = analyse("examples/saliere.lsd", &["*=0"]);
    assert_eq!(exact(&crossing).rank, 1);
}

#[test]
fn near_a_singular_configuration_the_numeric_rank_is_fooled() {
    let at = ["a.q=t:1e-7", "b.q=t:-1e-7", "d.q=t:1e-7", "c.q=t:1e-7"];
    let report = analyse("examples/hard/parallelogram_near_flat.lsd", &at);
    assert_eq!(exact(&report).rank, 2);
    assert_eq!(report.numeric_rank, Ok(1));
    assert!(report.numeric_fooled());
    // Away from it the two agree.
    let report = analyse("examples/hard/parallelogram_near_flat.lsd", &[]);
    assert_eq!(
        (exact(&report).rank, report.numeric_rank.clone()),
        (2, Ok(2))
    );
    // Off the configuration set there is no rank to prove.
    let off = analyse("examples/hard/parallelogram_near_flat.lsd", &["*=t:1/10"]);
    assert!(off.exact.is_err());
}

/// The thesis's test matrix for its rank routines (Papegay 1992, L6355–6577, seed notes §4.9)
/// at (x, y) = (71, 98): rank 3 (its determinant is non-zero); and decimals read exactly.
#[test]
fn the_thesis_test_matrix_has_rank_3() {
    let f = |n: i64, d: i64| Number::rational(Rational::fraction(n, d), 1);
    let m = vec![
        vec![f(169, 6958), f(48, 1921), f(-98, 27)],
        vec![f(-27, 5041), f(142, 4943), f(-71, 9533)],
        vec![f(-4563, 6958), f(5042, 169), f(98, 71)],
    ];
    assert_eq!(rank(&m), 3);
    let dependent = vec![
        m[0].clone(),
        m[1].clone(),
        m[0].iter().zip(&m[1]).map(|(a, b)| a.add(b)).collect(),
    ];
    assert_eq!(rank(&dependent), 2);
    assert_eq!(
        Rational::parse("1e-7"),
        Some(Rational::fraction(1, 10_000_000))
    );
    assert_eq!(Rational::parse("0.1"), Some(Rational::fraction(1, 10)));
}
