//! Topology and kinematics against independent oracles: the thesis's numbering of the satellite,
//! the Delta ISIR88 poses computed in closed form (fixture `tests/fixtures/delta.json`, made by
//! `bench/delta_reference.py`), analytic Jacobians against finite differences, and numbering
//! invariants on random mechanisms.

use std::path::PathBuf;

use lsdc::driver::{compile_files, compile_text};
use lsdc::elab::mechanism::Mechanism;
use lsdc::elab::value::BodyRef;
use lsdc::kinematics::assembly::{assemble, AssemblyOptions};
use lsdc::kinematics::closure::closure;
use lsdc::kinematics::eval::UnknownValues;
use lsdc::kinematics::forward::forward;
use lsdc::kinematics::initial_coordinates;
use lsdc::kinematics::model::{self, KinematicModel};
use lsdc::load::LoadOptions;
use lsdc::spatial;
use lsdc::studies::analysis;
use lsdc::topology;
use proptest::prelude::*;

fn options() -> LoadOptions {
    LoadOptions {
        library_dirs: Vec::new(),
        use_environment: false,
        scene: None,
    }
}

fn mechanism(path: &str) -> Mechanism {
    let compilation = compile_files(&[PathBuf::from(path)], &options()).expect("readable");
    assert!(
        !compilation.has_errors(),
        "{path}: {:?}",
        compilation.diagnostics
    );
    compilation.mechanism.expect("elaborates")
}

fn kinematic_model(m: &Mechanism) -> KinematicModel {
    let topology = topology::build(m).expect("connected");
    model::build(m, topology, UnknownValues::new()).expect("numeric geometry")
}

fn body_number(m: &Mechanism, model: &KinematicModel, name: &str) -> usize {
    let index = m
        .bodies
        .iter()
        .position(|b| b.name.as_deref() == Some(name))
        .expect("body exists");
    model
        .topology
        .number(BodyRef::Body(lsdc::elab::value::BodyId(index as u32)))
}

fn coordinate_index(model: &KinematicModel, name: &str) -> usize {
    model
        .coordinate_names()
        .iter()
        .position(|n| n == name)
        .unwrap_or_else(|| panic!("no coordinate {name}"))
}

#[test]
fn satellite_numbering_follows_the_thesis() {
    let m = mechanism("examples/satellite.lsd");
    let report = analysis::tree(&m).expect("tree");
    let names: Vec<&str> = report.bodies.iter().map(|b| b.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "satellite",
            "bras_primaire",
            "bras_secondaire",
            "reflecteur"
        ]
    );
    let parents: Vec<usize> = report.bodies.iter().map(|b| b.parent).collect();
    assert_eq!(parents, [0, 1, 2, 3]);
    assert!(report.complementary.is_empty());
    assert_eq!(report.mobility.expect("tree mobility").mobility, 9);
    let kinds: Vec<String> = report
        .bodies
        .iter()
        .map(|b| format!("{:?}", b.link.joint.as_ref().expect("analysed").kind))
        .collect();
    assert_eq!(kinds, ["Free", "Revolute", "Prismatic", "Revolute"]);
}

fn fixture() -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string("tests/fixtures/delta.json").expect("fixture"))
        .expect("json")
}

fn vector(value: &serde_json::Value) -> Vec<f64> {
    value
        .as_array()
        .expect("array")
        .iter()
        .map(|x| x.as_f64().expect("number"))
        .collect()
}

/// Assembles with the given coordinates held, moving them in small steps from the program's
/// own assembled configuration so the mechanism stays on the same assembly branch.
fn assemble_with(model: &KinematicModel, m: &Mechanism, held: &[(&str, f64)]) -> Vec<f64> {
    let (start, mut fixed) = initial_coordinates(m, model).expect("initial values");
    let options = AssemblyOptions::default();
    let mut q = assemble(model, &start, &fixed, &options)
        .expect("the program's configuration assembles")
        .q;
    let indices: Vec<usize> = held
        .iter()
        .map(|(name, _)| coordinate_index(model, name))
        .collect();
    let from: Vec<f64> = indices.iter().map(|&i| q[i]).collect();
    for &i in &indices {
        fixed[i] = true;
    }
    let steps = 20;
    for step in 1..=steps {
        let t = step as f64 / steps as f64;
        for (k, &i) in indices.iter().enumerate() {
            q[i] = from[k] + t * (held[k].1 - from[k]);
        }
        q = assemble(model, &q, &fixed, &options).expect("assembles").q;
    }
    q
}

