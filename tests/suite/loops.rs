//! Closed-loop mechanisms of the thesis (Papegay 1992, §1.2.4, §4.2, appendix C) against the
//! reference values of `tests/fixtures/loops.json`, computed independently by
//! `bench/loops_reference.py`: the complementary links, the rank of Δ at exactly closed
//! configurations, the mobility, rank drops at singular configurations.

use std::collections::HashMap;
use std::path::PathBuf;

use lsdc::driver::compile_files;
use lsdc::elab::mechanism::Mechanism;
use lsdc::kinematics::assembly::{assemble, AssemblyOptions};
use lsdc::kinematics::closure::closure;
use lsdc::kinematics::eval::UnknownValues;
use lsdc::kinematics::initial_coordinates;
use lsdc::kinematics::mobility::{constraint_rank, mobility};
use lsdc::kinematics::model::{self, KinematicModel};
use lsdc::load::LoadOptions;
use lsdc::studies::analysis;
use lsdc::topology;

fn fixture() -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string("tests/fixtures/loops.json").expect("fixture"))
        .expect("json")
}

fn load(path: &str) -> (Mechanism, KinematicModel) {
    let options = LoadOptions {
        library_dirs: Vec::new(),
        use_environment: false,
        scene: None,
    };
    let compilation = compile_files(&[PathBuf::from(path)], &options).expect("readable");
    assert!(
        compilation.diagnostics.is_empty(),
        "{path}: {:?}",
        compilation.diagnostics
    );
    let m = compilation.mechanism.expect("elaborates");
    let t = topology::build(&m).expect("connected");
    let model = model::build(&m, t, UnknownValues::new()).expect("numeric");
    (m, model)
}

/// The fixture's named coordinates as lsdc's coordinate vector.
fn coordinates(model: &KinematicModel, named: &serde_json::Value) -> Vec<f64> {
    let named: HashMap<String, f64> = named
        .as_object()
        .expect("object")
        .iter()
        .map(|(k, v)| (k.clone(), v.as_f64().expect("number")))
        .collect();
    model
        .coordinate_names()
        .iter()
        .map(|n| *named.get(n).unwrap_or_else(|| panic!("fixture lacks {n}")))
        .collect()
}

const EXAMPLES: [&str; 7] = [
    "four_bar",
    "slider_crank",
    "planar_triangle",
    "saliere",
    "homocinetic",
    "maille1",
    "maille2",
];

#[test]
fn complementary_links_follow_the_breadth_first_split() {
    let fixture = fixture();
    for name in EXAMPLES {
        let expected = &fixture["mechanisms"][name];
        let (m, model) = load(expected["file"].as_str().expect("file"));
        let cut: Vec<String> = model
            .complementary()
            .iter()
            .map(|j| j.name.clone())
            .collect();
        let expected_cut: Vec<String> = expected["complementary"]
            .as_array()
            .expect("list")
            .iter()
            .map(|v| v.as_str().expect("name").to_string())
            .collect();
        assert_eq!(cut, expected_cut, "{name}");
        assert_eq!(
            model.tree_coordinate_count() as u64,
            expected["tree_dof"].as_u64().expect("dof"),
            "{name}"
        );
        let _ = m;
    }
}

#[test]
fn rank_of_delta_at_exactly_closed_configurations() {
    let fixture = fixture();
    for name in EXAMPLES {
        let expected = &fixture["mechanisms"][name];
        let (_, model) = load(expected["file"].as_str().expect("file"));
        let q = coordinates(&model, &expected["closed"]);
        assert!(
            closure(&model, &q).expect("evaluates").residual.amax() < 1e-12,
            "{name}: the fixture's point is closed"
        );
        let (rank, _) = constraint_rank(&model, &q).expect("rank");
        assert_eq!(
            rank as u64,
            expected["rank_delta"].as_u64().expect("rank"),
            "{name}"
        );
    }
}

#[test]
fn mobility_of_each_mechanism() {
    // Notes §9.6: four-bar 1, slider-crank 1, triangle 3, salière 1 (Grübler: -2), homocinetic
    // joint 1, maille1 3, maille2 3.
    let expected = [
        ("four_bar", 1),
        ("slider_crank", 1),
        ("planar_triangle", 3),
        ("saliere", 1),
        ("homocinetic", 1),
        ("maille1", 3),
        ("maille2", 3),
    ];
    for (name, mobility_expected) in expected {
        let (m, _) = load(&format!("examples/{name}.lsd"));
        let report = analysis::tree(&m).expect("tree");
        let mobility = report
            .mobility
            .unwrap_or_else(|| panic!("{name}: {:?}", report.mobility_unavailable));
        assert_eq!(mobility.mobility, mobility_expected, "{name}");
        assert!(
            !mobility.singular,
            "{name}: the file's configuration is not singular"
        );
    }
}

