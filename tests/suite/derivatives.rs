//! The analytical derivatives of RNEA, ABA and CRBA (`rnea_derivatives`, `aba_derivatives`,
//! `crba_derivatives`) against central differences of the algorithms themselves, on random
//! trees (revolute, prismatic, spherical, free and welded joints, geared rotors, mimics), on the
//! examples without loops and on the UR5, Panda and Talos of `tests/fixtures/urdf`; and, exact to
//! round-off, against an independent algorithm: ½ vᵀ (∂M/∂q_j) v is the derivative of the
//! kinetic energy that the variational integrator computes on its own (`derivatives`); and
//! against an identity of Lagrangian mechanics, ∂τ/∂v + (∂τ/∂v)ᵀ = 2 Ṁ, in coordinates of
//! the joints' own.
//!
//! Positions move in the joints' tangent spaces (`Model::retract`: a quaternion along its
//! rotation), as the derivatives are defined. The measure of a derivative matrix is
//! max |analytic − differences| / max(1, max |analytic|); central differences of step 1e-6 are
//! good to about 1e-9 of that, the acceptance is 1e-6.

use std::path::PathBuf;

use lsdc::driver::{compile_files, compile_text};
use lsdc::dynamics::algorithms::aba_derivatives::AbaDerivatives;
use lsdc::dynamics::algorithms::crba_derivatives::mass_derivatives;
use lsdc::dynamics::algorithms::rnea_derivatives::{check_supported, RneaDerivatives};
use lsdc::dynamics::algorithms::{aba, crba, rnea, Data};
use lsdc::dynamics::model::Model;
use lsdc::load::urdf::{import_urdf, ImportOptions};
use lsdc::load::LoadOptions;
use lsdc::prepare::{prepare, Settings};
use lsdc::spatial::Force;
use nalgebra::{DMatrix, DVector};
use proptest::prelude::*;

use crate::common::example_paths;
use crate::common::trees::featured_tree_program;
use crate::dynamics::model_of;

const STEP: f64 = 1e-6;
const TOLERANCE: f64 = 1e-6;

fn options() -> LoadOptions {
    LoadOptions {
        library_dirs: Vec::new(),
        use_environment: false,
        scene: None,
    }
}

/// A state, accelerations, generalised forces and external forces from the numbers `numbers`.
pub(crate) struct Point {
    pub q: Vec<f64>,
    pub v: Vec<f64>,
    pub a: Vec<f64>,
    pub tau: Vec<f64>,
    pub external: Vec<Force>,
}

pub(crate) fn point(model: &Model, numbers: &[f64]) -> Point {
    let value = |k: usize| numbers[k % numbers.len()];
    let n = model.declared_count;
    let coordinates: Vec<f64> = (0..n).map(|i| value(3 * i + 1)).collect();
    let rates: Vec<f64> = (0..n).map(|i| value(5 * i + 2)).collect();
    let (q, v) = model
        .state_from_declared(&coordinates, &rates)
        .expect("state");
    Point {
        q,
        v,
        a: (0..model.nv).map(|i| value(11 * i + 4)).collect(),
        tau: (0..model.nv).map(|i| value(7 * i + 3)).collect(),
        external: (0..=model.body_count())
            .map(|i| Force::from_fn(|r, _| value(13 * i + r) * 0.3))
            .collect(),
    }
}

/// Central differences of `f` along each velocity's direction of the positions (in the
/// joints' tangent spaces) and of the velocities.
fn differences(
    model: &Model,
    p: &Point,
    mut f: impl FnMut(&[f64], &[f64]) -> DVector<f64>,
) -> (DMatrix<f64>, DMatrix<f64>) {
    let nv = model.nv;
    let (mut by_q, mut by_v) = (DMatrix::zeros(nv, nv), DMatrix::zeros(nv, nv));
    for j in 0..nv {
        let mut step = vec![0.0; nv];
        let (mut plus, mut minus) = (p.q.clone(), p.q.clone());
        step[j] = STEP;
        model.retract(&mut plus, &step);
        step[j] = -STEP;
        model.retract(&mut minus, &step);
        let column = (f(&plus, &p.v) - f(&minus, &p.v)) / (2.0 * STEP);
        by_q.set_column(j, &column);
        let (mut faster, mut slower) = (p.v.clone(), p.v.clone());
        faster[j] += STEP;
        slower[j] -= STEP;
        let column = (f(&p.q, &faster) - f(&p.q, &slower)) / (2.0 * STEP);
        by_v.set_column(j, &column);
    }
    (by_q, by_v)
}