#[test]
fn delta_forward_kinematics_matches_the_closed_form() {
    let fixture = fixture();
    for path in [
        "examples/delta_isir88_reduced.lsd",
        "examples/delta_isir88.lsd",
    ] {
        let m = mechanism(path);
        let model = kinematic_model(&m);
        let nacelle = body_number(&m, &model, "nacelle");
        for row in fixture["forward"].as_array().expect("rows") {
            let alpha = vector(&row["alpha"]);
            let expected = vector(&row["position"]);
            let held = [("A1.q", alpha[0]), ("A2.q", alpha[1]), ("A3.q", alpha[2])];
            let q = assemble_with(&model, &m, &held);
            let position = forward(&model, &q).expect("evaluates").poses[nacelle]
                .translation
                .vector;
            for k in 0..3 {
                assert!(
                    (position[k] - expected[k]).abs() < 1e-9,
                    "{path} α={alpha:?}: {position:?} vs {expected:?}"
                );
            }
        }
    }
}

#[test]
fn delta_inverse_kinematics_matches_the_closed_form() {
    let fixture = fixture();
    let m = mechanism("examples/delta_isir88_ik.lsd");
    let model = kinematic_model(&m);
    for row in fixture["inverse"].as_array().expect("rows") {
        let p = vector(&row["position"]);
        let expected = vector(&row["alpha"]);
        let held = [
            ("position.x", p[0]),
            ("position.y", p[1]),
            ("position.z", p[2]),
        ];
        let q = assemble_with(&model, &m, &held);
        for (k, name) in ["A1.q", "A2.q", "A3.q"].iter().enumerate() {
            let alpha = q[coordinate_index(&model, name)];
            // 1e-9 m at the arm's 0.2 m length is 5e-9 rad.
            assert!(
                (alpha - expected[k]).abs() < 5e-9,
                "P={p:?} {name}: {alpha} vs {}",
                expected[k]
            );
        }
    }
}

#[test]
fn delta_mobility_counts_rod_spins_as_internal() {
    let full = analysis::tree(&mechanism("examples/delta_isir88.lsd")).expect("tree");
    assert_eq!((full.bodies.len(), full.complementary.len()), (10, 5));
    let mobility = full.mobility.expect("computed");
    assert_eq!(
        (mobility.tree_dof, mobility.rank, mobility.mobility),
        (24, 15, 9)
    );
    assert_eq!(mobility.internal.len(), 6);
    for &(body, ways) in &mobility.internal {
        assert_eq!(ways, 1);
        assert!(
            full.bodies[body - 1].name.starts_with("rod"),
            "{}",
            full.bodies[body - 1].name
        );
    }
    let reduced = analysis::tree(&mechanism("examples/delta_isir88_reduced.lsd")).expect("tree");
    assert_eq!((reduced.bodies.len(), reduced.complementary.len()), (7, 2));
    assert_eq!(reduced.mobility.expect("computed").mobility, 3);
}

