#![allow(clippy::needless_range_loop)] // matrices are compared entry by entry
//! The three forms of the equations of motion (`--form lagrange|kane|newton-euler`) against
//! each other on every example, and against the double pendulum's closed forms; the Maple
//! output against the equations it was written from, by an evaluator of its own.

use std::collections::HashMap;
use std::path::PathBuf;

use lsdc::driver::compile_files;
use lsdc::load::LoadOptions;
use lsdc::symbolic::expr::Pool;
use lsdc::symbolic::{self, Equations, Form};

use crate::common::symbolic::Sequence;

/// The examples (control and hard ones too), then the URDF robots of the fixtures.
fn example_paths() -> Vec<PathBuf> {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let mut paths = Vec::new();
    for (dir, extension) in [
        ("examples", "lsd"),
        ("examples/control", "lsd"),
        ("examples/hard", "lsd"),
        ("tests/fixtures/urdf", "urdf"),
    ] {
        let mut found: Vec<PathBuf> = std::fs::read_dir(root.join(dir))
            .expect("a directory")
            .map(|e| e.expect("entry").path())
            .filter(|p| p.extension().is_some_and(|e| e == extension))
            .collect();
        found.sort();
        paths.extend(found);
    }
    paths
}

/// The equations of `path` in each form, or `None` when the symbolic back end refuses it (then
/// every form refuses it with the same code).
fn forms_of(path: &std::path::Path) -> Option<[Equations; 3]> {
    let compilation =
        compile_files(&[path.to_path_buf()], &LoadOptions::default()).expect("readable");
    let mechanism = compilation.mechanism.as_ref().expect("a mechanism");
    let topology = lsdc::topology::build(mechanism).expect("a topology");
    let generated = Form::ALL.map(|form| symbolic::generate_in(mechanism, &topology, form));
    match &generated[0] {
        Err(refused) => {
            for other in &generated[1..] {
                let code = &other.as_ref().err().expect("refused by every form")[0].code;
                assert_eq!(*code, refused[0].code, "{}", path.display());
            }
            None
        }
        Ok(_) => Some(generated.map(|g| g.expect("written by every form"))),
    }
}

/// A value per symbol name, drawn from a sequence seeded by the name and `trial`: positions and
/// rates in [-2, 2), anything else (masses, lengths, unknown laws' values) in [0.5, 1.5).
fn value_of(eq: &Equations, name: &str, trial: u64) -> f64 {
    let seed = name.bytes().fold(1469598103934665603u64 ^ trial, |h, b| {
        (h ^ b as u64).wrapping_mul(1099511628211)
    });
    let mut random = Sequence(seed);
    random.next();
    let v = &eq.variables;
    let moving = v.positions.iter().chain(&v.rates).any(|x| x.name == name);
    if moving {
        2.0 * random.next()
    } else {
        1.0 + 0.5 * random.next()
    }
}

/// M (every entry), S, F, Δ and Δ̇q of `eq` at the values of `trial`.
fn values(eq: &Equations, trial: u64) -> [Vec<f64>; 5] {
    let symbols = eq
        .symbol_values(|name| Some(value_of(eq, name, trial)))
        .expect("a value for every symbol");
    let at = eq.evaluate(&eq.tape(), &symbols);
    [
        at.mass.transpose().as_slice().to_vec(),
        at.second_member.as_slice().to_vec(),
        at.forces.as_slice().to_vec(),
        at.constraints.as_slice().to_vec(),
        at.constraint_bias.as_slice().to_vec(),
    ]
}

/// Largest |a − b| over max(1, largest |b|).
fn relative_gap(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len());
    let scale = b.iter().fold(1.0f64, |m, x| m.max(x.abs()));
    let gap = a
        .iter()
        .zip(b)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
    gap / scale
}

#[test]
fn kane_and_newton_euler_equal_the_lagrange_form_on_every_example() {
    let mut compared = Vec::new();
    for path in example_paths() {
        let Some([lagrange, kane, newton_euler]) = forms_of(&path) else {
            continue;
        };
        let name = path
            .file_name()
            .unwrap_or_default()
            .to_string_lossy()
            .to_string();
        let mut worst = [0.0f64; 2];
        for trial in 0..3 {
            let reference = values(&lagrange, trial);
            for (k, other) in [&kane, &newton_euler].into_iter().enumerate() {
                let at = values(other, trial);
                for (part, (a, b)) in at.iter().zip(&reference).enumerate() {
                    let gap = relative_gap(a, b);
                    assert!(
                        gap < 1e-11,
                        "{name}: {:?} and Lagrange differ by {gap:e} in part {part} (M, S, F, Δ, Δ̇q)",
                        Form::ALL[k + 1]
                    );
                    worst[k] = worst[k].max(gap);
                }
            }
        }
        // Both triangles of the Newton–Euler M are formed independently: it is symmetric too.
        let m = &values(&newton_euler, 0)[0];
        let n = newton_euler.dimension();
        for i in 0..n {
            for j in 0..i {
                let (a, b) = (m[i * n + j], m[j * n + i]);
                assert!(
                    (a - b).abs() <= 1e-11 * (1.0 + a.abs()),
                    "{name}: M not symmetric"
                );
            }
        }
        compared.push((
            name,
            worst,
            lagrange.size(),
            kane.size(),
            newton_euler.size(),
        ));
    }
    for (name, [kane, ne], l, k, e) in &compared {
        println!("{name:28} kane {kane:8.1e}  newton-euler {ne:8.1e}   nodes {l} / {k} / {e}");
    }
    assert!(
        compared.len() >= 30,
        "only {} examples compared",
        compared.len()
    );
}