/// max |analytic − reference| / max(1, max |analytic|).
pub(crate) fn mismatch(analytic: &DMatrix<f64>, reference: &DMatrix<f64>) -> f64 {
    let scale = analytic.amax().max(1.0);
    (analytic - reference).amax() / scale
}

/// The derivatives of RNEA and ABA at `p` against central differences; the worst measure.
fn check_against_differences(model: &Model, p: &Point, what: &str) -> f64 {
    let mut data = Data::new(model);
    let mut inverse = RneaDerivatives::new(model);
    inverse
        .compute(model, &mut data, &p.q, &p.v, &p.a, &p.external)
        .unwrap_or_else(|e| panic!("{what}: {e}"));
    let tau = rnea(model, &mut data, &p.q, &p.v, &p.a, &p.external).expect("rnea");
    assert!(
        (&inverse.tau - &tau).amax() <= 1e-12 * tau.amax().max(1.0),
        "{what}: the derivatives' τ {} is not RNEA's {}",
        inverse.tau,
        tau
    );
    let (by_q, by_v) = differences(model, p, |q, v| {
        rnea(model, &mut Data::new(model), q, v, &p.a, &p.external).expect("rnea")
    });
    let rnea_q = mismatch(&inverse.dtau_dq, &by_q);
    let rnea_v = mismatch(&inverse.dtau_dv, &by_v);

    let mut forward = AbaDerivatives::new(model);
    forward
        .compute(model, &mut data, &p.q, &p.v, &p.tau, &p.external)
        .unwrap_or_else(|e| panic!("{what}: {e}"));
    let (by_q, by_v) = differences(model, p, |q, v| {
        aba(model, &mut Data::new(model), q, v, &p.tau, &p.external).expect("aba")
    });
    let aba_q = mismatch(&forward.dacceleration_dq, &by_q);
    let aba_v = mismatch(&forward.dacceleration_dv, &by_v);
    let mass = crba(model, &mut data, &p.q).expect("crba");
    let identity = DMatrix::<f64>::identity(model.nv, model.nv);
    let aba_tau = mismatch(&(&forward.mass_inverse * &mass), &identity);

    let mass_q = mass_matrix_mismatch(model, p);
    let worst = [rnea_q, rnea_v, aba_q, aba_v, aba_tau, mass_q]
        .into_iter()
        .fold(0.0, f64::max);
    assert!(
        worst <= TOLERANCE,
        "{what}: ∂τ/∂q {rnea_q:e}, ∂τ/∂v {rnea_v:e}, ∂q̈/∂q {aba_q:e}, ∂q̈/∂v {aba_v:e}, \
         M⁻¹M − 1 {aba_tau:e}, ∂M/∂q {mass_q:e} > {TOLERANCE:e}"
    );
    worst
}

/// ∂M/∂q against central differences of CRBA: the worst measure over the velocities.
fn mass_matrix_mismatch(model: &Model, p: &Point) -> f64 {
    let mut data = Data::new(model);
    let derivatives = mass_derivatives(model, &mut data, &p.q).expect("derivatives");
    let mut worst = 0.0f64;
    for (j, derivative) in derivatives.iter().enumerate() {
        let mut step = vec![0.0; model.nv];
        let (mut plus, mut minus) = (p.q.clone(), p.q.clone());
        step[j] = STEP;
        model.retract(&mut plus, &step);
        step[j] = -STEP;
        model.retract(&mut minus, &step);
        let difference = (crba(model, &mut data, &plus).expect("crba")
            - crba(model, &mut data, &minus).expect("crba"))
            / (2.0 * STEP);
        worst = worst.max(mismatch(derivative, &difference));
    }
    worst
}

