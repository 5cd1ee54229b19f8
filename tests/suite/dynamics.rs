//! The dynamics algorithms against each other on random trees of 1 to 30 bodies with mixed
//! joints: RNEA(q, v, ABA(q, v, τ)) = τ, CRBA equal to the matrix built column by column from
//! RNEA, symmetric positive definite; with the link features of joints of one coordinate
//! (geared rotors, friction, mimics), M(q) ABA(q, v, τ) = τ − b(q, v) and CRBA equal to RNEA's
//! columns.

use lsdc::driver::compile_text;
use lsdc::dynamics::algorithms::{aba, crba, rnea, Data};
use lsdc::dynamics::model::{self, Model};
use lsdc::kinematics::eval::UnknownValues;
use lsdc::kinematics::model as kinematic_model;
use lsdc::load::LoadOptions;
use lsdc::spatial::Force;
use proptest::prelude::*;

use crate::common::trees::{featured_tree_program, tree_program};

/// The dynamic model of a tree program (also `derivatives`).
pub(crate) fn model_of(text: &str) -> Model {
    let options = LoadOptions {
        library_dirs: Vec::new(),
        use_environment: false,
        scene: None,
    };
    let compilation = compile_text("tree.lsd", text, None, &options);
    assert!(
        !compilation.has_errors(),
        "{:?}\n{text}",
        compilation.diagnostics
    );
    let mechanism = compilation.mechanism.expect("elaborates");
    let topology = lsdc::topology::build(&mechanism).expect("connected");
    let kinematics =
        kinematic_model::build(&mechanism, topology, UnknownValues::new()).expect("numeric");
    model::build(&mechanism, &kinematics).expect("dynamic model")
}