/// The difference of two forms' entries, simplified in one pool, is exactly 0.
#[test]
fn the_forms_symbolic_differences_simplify_to_zero() {
    for example in [
        "examples/pendulum.lsd",
        "examples/double_pendulum.lsd",
        "examples/satellite_fixed.lsd",
        "examples/elliptic_pendulum.lsd",
    ] {
        let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(example);
        let [lagrange, kane, newton_euler] = forms_of(&path).expect("written");
        let mut pool = Pool::new();
        let mut differences = Vec::new();
        let roots = |eq: &Equations| -> Vec<lsdc::symbolic::expr::ExprId> {
            [&eq.mass, &eq.second_member, &eq.forces]
                .into_iter()
                .flatten()
                .copied()
                .collect()
        };
        let mut memo = HashMap::new();
        let reference: Vec<_> = roots(&lagrange)
            .into_iter()
            .map(|id| pool.transplant(&lagrange.pool, id, &mut memo))
            .collect();
        for other in [&kane, &newton_euler] {
            let mut memo = HashMap::new();
            for (k, id) in roots(other).into_iter().enumerate() {
                let moved = pool.transplant(&other.pool, id, &mut memo);
                differences.push(pool.sub(moved, reference[k]));
            }
        }
        let (simplified, zeros) = lsdc::symbolic::simplify::simplify(&pool, &differences);
        let left: Vec<usize> = (0..zeros.len())
            .filter(|&k| !simplified.is_zero(zeros[k]))
            .collect();
        assert!(
            left.is_empty(),
            "{example}: {} of {} differences are not simplified to 0",
            left.len(),
            zeros.len()
        );
    }
}

/// The double pendulum of uniform rods (examples/double_pendulum.lsd) in relative angles:
/// M = [[I1 + m1 c1² + I2 + m2 (l1² + c2² + 2 l1 c2 cos q2), I2 + m2 (c2² + l1 c2 cos q2)],
/// [·, I2 + m2 c2²]], S = h (2 q1' q2' + q2'², −q1'²) with h = m2 l1 c2 sin q2, and
/// F = −∂V/∂q with V = −m1 g c1 cos q1 − m2 g (l1 cos q1 + c2 cos(q1 + q2)).
#[test]
fn every_form_gives_the_double_pendulums_closed_forms() {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("examples/double_pendulum.lsd");
    let forms = forms_of(&path).expect("written");
    let (m1, l1, m2, l2, g) = (1.0, 1.0, 0.8, 0.8, 9.81);
    let (c1, c2) = (l1 / 2.0, l2 / 2.0);
    let (i1, i2) = (m1 * l1 * l1 / 12.0, m2 * l2 * l2 / 12.0);
    for eq in &forms {
        for trial in 0..5 {
            let value = |name: &str| value_of(eq, name, trial);
            let (q1, q2) = (value("shoulder.q"), value("elbow.q"));
            let (d1, d2) = (value("shoulder.q'"), value("elbow.q'"));
            let [mass, second, forces, _, _] = values(eq, trial);
            let m12 = i2 + m2 * (c2 * c2 + l1 * c2 * q2.cos());
            let expected_mass = [
                i1 + m1 * c1 * c1 + i2 + m2 * (l1 * l1 + c2 * c2 + 2.0 * l1 * c2 * q2.cos()),
                m12,
                m12,
                i2 + m2 * c2 * c2,
            ];
            let h = m2 * l1 * c2 * q2.sin();
            let expected_second = [h * (2.0 * d1 * d2 + d2 * d2), -h * d1 * d1];
            let expected_forces = [
                -m1 * g * c1 * q1.sin() - m2 * g * (l1 * q1.sin() + c2 * (q1 + q2).sin()),
                -m2 * g * c2 * (q1 + q2).sin(),
            ];
            for (got, expected) in [
                (&mass, &expected_mass[..]),
                (&second, &expected_second[..]),
                (&forces, &expected_forces[..]),
            ] {
                let gap = relative_gap(got, expected);
                assert!(gap < 1e-13, "{:?}: {got:?} against {expected:?}", eq.form);
            }
        }
    }
}

/// `--form` reaches the command: each form's text says how it was derived, and `--form` with
/// another `--emit` is a usage error.
#[test]
fn the_form_is_chosen_on_the_command_line() {
    let pendulum = "examples/pendulum.lsd";
    for (form, words) in [
        ("kane", "Kane's equations"),
        ("newton-euler", "recursive Newton-Euler form"),
    ] {
        let (code, stdout, _) =
            crate::common::lsdc(&["compile", "--emit", "equations", "--form", form, pendulum]);
        assert_eq!(code, 0);
        assert!(stdout.contains(words), "{form}: {stdout}");
        assert!(stdout.contains("M[1,1] = "), "{stdout}");
    }
    let (code, _, stderr) =
        crate::common::lsdc(&["compile", "--emit", "notation", "--form", "kane", pendulum]);
    assert_eq!(code, 2, "{stderr}");
    // The level of vectors and matrices: the free bodies' blocks and Ψ, no scalar entry.
    let (code, stdout, _) = crate::common::lsdc(&[
        "compile",
        "--emit",
        "equations",
        "--level",
        "vector",
        pendulum,
    ]);
    assert_eq!(code, 0);
    assert!(
        stdout.contains("M(p) = &t(Psi(p)) &* MMassMax &* Psi(p) ;"),
        "{stdout}"
    );
    assert!(!stdout.contains("M[1,1]"), "{stdout}");
    let (code, _, _) = crate::common::lsdc(&[
        "compile",
        "--emit",
        "equations",
        "--level",
        "vector",
        "--format",
        "maple",
        pendulum,
    ]);
    assert_eq!(code, 2);
}