/// Joint kinds of `common::trees` the derivatives cover: revolute, prismatic (with the link
/// features when written as links), spherical, free, weld.
pub(crate) const COVERED_KINDS: [usize; 5] = [0, 1, 5, 7, 10];

/// Link features of `common::trees` the derivatives cover: none, a geared rotor, a mimic, both.
pub(crate) const COVERED_FEATURES: [usize; 4] = [0, 1, 4, 5];

/// A random tree of the derivatives' tests, the program and the numbers its values and its
/// states are drawn from: up to 12 joints of `kinds` with link features among `features`
/// (indices of `common::trees::JOINTS` and bits of `featured_tree_program`).
pub(crate) fn random_tree(
    kinds: &[usize],
    features: &[usize],
) -> impl Strategy<Value = (String, Vec<f64>)> {
    (
        prop::collection::vec(any::<prop::sample::Index>(), 1..12),
        prop::collection::vec(prop::sample::select(kinds.to_vec()), 12),
        prop::collection::vec(prop::sample::select(features.to_vec()), 12),
        prop::collection::vec(-1.5f64..1.5, 64),
    )
        .prop_map(|(parents, kinds, features, numbers)| {
            let parents: Vec<usize> = (parents.iter().enumerate())
                .map(|(i, p)| p.index(i + 1))
                .collect();
            let text = featured_tree_program(&parents, &kinds, &features, &numbers);
            (text, numbers)
        })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 32, ..ProptestConfig::default() })]

    #[test]
    fn derivatives_agree_with_central_differences_on_random_trees(
        (text, numbers) in random_tree(&COVERED_KINDS, &COVERED_FEATURES),
    ) {
        let model = model_of(&text);
        let p = point(&model, &numbers);
        check_against_differences(&model, &p, &text);
    }

    /// ½ vᵀ (∂M/∂q_j) v against the kinetic energy's gradient of the variational integrator, an
    /// independent algorithm (without rotors, which it leaves out): exact to round-off.
    #[test]
    fn mass_matrix_derivatives_give_the_kinetic_energy_gradient(
        (text, numbers) in random_tree(&COVERED_KINDS, &[0]),
    ) {
        let model = model_of(&text);
        let p = point(&model, &numbers);
        let mut data = Data::new(&model);
        let derivatives = mass_derivatives(&model, &mut data, &p.q).expect("derivatives");
        let gradient = lsdc::dynamics::derivatives::kinetic_energy_gradient(&model, &mut data, &p.q, &p.v)
            .expect("gradient");
        let v = DVector::from_column_slice(&p.v);
        let scale = gradient.amax().max(1.0);
        for (j, derivative) in derivatives.iter().enumerate() {
            let half = 0.5 * v.dot(&(derivative * &v));
            prop_assert!((half - gradient[j]).abs() <= 1e-12 * scale,
                "velocity {j}: ½ vᵀ ∂M/∂q v = {half}, ∂T/∂q = {}\n{text}", gradient[j]);
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 32, ..ProptestConfig::default() })]

    /// In coordinates of their own (revolute and prismatic joints, welds, geared rotors), the
    /// velocity terms of inverse dynamics are Christoffel's, c(q, v) = Γ(v, v), so that
    /// ∂τ/∂v + (∂τ/∂v)ᵀ = 2 Ṁ = 2 Σ_j (∂M/∂q_j) v_j: the velocity derivatives against the
    /// mass matrix's position derivatives, two separate parts of the algorithm, exact to
    /// round-off.
    #[test]
    fn velocity_derivatives_give_the_mass_matrix_rate(
        (text, numbers) in random_tree(&[0, 1, 10], &[0, 1]),
    ) {
        let model = model_of(&text);
        let p = point(&model, &numbers);
        let mut data = Data::new(&model);
        let mut inverse = RneaDerivatives::new(&model);
        inverse.compute(&model, &mut data, &p.q, &p.v, &p.a, &p.external).expect("derivatives");
        let derivatives = mass_derivatives(&model, &mut data, &p.q).expect("derivatives");
        let rate = derivatives
            .iter()
            .zip(&p.v)
            .fold(DMatrix::zeros(model.nv, model.nv), |sum, (d, vj)| sum + d * *vj);
        let symmetric = &inverse.dtau_dv + inverse.dtau_dv.transpose();
        let measure = mismatch(&symmetric, &(rate * 2.0));
        prop_assert!(measure <= 1e-12, "{measure:e}\n{text}");
    }
}