/// Central differences of the closure residual and of body poses against the analytic Jacobians.
/// The closure's rows leave out the coordinates above each loop's last common ancestor (on both
/// of its bodies' paths to earth): such a coordinate turns the whole loop, its position error r
/// with it, so that the differences there are ω × r in the position rows and zero in the
/// rotation rows, added here to the analytic Jacobian.
fn check_jacobians(model: &KinematicModel, q: &[f64]) {
    let h = 1e-6;
    let analytic = closure(model, q).expect("evaluates");
    let mut analytic_jacobian = analytic.jacobian.dense();
    let configuration = &analytic.configuration;
    for (k, joint) in model.complementary().iter().enumerate() {
        let target_path = configuration.path_columns(joint.second_body);
        let position_error = analytic.residual.fixed_rows::<3>(6 * k + 3).into_owned();
        for c in configuration.path_columns(joint.first_body) {
            if target_path.binary_search(&c).is_ok() {
                let turning = spatial::angular(&configuration.column(c)).cross(&position_error);
                analytic_jacobian
                    .fixed_view_mut::<3, 1>(6 * k + 3, c)
                    .copy_from(&turning);
            }
        }
    }
    for c in 0..model.coordinate_count {
        let (mut plus, mut minus) = (q.to_vec(), q.to_vec());
        plus[c] += h;
        minus[c] -= h;
        let (rp, rm) = (
            closure(model, &plus).expect(""),
            closure(model, &minus).expect(""),
        );
        let numeric = (&rp.residual - &rm.residual) / (2.0 * h);
        let difference = (&numeric - analytic_jacobian.column(c)).amax();
        assert!(
            difference < 1e-6 * (1.0 + numeric.amax()),
            "closure column {c}: {difference}"
        );
        for body in 1..=model.topology.body_count() {
            let (xp, xm) = (rp.configuration.poses[body], rm.configuration.poses[body]);
            let x = analytic.configuration.poses[body];
            // World angular velocity from the rotation difference, and the origin's velocity.
            let omega = (xp.rotation * xm.rotation.inverse()).scaled_axis() / (2.0 * h);
            let velocity = (xp.translation.vector - xm.translation.vector) / (2.0 * h);
            let twist = spatial::Twist::from_column_slice(
                analytic.configuration.jacobian(body).column(c).as_slice(),
            );
            let expected_velocity = spatial::point_velocity(&twist, &x.translation.vector);
            assert!(
                (omega - spatial::angular(&twist)).amax() < 1e-6,
                "body {body} column {c} angular"
            );
            assert!(
                (velocity - expected_velocity).amax() < 1e-6,
                "body {body} column {c} linear"
            );
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

    #[test]
    fn analytic_jacobians_match_finite_differences(example in 0usize..4, seed in prop::collection::vec(-3.0f64..3.0, 40)) {
        let path = ["examples/delta_isir88.lsd", "examples/delta_isir88_reduced.lsd", "examples/delta_isir88_ik.lsd", "examples/satellite_numeric.lsd"][example];
        let m = mechanism(path);
        let model = kinematic_model(&m);
        let q: Vec<f64> = (0..model.coordinate_count).map(|i| seed[i % seed.len()]).collect();
        // Near a half turn of a loop's relative rotation its error, 2 - |s| along s / |s|
        // (`kinematics::closure`), takes its direction from a vanishing skew part s: a
        // round-off of s is magnified by 2 / |s| in the residual, and central differences at
        // h = 1e-6 measure that, not the Jacobian (|s| = 5e-5 gave 4e-12 of noise in the
        // residual, 2e-6 in the difference, while h = 1e-4 agreed to 1.4e-8). Such
        // configurations, far from closed, are left out: |s| below 1e-2.
        let residual = closure(&model, &q).expect("evaluates").residual;
        let loops = residual.len() / 6;
        prop_assume!((0..loops).all(|k| residual.rows(6 * k, 3).norm() < 2.0 - 1e-2));
        check_jacobians(&model, &q);
    }

    #[test]
    fn numbering_invariants_hold_on_random_mechanisms(
        parents in prop::collection::vec(any::<prop::sample::Index>(), 1..25),
        extra in prop::collection::vec((any::<prop::sample::Index>(), any::<prop::sample::Index>()), 0..10),
    ) {
        // Body k joins a random earlier body (or earth) so all are connected; extra joins close loops.
        let n = parents.len();
        let mut text = String::new();
        for k in 1..=n {
            text += &format!("let b{k} = body end;\n");
        }
        let name = |i: usize| if i == 0 { "earth".to_string() } else { format!("b{i}") };
        let mut joins = Vec::new();
        for (k, p) in parents.iter().enumerate() {
            joins.push((p.index(k + 1), k + 1));
        }
        for (a, b) in &extra {
            let (a, b) = (a.index(n + 1), b.index(n + 1));
            if a != b {
                joins.push((a, b));
            }
        }
        for (a, b) in &joins {
            text += &format!("join {} and {} with link(q) dof = q || [0,0,1] end;\n", name(*a), name(*b));
        }
        let compilation = compile_text("random.lsd", &text, None, &options());
        let m = compilation.mechanism.expect("elaborates");
        let t = topology::build(&m).expect("connected");
        prop_assert_eq!(t.body_count(), n);
        prop_assert_eq!(t.complementary.len(), joins.len() - n);
        for (j, link) in t.principal.iter().enumerate() {
            prop_assert_eq!(link.child, j + 1);
            prop_assert_eq!(link.number, j + 1);
            prop_assert!(link.parent < link.child);
        }
        // Breadth-first: parents appear in non-decreasing order.
        for pair in t.principal.windows(2) {
            prop_assert!(pair[0].parent <= pair[1].parent);
        }
        for (k, link) in t.complementary.iter().enumerate() {
            prop_assert_eq!(link.number, n + 1 + k);
        }
    }
}

#[test]
fn joints_are_classified_with_their_degrees_of_constraint() {
    // Papegay 1992, §1.2.2 and notes §9.4: revolute 5/1, prismatic 5/1, helical 5/1, weld 6/0,
    // universal 4/2, cylindrical 4/2, spherical 3/3, planar 3/3, planar translation 4/2, free 0/6.
    let text = "import joints;\nlet a = body end;\n\
        join earth and a with weld;\n\
        join earth and a with revolute([0,0,1]);\n\
        join earth and a with prismatic([1,1,0]);\n\
        join earth and a with helical([0,0,1], 0.01);\n\
        join earth and a with cylindrical([0,1,0]);\n\
        join earth and a with universal([1,0,0], [0,1,0]);\n\
        join earth and a with spherical;\n\
        join earth and a with planar;\n\
        join earth and a with link(x, y) dof = [x, y, 0] end;\n\
        join earth and a with free;\n\
        join earth and a with link(a, b) dof1 = b || [1,0,0], dof2 = [0,a,0] end;\n\
        join earth and a with link(x) dof = [x, x, 0] end;\n";
    let compilation = compile_text("joints.lsd", text, None, &options());
    let m = compilation.mechanism.expect("elaborates");
    let expected = [
        ("Weld", 0),
        ("Revolute", 1),
        ("Prismatic", 1),
        ("Helical", 1),
        ("Cylindrical", 2),
        ("Universal", 2),
        ("Spherical", 3),
        ("Planar", 3),
        ("Translational", 2),
        ("Free", 6),
        ("General", 2),
        ("Prismatic", 1),
    ];
    for (k, (kind, dof)) in expected.iter().enumerate() {
        let join = lsdc::elab::value::JoinId(k as u32);
        let joint = model::link_only(&m, join, &UnknownValues::new()).expect("numeric");
        let analysis = lsdc::kinematics::joint::analyse(&joint).expect("analysed");
        assert_eq!(
            (format!("{:?}", analysis.kind).as_str(), analysis.dof),
            (*kind, *dof),
            "join {}",
            k + 1
        );
        assert_eq!(analysis.constraint, 6 - dof);
    }
}

#[test]
fn tree_and_assembly_use_given_values() {
    let text =
        "import joints;\nlet L = ?s;\nlet a = body end; let b = body end; let c = body end;\n\
        join earth and a with revolute([0,0,1]) as j1;\n\
        join [L,0,0] ++ 1 @ a and b with revolute([0,0,1]) as j2;\n\
        join [3,0,0] ++ 1 @ earth and c with revolute([0,0,1]) as j3;\n\
        join [2.5,0,0] ++ 1 @ b and [2,0,0] ++ 1 @ c with revolute([0,0,1]) as j4;\n\
        given L = 1;\ninitial j1.q = 1, j2.q = -0.8, j3.q = 1.6, j4.q = 0.5;\n";
    let m = compile_text("given.lsd", text, None, &options())
        .mechanism
        .expect("elaborates");
    let report = analysis::tree(&m).expect("tree");
    assert_eq!(report.mobility.expect("computed with L = 1").mobility, 1);
}

/// The spatial twist, in the first frame, of a moving pose: ω from Ṙ Rᵀ, and the velocity of
/// the point at the origin, ṗ − ω × p; Ṗ by central differences of `pose(t)` at t = 0.
fn twist_by_differences(pose: impl Fn(f64) -> lsdc::spatial::Pose) -> lsdc::spatial::Twist {
    let h = 1e-6;
    let (plus, minus, here) = (pose(h), pose(-h), pose(0.0));
    let rotation = |p: &lsdc::spatial::Pose| *p.rotation.to_rotation_matrix().matrix();
    let r_dot = (rotation(&plus) - rotation(&minus)) / (2.0 * h);
    let w = r_dot * rotation(&here).transpose();
    let omega = nalgebra::Vector3::new(w[(2, 1)], w[(0, 2)], w[(1, 0)]);
    let p_dot = (plus.translation.vector - minus.translation.vector) / (2.0 * h);
    spatial::twist(omega, p_dot - omega.cross(&here.translation.vector))
}

/// The compiled dof chains against finite differences, on every example's joints and on chains
/// whose parameters are nonlinear in their coordinates, at random coordinates and rates: the
/// velocity (the subspace times the rates) against the pose's, the bias against the velocity's
/// change along the rates, and the velocity's derivative along a random direction.
#[test]
fn compiled_chains_match_finite_differences() {
    let mut files: Vec<PathBuf> = std::fs::read_dir("examples")
        .expect("examples")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "lsd"))
        .collect();
    files.sort();
    let mut mechanisms: Vec<(String, Mechanism)> = files
        .iter()
        .filter_map(|file| {
            let compilation = compile_files(std::slice::from_ref(file), &options()).ok()?;
            let m = compilation
                .mechanism
                .filter(|_| compilation.diagnostics.is_empty())?;
            Some((file.display().to_string(), m))
        })
        .collect();
    let nonlinear = "let L = 0.7 ;
        let b1 = body end ;
        let b2 = body end ;
        join earth and b1.frame with link(x, y)
          dof1 = [L * sin(x) * y, x ^ 2 / (1 + y ^ 2), sqrt(2 + cos(y))],
          dof2 = (x * y + atan2(y, 2 + x)) || [0, 1, 1],
          dof3 = [exp(y / 3), 0, log(3 + x)]
        end ;
        join b1.frame and b2.frame with link(a)
          dof1 = (a + 0.3 * a ^ 3) || [1, 0, 0], dof2 = [tan(a / 3), 0, abs(a) + 1]
        end ;";
    let compilation = compile_text("nonlinear.lsd", nonlinear, None, &options());
    assert!(!compilation.has_errors(), "{:?}", compilation.diagnostics);
    mechanisms.push((
        "nonlinear".to_string(),
        compilation.mechanism.expect("elaborates"),
    ));
    let mut seed = 12345u64;
    let mut random = move |scale: f64| {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        scale * (2.0 * ((seed >> 11) as f64 / (1u64 << 53) as f64) - 1.0)
    };
    let mut compared = 0;
    for (name, m) in mechanisms {
        let Ok(topology) = topology::build(&m) else {
            continue;
        };
        let Ok(unknowns) = lsdc::kinematics::unknowns::given_values(&m) else {
            continue;
        };
        let Ok(model) = model::build(&m, topology, unknowns) else {
            continue;
        };
        for joint in &model.joints {
            let n = joint.coordinate_count();
            for _ in 0..5 {
                let q: Vec<f64> = (0..n).map(|_| random(1.2)).collect();
                let v: Vec<f64> = (0..n).map(|_| random(2.0)).collect();
                let d: Vec<f64> = (0..n).map(|_| random(1.0)).collect();
                let moved = |along: &[f64], t: f64| -> Vec<f64> {
                    q.iter().zip(along).map(|(q, a)| q + t * a).collect()
                };
                let motion = |q: &[f64]| joint.chain_motion(q, Some(&v)).expect("evaluates");
                let here = motion(&q);
                let close =
                    |what: &str, exact: &lsdc::spatial::Twist, fd: &lsdc::spatial::Twist| {
                        let scale = exact.norm().max(1.0);
                        assert!(
                            (exact - fd).norm() < 1e-6 * scale,
                            "{name}, {}, {what}: {exact} vs {fd}",
                            joint.name
                        );
                    };
                let pose = |t: f64| motion(&moved(&v, t)).pose;
                close("velocity", &here.velocity, &twist_by_differences(pose));
                let h = 1e-6;
                let change = |along: &[f64]| {
                    (motion(&moved(along, h)).velocity - motion(&moved(along, -h)).velocity)
                        / (2.0 * h)
                };
                close("bias", &here.bias, &change(&v));
                let derivative = joint.velocity_derivative(&q, &v, &d).expect("evaluates");
                close("velocity derivative", &derivative, &change(&d));
                compared += 1;
            }
        }
    }
    assert!(compared > 100, "{compared}");
}