#[test]
fn meshes_have_a_constraint_acting_only_at_second_order() {
    // On the closed set of maille1 and maille2, rank(Δ) is one less than the closed set's
    // codimension: tree DOF − rank(Δ) = 4 while the closed configurations form a 3-dimensional set.
    for (name, rank) in [("maille1", 4), ("maille2", 10)] {
        let (m, _) = load(&format!("examples/{name}.lsd"));
        let mobility = analysis::tree(&m)
            .expect("tree")
            .mobility
            .expect("computed");
        assert_eq!(
            (
                mobility.rank,
                mobility.first_order_mobility,
                mobility.mobility
            ),
            (rank, 4, 3),
            "{name}"
        );
    }
}

#[test]
fn rank_drops_at_singular_configurations() {
    let fixture = fixture();
    for name in ["saliere", "maille1", "maille2"] {
        let expected = &fixture["mechanisms"][name];
        let (_, model) = load(expected["file"].as_str().expect("file"));
        let q = coordinates(&model, &expected["singular"]["coords"]);
        let report = mobility(&model, &q).expect("mobility");
        assert_eq!(
            report.rank as u64,
            expected["singular"]["rank_delta"].as_u64().expect("rank"),
            "{name}"
        );
        assert!(report.singular, "{name}: the rank drop is reported");
        assert!(report.generic_rank > report.rank, "{name}");
    }
}

#[test]
fn saliere_defeats_gruebler() {
    let (m, model) = load("examples/saliere.lsd");
    // Spatial Grübler: 6 × moving bodies − Σ degrees of constraint of the links.
    let constraints: usize = analysis::tree(&m)
        .expect("tree")
        .bodies
        .iter()
        .map(|b| b.link.joint.as_ref().expect("analysed").constraint)
        .sum::<usize>()
        + 5 * model.complementary().len();
    let gruebler = 6 * model.topology.body_count() as i64 - constraints as i64;
    assert_eq!(gruebler, -2);
    assert_eq!(
        analysis::tree(&m)
            .expect("tree")
            .mobility
            .expect("computed")
            .mobility,
        1
    );
}

#[test]
fn homocinetic_joint_turns_both_shafts_at_the_same_speed() {
    let (m, model) = load("examples/homocinetic.lsd");
    let (start, fixed) = initial_coordinates(&m, &model).expect("initial");
    let q = assemble(&model, &start, &fixed, &AssemblyOptions::default())
        .expect("assembles")
        .q;
    let jacobian = closure(&model, &q).expect("evaluates").jacobian.dense();
    // The velocity of the mechanism spans the kernel of the closure Jacobian (mobility 1); pad
    // the Jacobian to a square matrix so the SVD returns every right singular vector.
    let n = jacobian.ncols();
    let mut square = nalgebra::DMatrix::zeros(n.max(jacobian.nrows()), n);
    square.rows_mut(0, jacobian.nrows()).copy_from(&jacobian);
    let svd = square.svd(false, true);
    let v_t = svd.v_t.expect("right singular vectors");
    let smallest = (0..svd.singular_values.len())
        .min_by(|&a, &b| svd.singular_values[a].total_cmp(&svd.singular_values[b]))
        .expect("values");
    let names = model.coordinate_names();
    let rate = |n: &str| {
        v_t[(
            smallest,
            names.iter().position(|x| x == n).expect("coordinate"),
        )]
    };
    let (input, output) = (rate("l1.q"), rate("l4.q"));
    assert!(input.abs() > 0.1, "the input shaft turns");
    assert!(
        (input - output).abs() < 1e-9,
        "input {input} vs output {output}"
    );
    assert!(
        rate("l5.q").abs() < 1e-9,
        "the sliding shaft does not slide"
    );
}

#[test]
fn lsdc_assembles_every_example_from_its_initial_values() {
    for name in EXAMPLES {
        let (m, model) = load(&format!("examples/{name}.lsd"));
        let (start, fixed) = initial_coordinates(&m, &model).expect("initial");
        let assembled =
            assemble(&model, &start, &fixed, &AssemblyOptions::default()).expect("assembles");
        assert!(assembled.residual < 1e-12, "{name}: {}", assembled.residual);
    }
}