/// A covered model prepared from a file, or why it is left out.
pub(crate) fn example_model(path: &PathBuf) -> Result<Model, String> {
    let compilation =
        compile_files(std::slice::from_ref(path), &options()).map_err(|e| e.to_string())?;
    if compilation.has_errors() {
        return Err("does not compile".into());
    }
    let mechanism = compilation.mechanism.ok_or("does not elaborate")?;
    let prepared = prepare(&mechanism, &[], &Settings::default())
        .map_err(|_| "cannot be prepared without values".to_string())?;
    let model = prepared.model;
    if model.has_loops() || model.has_contacts() {
        return Err("has loops or contacts".into());
    }
    check_supported(&model).map_err(|e| e.to_string())?;
    Ok(model)
}

#[test]
fn derivatives_agree_with_central_differences_on_the_examples() {
    let numbers: Vec<f64> = (0..64)
        .map(|k| ((k * 37 % 61) as f64 / 20.0) - 1.5)
        .collect();
    let (mut covered, mut left_out) = (Vec::new(), Vec::new());
    for path in example_paths() {
        match example_model(&path) {
            Ok(model) => {
                let p = point(&model, &numbers);
                let worst = check_against_differences(&model, &p, &path.display().to_string());
                covered.push(format!("{} ({worst:.1e})", path.display()));
            }
            Err(reason) => left_out.push(format!("{}: {reason}", path.display())),
        }
    }
    eprintln!("covered: {covered:#?}\nleft out: {left_out:#?}");
    assert!(
        covered.len() >= 10,
        "only {} examples covered: {left_out:#?}",
        covered.len()
    );
}

/// The robots of `tests/fixtures/urdf`: UR5 and Panda on fixed bases, Talos on a free one and
/// on a fixed one (its legs and upper body then separate trees, whose velocities the breadth-first
/// numbering interleaves and the mass matrix's factor puts in depth-first order).
#[test]
fn derivatives_agree_with_central_differences_on_ur5_panda_and_talos() {
    let numbers: Vec<f64> = (0..64)
        .map(|k| ((k * 29 % 53) as f64 / 18.0) - 1.4)
        .collect();
    let robots = [
        ("ur5", false),
        ("panda", false),
        ("talos_reduced", true),
        ("talos_reduced", false),
    ];
    for (robot, floating) in robots {
        let model = robot_model(robot, floating);
        let p = point(&model, &numbers);
        let worst = check_against_differences(&model, &p, robot);
        eprintln!("{robot}: nv = {}, worst {worst:.2e}", model.nv);
    }
}

/// Forward dynamics' derivatives keep scratch from call to call (the solves' rows, which the
/// pass back overwrites on the tree's pattern only and the solves leave dense): one
/// `AbaDerivatives` taken through several states gives, bit for bit, what a fresh one gives at
/// each, on Talos's three separate trees and on UR5's chain.
#[test]
fn forward_derivatives_do_not_depend_on_the_states_before() {
    for (robot, floating) in [("talos_reduced", false), ("ur5", false)] {
        let model = robot_model(robot, floating);
        let mut reused = AbaDerivatives::new(&model);
        let mut data = Data::new(&model);
        for shift in 0..4 {
            let numbers: Vec<f64> = (0..64)
                .map(|k| (((k + 7 * shift) * 29 % 53) as f64 / 18.0) - 1.4)
                .collect();
            let p = point(&model, &numbers);
            let mut fresh = AbaDerivatives::new(&model);
            for derivatives in [&mut reused, &mut fresh] {
                (derivatives.compute(&model, &mut data, &p.q, &p.v, &p.tau, &p.external))
                    .unwrap_or_else(|e| panic!("{robot}: {e}"));
            }
            let outputs = [
                (
                    "q̈",
                    reused.acceleration.as_slice(),
                    fresh.acceleration.as_slice(),
                ),
                (
                    "∂q̈/∂q",
                    reused.dacceleration_dq.as_slice(),
                    fresh.dacceleration_dq.as_slice(),
                ),
                (
                    "∂q̈/∂v",
                    reused.dacceleration_dv.as_slice(),
                    fresh.dacceleration_dv.as_slice(),
                ),
                (
                    "M⁻¹",
                    reused.mass_inverse.as_slice(),
                    fresh.mass_inverse.as_slice(),
                ),
            ];
            for (what, after_others, alone) in outputs {
                assert_eq!(after_others, alone, "{robot}, state {shift}: {what}");
            }
        }
    }
}

