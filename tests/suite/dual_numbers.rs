//! The analytical derivatives of RNEA and ABA (`rnea_derivatives`, `aba_derivatives`, after
//! Carpentier & Mansard, RSS 2018) against forward-mode automatic differentiation of the
//! algorithms themselves: RNEA and ABA are generic over their scalar, and run in dual numbers
//! (`num_dual::Dual64`, x + ε ẋ with ε² = 0) they carry the exact derivative along one
//! direction through every operation, an oracle that shares none of the analytical passes'
//! algebra and, unlike central differences, no truncation error: the two agree to round-off.
//!
//! One direction per velocity: the positions move along the joints' tangent spaces as the
//! analytical derivatives define them (`Model::retract`: a quaternion along q ⊗ (0, ε e_c)/2,
//! a free joint's position along its rotated linear velocity), seeded as q + ε ∂q/∂ε; the
//! velocities and efforts along their unit vectors. On the random trees of the central
//! differences' test (revolute, prismatic, spherical, free and welded joints, geared rotors,
//! mimics), on the examples they cover and on the UR5, Panda and Talos.
//!
//! The measure is that of the central differences' test, max |analytic − dual| / max(1,
//! max |analytic|), for each of ∂τ/∂q, ∂τ/∂v, ∂q̈/∂q, ∂q̈/∂v and ∂q̈/∂τ = M⁻¹: relative to the
//! largest entry, absolute below 1, where a derivative that vanishes (∂τ/∂v of a lone revolute
//! joint, whose velocity product Sᵀ(S q̇ ×* I S q̇) is zero) is round-off on either side.
//! Accepted at 1e-12.
//!
//! The loops' rows too (`loops::constraints_into`, generic over the scalar like the
//! recursions): their Jacobian G and their bias γ against the derivative parts of the rows
//! themselves in dual numbers, on the random four-bars and Bennett linkages of
//! `loop_properties` and on the examples with loops (`check_loop_rows`).

use lsdc::driver::compile_files;
use lsdc::dynamics::algorithms::aba_derivatives::AbaDerivatives;
use lsdc::dynamics::algorithms::rnea_derivatives::RneaDerivatives;
use lsdc::dynamics::algorithms::{aba, crba, forward_kinematics, rnea, Data};
use lsdc::dynamics::loops::{constraints, constraints_into, Constraints, Extent};
use lsdc::dynamics::model::Model;
use lsdc::prepare::{prepare, Prepared, Settings};
use lsdc::spatial::Force;
use nalgebra::{DMatrix, DVector};
use num_dual::Dual64;
use proptest::prelude::*;

use crate::common::example_paths;
use crate::common::programs::{initial_state, no_library_path};
use crate::derivatives::{
    example_model, mismatch, point, random_tree, robot_model, Point, COVERED_FEATURES,
    COVERED_KINDS,
};
use crate::dynamics::model_of;
use crate::loop_properties::{bennett, bennett_draws, four_bar, four_bar_draws};

const TOLERANCE: f64 = 1e-12;

/// x + ε dx, entry by entry.
pub(crate) fn seeded(x: &[f64], dx: &[f64]) -> Vec<Dual64> {
    x.iter().zip(dx).map(|(&x, &d)| Dual64::new(x, d)).collect()
}

/// x without derivative.
pub(crate) fn constant(x: &[f64]) -> Vec<Dual64> {
    x.iter().map(|&x| Dual64::from_re(x)).collect()
}

/// The unit vector along velocity j.
pub(crate) fn unit(n: usize, j: usize) -> Vec<f64> {
    (0..n).map(|i| if i == j { 1.0 } else { 0.0 }).collect()
}

/// ∂q/∂ε of the positions moved by ε along velocity j in the joints' tangent spaces: each
/// joint's position rate at q for that unit velocity (the first-order term of `Model::retract`).
pub(crate) fn tangent(model: &Model, q: &[f64], j: usize) -> Vec<f64> {
    position_rate(model, q, &unit(model.velocities(), j))
}

/// The positions' rate at q for the state velocities `direction`: each tree joint's, then the
/// loops' own coordinates', which move with their rates.
pub(crate) fn position_rate(model: &Model, q: &[f64], direction: &[f64]) -> Vec<f64> {
    let mut rate = vec![0.0; q.len()];
    rate[model.nq..].copy_from_slice(&direction[model.nv..]);
    for joint in &model.joints {
        let (qs, vs) = (
            joint.q_offset..joint.q_offset + joint.nq(),
            joint.v_offset..joint.v_offset + joint.nv(),
        );
        joint.position_rate(&q[qs.clone()], &direction[vs], &mut rate[qs]);
    }
    rate
}