fn random_state(model: &Model, numbers: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let n = model.declared_count;
    let coordinates: Vec<f64> = (0..n)
        .map(|i| numbers[(3 * i + 1) % numbers.len()])
        .collect();
    let rates: Vec<f64> = (0..n)
        .map(|i| numbers[(5 * i + 2) % numbers.len()])
        .collect();
    model
        .state_from_declared(&coordinates, &rates)
        .expect("state")
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

    #[test]
    fn inverse_and_forward_dynamics_agree(
        parents in prop::collection::vec(any::<prop::sample::Index>(), 1..30),
        kinds in prop::collection::vec(0usize..10, 30),
        numbers in prop::collection::vec(-1.5f64..1.5, 64),
    ) {
        let parents: Vec<usize> = parents.iter().enumerate().map(|(i, p)| p.index(i + 1)).collect();
        let model = model_of(&tree_program(&parents, &kinds, &numbers));
        let mut data = Data::new(&model);
        let (q, v) = random_state(&model, &numbers);
        let tau: Vec<f64> = (0..model.nv).map(|i| numbers[(7 * i + 3) % numbers.len()]).collect();
        let external: Vec<Force> = (0..=model.body_count())
            .map(|i| Force::from_fn(|r, _| numbers[(11 * i + r) % numbers.len()] * 0.3))
            .collect();
        let acceleration = aba(&model, &mut data, &q, &v, &tau, &external).expect("regular");
        let back = rnea(&model, &mut data, &q, &v, acceleration.as_slice(), &external).expect("evaluates");
        let scale = 1.0 + tau.iter().fold(0.0f64, |m, t| m.max(t.abs()));
        for k in 0..model.nv {
            prop_assert!((back[k] - tau[k]).abs() < 1e-12 * scale * (1.0 + acceleration.amax()), "τ{k}: {} vs {}", back[k], tau[k]);
        }

        let mass = crba(&model, &mut data, &q).expect("evaluates");
        let none = vec![Force::zeros(); model.body_count() + 1];
        let zero_v = vec![0.0; model.nv];
        let bias = rnea(&model, &mut data, &q, &zero_v, &vec![0.0; model.nv], &none).expect("evaluates");
        for c in 0..model.nv {
            let mut unit = vec![0.0; model.nv];
            unit[c] = 1.0;
            let column = rnea(&model, &mut data, &q, &zero_v, &unit, &none).expect("evaluates") - &bias;
            for r in 0..model.nv {
                prop_assert!((mass[(r, c)] - column[r]).abs() < 1e-11 * (1.0 + mass.amax()), "M[{r},{c}]");
            }
        }
        prop_assert!((&mass - mass.transpose()).amax() < 1e-12 * (1.0 + mass.amax()));
        prop_assert!(mass.clone().cholesky().is_some(), "positive definite");
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

    /// Every joint kind, and on joints of one coordinate every link feature: the rotors' terms
    /// of ABA (stacked with the child) against those of CRBA (J w wᵀ) and RNEA (their torques),
    /// three separate derivations; friction and mimics are efforts and couplings of a run, which
    /// none of the three counts.
    #[test]
    fn forward_dynamics_inverts_the_mass_matrix_with_link_features(
        parents in prop::collection::vec(any::<prop::sample::Index>(), 1..16),
        kinds in prop::collection::vec(prop_oneof![3 => 0usize..3, 1 => 0usize..11], 16),
        features in prop::collection::vec(0usize..8, 16),
        numbers in prop::collection::vec(-1.5f64..1.5, 64),
    ) {
        let parents: Vec<usize> = parents.iter().enumerate().map(|(i, p)| p.index(i + 1)).collect();
        let model = model_of(&featured_tree_program(&parents, &kinds, &features, &numbers));
        let mut data = Data::new(&model);
        let (q, v) = random_state(&model, &numbers);
        let tau: Vec<f64> = (0..model.nv).map(|i| numbers[(7 * i + 3) % numbers.len()]).collect();
        let external: Vec<Force> = (0..=model.body_count())
            .map(|i| Force::from_fn(|r, _| numbers[(11 * i + r) % numbers.len()] * 0.3))
            .collect();
        let acceleration = aba(&model, &mut data, &q, &v, &tau, &external).expect("regular");
        let bias = rnea(&model, &mut data, &q, &v, &vec![0.0; model.nv], &external).expect("evaluates");
        let mass = crba(&model, &mut data, &q).expect("evaluates");
        let moved = &mass * &acceleration;
        let scale = tau.iter().chain(bias.iter()).chain(moved.iter()).fold(1.0f64, |m, x| m.max(x.abs()));
        for k in 0..model.nv {
            let wanted = tau[k] - bias[k];
            prop_assert!((moved[k] - wanted).abs() <= 1e-12 * scale, "(M a)_{k} = {} vs τ − b = {wanted}", moved[k]);
        }

        let none = vec![Force::zeros(); model.body_count() + 1];
        let zero_v = vec![0.0; model.nv];
        let gravity = rnea(&model, &mut data, &q, &zero_v, &zero_v, &none).expect("evaluates");
        for c in 0..model.nv {
            let mut unit = vec![0.0; model.nv];
            unit[c] = 1.0;
            let column = rnea(&model, &mut data, &q, &zero_v, &unit, &none).expect("evaluates") - &gravity;
            for r in 0..model.nv {
                prop_assert!((mass[(r, c)] - column[r]).abs() <= 1e-12 * (1.0 + mass.amax()), "M[{r},{c}]");
            }
        }
    }
}

fn model_of_file(path: &str) -> Model {
    model_of(&std::fs::read_to_string(path).expect("example"))
}

/// Notes §9.8: the mass matrix and Lagrange equations of the fixed-satellite subsystem, derived
/// independently with SymPy, at random states.
#[test]
fn fixed_satellite_matches_the_closed_form_equations() {
    let model = model_of_file("examples/satellite_fixed.lsd");
    let mut data = Data::new(&model);
    let (z34, mu4) = (0.5, 40.0);
    let none = vec![Force::zeros(); model.body_count() + 1];
    for sample in 0..20 {
        let s = sample as f64;
        let q = [
            0.3 + 0.7 * s.sin(),
            1.2 + 0.5 * (1.3 * s).cos(),
            -0.4 + 0.9 * (0.7 * s).sin(),
        ];
        let qd = [
            0.5 * (2.1 * s).cos(),
            -0.2 + 0.3 * s.sin(),
            0.7 * (0.3 * s).cos(),
        ];
        let qdd = [0.1 * s.cos(), -0.4 * (1.7 * s).sin(), 0.25 + 0.1 * s];
        let (q7, q8, q9) = (q[0], q[1], q[2]);
        let (s7, c9, s9) = (q7.sin(), q9.cos(), q9.sin());
        let _ = s7;
        let expected = nalgebra::Matrix3::new(
            q8 * q8 + z34 * z34 * c9 * c9,
            -z34 * c9,
            -z34 * q8 * s9,
            -z34 * c9,
            1.0,
            0.0,
            -z34 * q8 * s9,
            0.0,
            z34 * z34,
        ) * mu4;
        let mass = crba(&model, &mut data, &q).expect("evaluates");
        assert!(
            (mass.fixed_view::<3, 3>(0, 0) - expected).amax() < 1e-12 * mu4,
            "M at {q:?}:\n{mass}\n{expected}"
        );
        let (d7, d8, d9) = (qd[0], qd[1], qd[2]);
        let (a7, a8, a9) = (qdd[0], qdd[1], qdd[2]);
        let lagrange = [
            mu4 * ((q8 * q8 + z34 * z34 * c9 * c9) * a7 - z34 * c9 * a8 - z34 * q8 * s9 * a9
                + 2.0 * q8 * d7 * d8
                - 2.0 * z34 * z34 * s9 * c9 * d7 * d9
                - z34 * q8 * c9 * d9 * d9),
            mu4 * (a8 - z34 * c9 * a7 - q8 * d7 * d7 + 2.0 * z34 * s9 * d7 * d9),
            mu4 * (z34 * z34 * a9 - z34 * q8 * s9 * a7 + z34 * z34 * s9 * c9 * d7 * d7
                - 2.0 * z34 * s9 * d7 * d8),
        ];
        let tau = rnea(&model, &mut data, &q, &qd, &qdd, &none).expect("evaluates");
        for k in 0..3 {
            assert!(
                (tau[k] - lagrange[k]).abs() < 1e-11 * mu4,
                "Q{} at {q:?}: {} vs {}",
                k + 7,
                tau[k],
                lagrange[k]
            );
        }
    }
}

/// The joint bias terms against a finite difference of body velocities: with no coordinate
/// acceleration, each body's acceleration is the time derivative of its velocity along q + t·v.
#[test]
fn body_accelerations_are_derivatives_of_body_velocities() {
    let chain_joints = [0usize, 1, 2, 3, 4, 8];
    let parents = [0usize, 1, 1, 2, 4, 0, 6, 3];
    let kinds: Vec<usize> = (0..parents.len())
        .map(|i| chain_joints[i % chain_joints.len()])
        .collect();
    let numbers: Vec<f64> = (0..64).map(|i| ((i as f64) * 1.7).sin()).collect();
    let model = model_of(&tree_program(&parents, &kinds, &numbers));
    let mut data = Data::new(&model);
    let (q, v) = random_state(&model, &numbers);
    let none = vec![Force::zeros(); model.body_count() + 1];
    rnea(&model, &mut data, &q, &v, &vec![0.0; model.nv], &none).expect("evaluates");
    let accelerations = data.acceleration.clone();
    let h = 1e-6;
    let at = |t: f64, data: &mut Data| {
        let moved: Vec<f64> = q.iter().zip(&v).map(|(x, r)| x + t * r).collect();
        lsdc::dynamics::algorithms::forward_kinematics(&model, data, &moved, &v)
            .expect("evaluates");
        data.velocity.clone()
    };
    let (plus, minus) = (at(h, &mut data), at(-h, &mut data));
    for i in 1..=model.body_count() {
        let numeric = (plus[i] - minus[i]) / (2.0 * h);
        assert!(
            (numeric - accelerations[i]).amax() < 1e-6,
            "body {i}: {numeric} vs {}",
            accelerations[i]
        );
    }
}

/// ∂T/∂q at fixed velocities against central differences of the kinetic energy.
#[test]
fn kinetic_energy_gradient_matches_finite_differences() {
    let chain_joints = [0usize, 1, 2, 3, 4, 8, 10];
    let parents = [0usize, 1, 1, 2, 4, 0, 6, 3, 8];
    let kinds: Vec<usize> = (0..parents.len())
        .map(|i| chain_joints[(i + 2) % chain_joints.len()])
        .collect();
    let numbers: Vec<f64> = (0..64).map(|i| ((i as f64) * 2.3).cos()).collect();
    let model = model_of(&tree_program(&parents, &kinds, &numbers));
    let mut data = Data::new(&model);
    let (q, v) = random_state(&model, &numbers);
    let gradient = lsdc::dynamics::derivatives::kinetic_energy_gradient(&model, &mut data, &q, &v)
        .expect("chain joints");
    let energy = |q: &[f64], data: &mut Data| {
        lsdc::dynamics::algorithms::forward_kinematics(&model, data, q, &v).expect("evaluates");
        lsdc::dynamics::energy::kinetic_energy(&model, data)
    };
    let h = 1e-6;
    for k in 0..model.nv {
        let (mut plus, mut minus) = (q.clone(), q.clone());
        plus[k] += h;
        minus[k] -= h;
        let numeric = (energy(&plus, &mut data) - energy(&minus, &mut data)) / (2.0 * h);
        assert!(
            (numeric - gradient[k]).abs() < 1e-6 * (1.0 + numeric.abs()),
            "∂T/∂q{k}: {} vs {numeric}",
            gradient[k]
        );
    }
}

/// The positions q moved by ε along velocity `k` of the joint that owns it: a coordinate by ε,
/// a spherical or free joint by q · exp(ε e_k) on its group (the rotation by the body-axes
/// rotation vector, a free joint's position by ε along its body axis).
fn moved_along(model: &Model, q: &[f64], k: usize, epsilon: f64) -> Vec<f64> {
    use lsdc::dynamics::joint::JointType;
    use nalgebra::{Quaternion, UnitQuaternion, Vector3};
    let joint = model
        .joints
        .iter()
        .find(|j| (j.v_offset..j.v_offset + j.nv()).contains(&k))
        .expect("a tree velocity");
    let c = k - joint.v_offset;
    let mut moved = q.to_vec();
    let turn = |at: usize, moved: &mut Vec<f64>| {
        let start = UnitQuaternion::from_quaternion(Quaternion::new(
            q[at],
            q[at + 1],
            q[at + 2],
            q[at + 3],
        ));
        let mut axis = Vector3::zeros();
        axis[c] = epsilon;
        let end = start * UnitQuaternion::from_scaled_axis(axis);
        moved[at..at + 4].copy_from_slice(&[end.w, end.i, end.j, end.k]);
        start
    };
    match joint.kind {
        JointType::Chain => moved[joint.q_offset + c] += epsilon,
        JointType::Spherical { .. } => {
            turn(joint.q_offset, &mut moved);
        }
        JointType::Free { .. } if c < 3 => {
            turn(joint.q_offset + 3, &mut moved);
        }
        JointType::Free { .. } => {
            let o = joint.q_offset;
            let rotation = UnitQuaternion::from_quaternion(Quaternion::new(
                q[o + 3],
                q[o + 4],
                q[o + 5],
                q[o + 6],
            ));
            let mut direction = Vector3::zeros();
            direction[c - 3] = epsilon;
            let shift = rotation * direction;
            for i in 0..3 {
                moved[o + i] += shift[i];
            }
        }
    }
    moved
}

/// ∂T/∂q along the groups of spherical and free joints (left-trivialised, at fixed body
/// velocities) against central differences of the kinetic energy along q · exp(±ε e_k).
#[test]
fn kinetic_energy_gradient_on_groups_matches_finite_differences() {
    let joints = [5usize, 7, 0, 5, 1, 7, 4];
    let parents = [0usize, 1, 1, 2, 4, 0, 6, 3, 8];
    let kinds: Vec<usize> = (0..parents.len())
        .map(|i| joints[i % joints.len()])
        .collect();
    let numbers: Vec<f64> = (0..64).map(|i| ((i as f64) * 1.7).sin()).collect();
    let model = model_of(&tree_program(&parents, &kinds, &numbers));
    assert!(model.nq > model.nv, "the tree has quaternion joints");
    let mut data = Data::new(&model);
    let (q, v) = random_state(&model, &numbers);
    let gradient = lsdc::dynamics::derivatives::kinetic_energy_gradient(&model, &mut data, &q, &v)
        .expect("evaluates");
    let energy = |q: &[f64], data: &mut Data| {
        lsdc::dynamics::algorithms::forward_kinematics(&model, data, q, &v).expect("evaluates");
        lsdc::dynamics::energy::kinetic_energy(&model, data)
    };
    let h = 1e-6;
    for k in 0..model.nv {
        let plus = moved_along(&model, &q, k, h);
        let minus = moved_along(&model, &q, k, -h);
        let numeric = (energy(&plus, &mut data) - energy(&minus, &mut data)) / (2.0 * h);
        assert!(
            (numeric - gradient[k]).abs() < 1e-6 * (1.0 + numeric.abs()),
            "∂T/∂q along velocity {k}: {} vs {numeric}",
            gradient[k]
        );
    }
}

/// `lsdc eval`'s forward dynamics of the geared arm (its rotors on the base and on the upper
/// arm) at the state of issue 44, where it once ignored the rotors ([0.230, 30.46]): M a = τ − b
/// with M and b = RNEA(q, v, 0) of the same evaluation, the 2 × 2 system solved by hand.
#[test]
fn geared_arm_forward_dynamics_inverts_its_mass_matrix() {
    let prepared = crate::common::programs::prepared("geared_arm", &[]);
    let state = lsdc::api::StateInput {
        q: vec![0.3, -0.4],
        v: Some(vec![0.5, 0.2]),
        a: Some(vec![0.0, 0.0]),
        tau: Some(vec![0.0, 0.0]),
    };
    let evaluation = lsdc::api::evaluate(&prepared, &[state]).expect("evaluates");
    let output = &evaluation.states[0];
    let (m, b) = (&output.crba, output.rnea.as_ref().expect("rnea"));
    let a = output.aba.as_ref().expect("aba");
    let det = m[0][0] * m[1][1] - m[0][1] * m[1][0];
    let wanted = [
        (m[1][1] * -b[0] - m[0][1] * -b[1]) / det,
        (m[0][0] * -b[1] - m[1][0] * -b[0]) / det,
    ];
    for k in 0..2 {
        assert!(
            (a[k] - wanted[k]).abs() <= 1e-12 * wanted[k].abs().max(1e-3),
            "{a:?} vs {wanted:?}"
        );
    }
}