pub fn robot_model(robot: &str, floating: bool) -> Model {
    let urdf = format!("tests/fixtures/urdf/{robot}.urdf");
    let compilation = if floating {
        let xml = std::fs::read_to_string(&urdf).expect("urdf");
        let import = ImportOptions {
            floating_base: true,
            gravity: true,
        };
        let imported = import_urdf(&urdf, &xml, &import).expect("imports");
        compile_text(&format!("{robot}.lsd"), &imported.text, None, &options())
    } else {
        compile_files(&[PathBuf::from(&urdf)], &options()).expect("loads")
    };
    let mechanism = compilation.mechanism.expect("compiles");
    prepare(&mechanism, &[], &Settings::default())
        .expect("prepares")
        .model
}

/// `lsdc eval --derivatives` on the pendulum against the closed forms of τ = m g l sin q + J q̈
/// (m = 1.2 kg, l = 0.5 m, J = 0.4 kg·m²): ∂τ/∂q = m g l cos q, ∂q̈/∂q = −m g l cos q / J,
/// ∂q̈/∂τ = 1/J; and a joint the derivatives do not cover, named in the state's errors.
#[test]
fn eval_prints_the_derivatives_and_names_a_joint_they_do_not_cover() {
    let states = std::env::temp_dir().join(format!("derivatives-{}.json", std::process::id()));
    std::fs::write(&states, r#"[{"q": [0.5], "v": [1], "a": [0], "tau": [0]}]"#).expect("write");
    let states = states.to_str().expect("path");
    let (code, out, err) = crate::common::lsdc(&[
        "eval",
        "examples/pendulum.lsd",
        "--states",
        states,
        "--derivatives",
    ]);
    assert_eq!(code, 0, "{err}");
    let json: serde_json::Value = serde_json::from_str(&out).expect("json");
    let derivatives = &json["states"][0]["derivatives"];
    let weight = 1.2 * 9.81 * 0.5 * 0.5f64.cos();
    let close = |value: &serde_json::Value, expected: f64| {
        let x = value.as_f64().expect("number");
        assert!((x - expected).abs() < 1e-12, "{x} against {expected}");
    };
    close(&derivatives["rnea"]["dq"][0][0], weight);
    close(&derivatives["aba"]["dq"][0][0], -weight / 0.4);
    close(&derivatives["aba"]["dtau"][0][0], 1.0 / 0.4);
    close(&derivatives["crba"][0][0][0], 0.0);
    assert_eq!(derivatives["efforts_held"], false);

    let program = std::env::temp_dir().join(format!("cylinder-{}.lsd", std::process::id()));
    let text = "import joints;\n\
        let b = body mass = 1, iframe = [0.1, 0, 0] ++ 1, inertia = [1, 1, 1] end;\n\
        join earth and b with cylindrical([0, 0, 1]) as rod;\n";
    std::fs::write(&program, text).expect("write");
    std::fs::write(
        states,
        r#"[{"q": [0.5, 0.1], "v": [1, 0], "a": [0, 0], "tau": [0, 0]}]"#,
    )
    .expect("write");
    let (code, out, err) = crate::common::lsdc(&[
        "eval",
        program.to_str().expect("path"),
        "--states",
        states,
        "--derivatives",
    ]);
    assert_eq!(code, 0, "{err}");
    let json: serde_json::Value = serde_json::from_str(&out).expect("json");
    let message = json["states"][0]["errors"]["derivatives"]
        .as_str()
        .unwrap_or_else(|| panic!("no error: {out}"));
    assert!(message.contains("`rod`"), "{message}");
}