/// The values and the derivative parts of a dual vector.
pub(crate) fn parts(x: &DVector<Dual64>) -> (DVector<f64>, DVector<f64>) {
    (x.map(|x| x.re), x.map(|x| x.eps))
}

/// The derivatives of RNEA and ABA at `p` by dual numbers, one column per velocity.
struct DualDerivatives {
    dtau_dq: DMatrix<f64>,
    dtau_dv: DMatrix<f64>,
    dacceleration_dq: DMatrix<f64>,
    dacceleration_dv: DMatrix<f64>,
    dacceleration_dtau: DMatrix<f64>,
}

/// The values of RNEA run in dual numbers against RNEA in `f64`: the same operations on the
/// values but for divisions, which `num_dual` computes as products by the reciprocal (a
/// quaternion's normalisation), so equal to round-off: 1e-14 relative. RNEA has no solve,
/// nothing to amplify a last bit.
fn same_values(dual: &DVector<f64>, plain: &DVector<f64>, what: &str, algorithm: &str) {
    let difference = (dual - plain).amax();
    assert!(
        difference <= 1e-14 * plain.amax(),
        "{what}: {algorithm} in dual numbers gives {dual}, in f64 {plain}"
    );
}

/// The accelerations of ABA run in dual numbers solve the `f64` equations of motion: ABA is a
/// solve with M, so a last bit moved by a division is amplified by M's conditioning in the
/// accelerations themselves (1.7e-14 of the largest on a random tree of 24 velocities), but
/// not in their backward error, the residual of the equations they solve (Higham, Accuracy and
/// Stability of Numerical Algorithms, 2002, §1.5 and §7.1):
/// ‖τ − RNEA(q, v, q̈)‖ ≤ 1e-14 (‖τ‖ + ‖M‖ ‖q̈‖), the bound of `same_values` on that scale.
fn solves_the_equations(model: &Model, p: &Point, accelerations: &DVector<f64>, what: &str) {
    let mut data = Data::new(model);
    let efforts = rnea(
        model,
        &mut data,
        &p.q,
        &p.v,
        accelerations.as_slice(),
        &p.external,
    )
    .expect("rnea");
    let mass = crba(model, &mut data, &p.q).expect("crba");
    let tau = DVector::from_column_slice(&p.tau);
    let residual = (&efforts - &tau).amax();
    let scale = tau.amax() + mass.abs().row_sum().amax() * accelerations.amax();
    assert!(
        residual <= 1e-14 * scale,
        "{what}: ABA in dual numbers gives {accelerations}, whose residual {residual:e} is above \
         1e-14 of {scale:e}"
    );
}

/// Runs RNEA and ABA in dual numbers along every velocity's direction of q, v and τ, checking
/// on the way that their values are those of the `f64` algorithms (`same_values`).
fn dual_derivatives(model: &Model, p: &Point, what: &str) -> DualDerivatives {
    let nv = model.nv;
    let mut data = Data::<Dual64>::with_scalar(model);
    let external: Vec<Force<Dual64>> = p.external.iter().map(|f| f.map(Dual64::from_re)).collect();
    let (q, v, a, tau) = (
        constant(&p.q),
        constant(&p.v),
        constant(&p.a),
        constant(&p.tau),
    );
    let tau_f64 = rnea(model, &mut Data::new(model), &p.q, &p.v, &p.a, &p.external).expect("rnea");
    let mut inverse = |q: &[Dual64], v: &[Dual64]| {
        let (value, derivative) =
            parts(&rnea(model, &mut data, q, v, &a, &external).expect("rnea"));
        same_values(&value, &tau_f64, what, "RNEA");
        derivative
    };
    let by = |f: &mut dyn FnMut(usize) -> DVector<f64>| {
        let mut columns = DMatrix::zeros(nv, nv);
        for j in 0..nv {
            columns.set_column(j, &f(j));
        }
        columns
    };
    let dtau_dq = by(&mut |j| inverse(&seeded(&p.q, &tangent(model, &p.q, j)), &v));
    let dtau_dv = by(&mut |j| inverse(&q, &seeded(&p.v, &unit(p.v.len(), j))));
    let mut data = Data::<Dual64>::with_scalar(model);
    let mut forward = |q: &[Dual64], v: &[Dual64], tau: &[Dual64]| {
        let accelerations = aba(model, &mut data, q, v, tau, &external).expect("aba");
        let (value, derivative) = parts(&accelerations);
        solves_the_equations(model, p, &value, what);
        derivative
    };
    DualDerivatives {
        dtau_dq,
        dtau_dv,
        dacceleration_dq: by(&mut |j| forward(&seeded(&p.q, &tangent(model, &p.q, j)), &v, &tau)),
        dacceleration_dv: by(&mut |j| forward(&q, &seeded(&p.v, &unit(p.v.len(), j)), &tau)),
        dacceleration_dtau: by(&mut |j| forward(&q, &v, &seeded(&p.tau, &unit(p.tau.len(), j)))),
    }
}

/// The analytical derivatives of RNEA and ABA at `p` against the dual numbers'; the worst
/// measure.
fn check_against_dual_numbers(model: &Model, p: &Point, what: &str) -> f64 {
    let mut data = Data::new(model);
    let mut inverse = RneaDerivatives::new(model);
    inverse
        .compute(model, &mut data, &p.q, &p.v, &p.a, &p.external)
        .unwrap_or_else(|e| panic!("{what}: {e}"));
    let mut forward = AbaDerivatives::new(model);
    forward
        .compute(model, &mut data, &p.q, &p.v, &p.tau, &p.external)
        .unwrap_or_else(|e| panic!("{what}: {e}"));
    let dual = dual_derivatives(model, p, what);
    let measures = [
        ("∂τ/∂q", mismatch(&inverse.dtau_dq, &dual.dtau_dq)),
        ("∂τ/∂v", mismatch(&inverse.dtau_dv, &dual.dtau_dv)),
        (
            "∂q̈/∂q",
            mismatch(&forward.dacceleration_dq, &dual.dacceleration_dq),
        ),
        (
            "∂q̈/∂v",
            mismatch(&forward.dacceleration_dv, &dual.dacceleration_dv),
        ),
        (
            "∂q̈/∂τ",
            mismatch(&forward.mass_inverse, &dual.dacceleration_dtau),
        ),
    ];
    let worst = measures.iter().map(|m| m.1).fold(0.0, f64::max);
    assert!(
        worst <= TOLERANCE,
        "{what}: {measures:?} above {TOLERANCE:e}"
    );
    worst
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 32, ..ProptestConfig::default() })]

    #[test]
    fn derivatives_agree_with_dual_numbers_on_random_trees(
        (text, numbers) in random_tree(&COVERED_KINDS, &COVERED_FEATURES),
    ) {
        let model = model_of(&text);
        let p = point(&model, &numbers);
        check_against_dual_numbers(&model, &p, &text);
    }
}

#[test]
fn derivatives_agree_with_dual_numbers_on_the_examples() {
    let numbers: Vec<f64> = (0..64)
        .map(|k| ((k * 37 % 61) as f64 / 20.0) - 1.5)
        .collect();
    let mut covered = Vec::new();
    for path in example_paths() {
        if let Ok(model) = example_model(&path) {
            let p = point(&model, &numbers);
            let worst = check_against_dual_numbers(&model, &p, &path.display().to_string());
            covered.push(format!("{} ({worst:.1e})", path.display()));
        }
    }
    eprintln!("covered: {covered:#?}");
    assert!(
        covered.len() >= 10,
        "only {} examples covered",
        covered.len()
    );
}

#[test]
fn derivatives_agree_with_dual_numbers_on_ur5_panda_and_talos() {
    let numbers: Vec<f64> = (0..64)
        .map(|k| ((k * 29 % 53) as f64 / 18.0) - 1.4)
        .collect();
    for (robot, floating) in [("ur5", false), ("panda", false), ("talos_reduced", true)] {
        let model = robot_model(robot, floating);
        let p = point(&model, &numbers);
        let worst = check_against_dual_numbers(&model, &p, robot);
        eprintln!("{robot}: nv = {}, worst {worst:.2e}", model.nv);
    }
}

/// A dof chain evaluated in general (a cylindrical joint: two coordinates) has its geometry
/// from the program's expressions, evaluated in `f64` only: dual numbers are refused there, with
/// an error, rather than given derivatives that miss the chain's.
#[test]
fn dual_numbers_refuse_a_general_dof_chain() {
    let model = model_of(
        "import joints;\n\
         let b = body mass = 1, iframe = [0.1, 0, 0] ++ 1, inertia = [1, 1, 1] end;\n\
         join earth and b with cylindrical([0, 0, 1]) as rod;\n",
    );
    let zero = constant(&vec![0.0; model.nv]);
    let q = constant(&vec![0.1; model.positions()]);
    let external = vec![Force::<Dual64>::zeros(); model.body_count() + 1];
    let mut data = Data::<Dual64>::with_scalar(&model);
    assert!(rnea(&model, &mut data, &q, &zero, &zero, &external).is_err());
    assert!(aba(&model, &mut data, &q, &zero, &zero, &external).is_err());
}

/// The loops' rows in dual numbers (`loops::constraints_into` generic over its scalar) against
/// the derivatives the rows carry in `f64`, at a closed configuration q: the position rows φ
/// moved along each velocity's direction change by G's column (∂φ/∂ε = G e_j, where φ = 0:
/// the rows' rotation vector and gap are the frames' relative motion at the loop point only
/// there), and the velocity rows G v moved along the motion q̇ = v at fixed v change by
/// γ = Ġ v, for v on the loops, G v = 0 (the loop point's own motion adds (ω_T − ω_E) × ṗ
/// otherwise): the given velocities less their least-squares part off the loops,
/// G⁺ G v, which takes the assembly's velocity residual (1e-12 on a random Bennett linkage)
/// out of the comparison. The measure of `mismatch`; the rows' values in dual numbers are
/// those in `f64` to 1e-14 of their scale, and the state's closure is checked first.
fn check_loop_rows(model: &Model, q: &[f64], v: &[f64], what: &str) -> f64 {
    let at = |v: &[f64]| {
        constraints(model, &mut Data::new(model), q, v, Extent::WithBias)
            .unwrap_or_else(|e| panic!("{what}: {e:?}"))
    };
    let jacobian = at(v).jacobian.dense();
    let off = jacobian
        .clone()
        .pseudo_inverse(1e-10)
        .expect("pseudo-inverse")
        * (&jacobian * DVector::from_column_slice(v));
    let v = (DVector::from_column_slice(v) - off).as_slice().to_vec();
    let rows = at(&v);
    let scale = jacobian.amax().max(1.0);
    let (closure, velocity) = (rows.residual.amax(), rows.velocity.amax());
    assert!(
        closure <= 1e-12 * scale
            && velocity <= 1e-14 * scale * DVector::from_column_slice(&v).amax().max(1.0),
        "{what}: not on the loops (position rows {closure:e}, velocity rows {velocity:e})"
    );
    let mut data = Data::<Dual64>::with_scalar(model);
    let mut dual = Constraints::<Dual64>::with_scalar(model);
    let mut rows_along = |dq: &[f64]| {
        let (q, v) = (seeded(q, dq), constant(&v));
        forward_kinematics(model, &mut data, &q, &v).expect("kinematics");
        constraints_into(model, &mut data, &q, &v, Extent::WithBias, &mut dual)
            .unwrap_or_else(|e| panic!("{what}: {e:?}"));
        let (residual, by_position) = parts(&dual.residual);
        let (_, by_motion) = parts(&dual.velocity);
        let values = dual.jacobian.dense().map(|x| x.re);
        let difference = (&values - &jacobian).amax();
        let residual_difference = (&residual - &rows.residual).amax();
        assert!(
            difference <= 1e-14 * scale && residual_difference <= 1e-14 * scale,
            "{what}: G in dual numbers {difference:e} from f64's, position rows {residual_difference:e}"
        );
        (by_position, by_motion)
    };
    let n = model.velocities();
    let mut by_position = DMatrix::zeros(jacobian.nrows(), n);
    for j in 0..n {
        by_position.set_column(j, &rows_along(&tangent(model, q, j)).0);
    }
    let motion = rows_along(&position_rate(model, q, &v)).1;
    let bias = DMatrix::from_column_slice(rows.bias.len(), 1, rows.bias.as_slice());
    let measures = [
        ("G", mismatch(&jacobian, &by_position)),
        (
            "γ",
            mismatch(
                &bias,
                &DMatrix::from_column_slice(motion.len(), 1, motion.as_slice()),
            ),
        ),
    ];
    let worst = measures.iter().map(|m| m.1).fold(0.0, f64::max);
    eprintln!("{what}: {measures:?}; position rows {closure:e}, velocity rows {velocity:e}");
    assert!(
        worst <= TOLERANCE,
        "{what}: {measures:?} above {TOLERANCE:e}"
    );
    worst
}

/// The positions and velocities of a prepared mechanism's assembled initial state.
pub(crate) fn assembled(prepared: &Prepared) -> (Vec<f64>, Vec<f64>) {
    let model = &prepared.model;
    let y = initial_state(prepared);
    let (q, v) = y.split_at(model.positions());
    (q.to_vec(), v.to_vec())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 16, failure_persistence: None, ..ProptestConfig::default() })]

    /// The random four-bars and Bennett linkages of `loop_properties`, closed by construction.
    #[test]
    fn loop_rows_agree_with_dual_numbers_on_random_four_bars((l, crank, rate) in four_bar_draws()) {
        let Some(p) = four_bar(l, crank, rate) else {
            return Err(TestCaseError::reject("does not close at this crank angle"));
        };
        let (q, v) = assembled(&p);
        check_loop_rows(&p.model, &q, &v, &format!("four-bar {l:?} at {crank}"));
    }

    #[test]
    fn loop_rows_agree_with_dual_numbers_on_random_bennett_linkages(
        (a1, alpha1, alpha2, crank, rate) in bennett_draws(),
    ) {
        let p = bennett(a1, alpha1, alpha2, crank, rate);
        let (q, v) = assembled(&p);
        check_loop_rows(&p.model, &q, &v, &format!("Bennett {a1}, {alpha1}, {alpha2}, at {crank}"));
    }
}

/// The examples with loops, at their assembled initial states: the four-bars, the slider-crank,
/// the Delta's full model (ball joints), the hard linkages (Bricard's, Bennett's, a row of ten
/// four-bars). A loop closed by, or a tree joint with, a dof chain evaluated in general is
/// evaluated in `f64` only and refused in dual numbers (`DynamicsScalar`): left out, named
/// with the reason (the second list).
pub(crate) fn loop_examples() -> (Vec<(String, Prepared)>, Vec<String>) {
    let (mut covered, mut left_out) = (Vec::new(), Vec::new());
    for (name, prepared) in loop_programs() {
        let (q, v) = assembled(&prepared);
        let model = &prepared.model;
        let mut data = Data::<Dual64>::with_scalar(model);
        let mut dual = Constraints::<Dual64>::with_scalar(model);
        let (dq, dv) = (constant(&q), constant(&v));
        let refused = forward_kinematics(model, &mut data, &dq, &dv).and_then(|()| {
            constraints_into(model, &mut data, &dq, &dv, Extent::WithBias, &mut dual)
        });
        match refused {
            Err(e) => left_out.push(format!("{name}: {e:?}")),
            Ok(()) => covered.push((name, prepared)),
        }
    }
    (covered, left_out)
}

/// Every example with loops that compiles and prepares (the examples' folder and the hard
/// linkages), named by its path.
pub(crate) fn loop_programs() -> Vec<(String, Prepared)> {
    let hard = [
        "bennett",
        "bricard",
        "four_bar_row_10",
        "squeezer",
        "watt_six_bar",
    ];
    let paths = example_paths().into_iter().chain(
        hard.iter()
            .map(|name| format!("examples/hard/{name}.lsd").into()),
    );
    let mut programs = Vec::new();
    for path in paths {
        let name = path.display().to_string();
        let Ok(compilation) = compile_files(std::slice::from_ref(&path), &no_library_path()) else {
            continue;
        };
        if compilation.has_errors() {
            continue;
        }
        let Some(mechanism) = compilation.mechanism else {
            continue;
        };
        let Ok(prepared) = prepare(&mechanism, &[], &Settings::default()) else {
            continue;
        };
        if prepared.model.has_loops() {
            programs.push((name, prepared));
        }
    }
    programs
}

#[test]
fn loop_rows_agree_with_dual_numbers_on_the_examples() {
    let (examples, left_out) = loop_examples();
    let mut covered = Vec::new();
    for (name, prepared) in &examples {
        let (q, v) = assembled(prepared);
        let worst = check_loop_rows(&prepared.model, &q, &v, name);
        covered.push(format!("{name} ({worst:.1e})"));
    }
    eprintln!("covered: {covered:#?}\nleft out: {left_out:#?}");
    assert!(
        covered.len() >= 8,
        "only {} covered: {left_out:#?}",
        covered.len()
    );
}
