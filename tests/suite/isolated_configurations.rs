//! A closed configuration that the loops hold still though they allow motions to first order
//! (a chain stretched to the full length it spans) is refused before a run (E0830), and
//! mechanisms that move from singular configurations are not. Oracles: the triangle inequality
//! (bars a, b, c on a ground d with b = a + c + d close only on one line, and close with room
//! to move when d is longer: a joint of the tree held off the line, the others free, does not
//! close), and, for the mechanisms that move, a second algorithm: the dimension of the closed
//! set near the configuration, sampled by assembling from small perturbations
//! (`kinematics::mobility`; it cannot tell an isolated configuration, where the samples come
//! back only to assembly's tolerance, from one that moves).

use lsdc::driver::compile_text;
use lsdc::kinematics::assembly::{assemble, AssemblyOptions};
use lsdc::kinematics::initial_coordinates;
use lsdc::kinematics::isolation::{isolated, isolated_at_second_order, moves_in_its_plane};
use lsdc::kinematics::mobility::mobility;
use lsdc::kinematics::model::{self, KinematicModel};
use lsdc::kinematics::unknowns::given_values;
use lsdc::load::LoadOptions;

use crate::common::programs::{example_text, refusal_codes};
use crate::long_chains::chains::{ladder_program, necklace_program};

/// A planar chain of bars of `lengths` from the earth's origin to the point `ground` along x,
/// closed there, written as the `loops` fuzz target writes it: revolutes about z, uniform
/// bars under gravity, the first crank thrown at −5 rad/s.
fn chain(lengths: &[f64], ground: f64, angles: &[f64]) -> String {
    let mut text = String::from(
        "import joints ;\nimport gravity ;\nlet bar(l) = body mass = l, iframe = [l / 2, 0, 0] ++ 1, inertia = [1e-4 * l, l * l * l / 12, l * l * l / 12] end ;\n",
    );
    for (k, length) in lengths.iter().enumerate() {
        text += &format!(
            "let b{k} = bar({length}) ;\napply weight_in(b{k}, [0, -9.81, 0]) on b{k}.iframe ;\n"
        );
    }
    text += "join earth and b0 with revolute([0, 0, 1]) as j0 ;\n";
    for k in 1..lengths.len() {
        text += &format!(
            "join [{}, 0, 0] ++ 1 @ b{} and b{k} with revolute([0, 0, 1]) as j{k} ;\n",
            lengths[k - 1],
            k - 1
        );
    }
    let last = lengths.len() - 1;
    text += &format!(
        "join [{}, 0, 0] ++ 1 @ b{last} and [{ground}, 0, 0] ++ 1 @ earth with revolute([0, 0, 1]) as jn ;\n",
        lengths[last]
    );
    let initial: Vec<String> = (angles.iter().enumerate())
        .map(|(k, a)| format!("j{k}.q = {a}"))
        .collect();
    text + &format!("initial {} ;\ninitial j0.q' = -5 ;\n", initial.join(", "))
}

/// The fuzz target's four-bar (`fuzz/seeds/loops/four-bar-stretched`): bars 0.2, 1.666 and
/// 0.2 m on a ground of `ground`; 0.2 + 1.266 + 0.2 = 1.666.
fn four_bar(ground: f64) -> String {
    chain(&[0.2, 1.666, 0.2], ground, &[-2.15, -3.2, -3.2])
}

/// The fuzz target's six-bar (`fuzz/seeds/loops/six-bar-stretched`), its bars adding up to
/// its ground of 1.266 m.
fn six_bar() -> String {
    chain(&[0.222, 0.2, 0.2, 0.222, 0.2, 0.222], 1.266, &[-3.2; 6])
}

/// The model of a program and the configuration assembled from its `initial` values.
fn assembled(text: &str) -> (KinematicModel, Vec<f64>) {
    let options = LoadOptions {
        library_dirs: vec!["examples/lib".into()],
        use_environment: false,
        scene: None,
    };
    let compilation = compile_text("chain.lsd", text, None, &options);
    assert!(!compilation.has_errors(), "{:?}", compilation.diagnostics);
    let mechanism = compilation.mechanism.expect("elaborates");
    let topology = lsdc::topology::build(&mechanism).expect("connected");
    let values = given_values(&mechanism).expect("values");
    let model = model::build(&mechanism, topology, values).expect("numeric geometry");
    let (start, fixed) = initial_coordinates(&mechanism, &model).expect("initial values");
    let q = assemble(&model, &start, &fixed, &AssemblyOptions::default())
        .expect("assembles")
        .q;
    (model, q)
}

#[test]
fn a_chain_stretched_to_the_length_it_spans_is_refused_before_a_run() {
    for (what, text) in [("four-bar", four_bar(1.266)), ("six-bar", six_bar())] {
        // Before the refusal, dopri5 spent its 10⁶ steps (38 and 82 s of CPU) on these.
        assert_eq!(refusal_codes(&text), ["E0830"], "{what}");
        let (model, q) = assembled(&text);
        let found = isolated(&model, &q).expect("evaluates");
        let found = found.unwrap_or_else(|| panic!("{what}: no certificate of isolation"));
        let ranks = mobility(&model, &q).expect("evaluates");
        assert_eq!(found.first_order, ranks.first_order_mobility, "{what}");
        assert!(found.first_order > 0, "{what}");
        assert!(found.margin > 1e-2, "{what}: margin {}", found.margin);
        // Every bar is on the x axis.
        let configuration = lsdc::kinematics::forward::forward(&model, &q).expect("evaluates");
        for pose in &configuration.poses {
            let y = pose.translation.vector.y;
            assert!(y.abs() < 1e-6, "{what}: a bar off the line, y = {y}");
        }
        // The triangle inequality: a chain that spans its full length closes only straight, so
        // no joint of the tree turned off the line, either way, by 1 or 10 mrad, closes.
        for i in 0..model.tree_coordinate_count() {
            for change in [-1e-2, -1e-3, 1e-3, 1e-2] {
                assert!(
                    closes_with(&model, &q, i, change).is_none(),
                    "{what}: closes with {} moved by {change}",
                    model.coordinate_names()[i]
                );
            }
        }
    }
}

/// The closed configuration with coordinate `i` held at its value in `q` moved by `change`,
/// the others free, if there is one.
fn closes_with(model: &KinematicModel, q: &[f64], i: usize, change: f64) -> Option<Vec<f64>> {
    let mut start = q.to_vec();
    start[i] += change;
    let mut fixed = vec![false; q.len()];
    fixed[i] = true;
    let assembled = assemble(model, &start, &fixed, &AssemblyOptions::default()).ok()?;
    Some(assembled.q)
}

#[test]
fn a_chain_with_room_to_move_is_not_refused() {
    // Ground 10 mm, 1 µm and 1 nm longer than the stretched chain spans: the loop closes off
    // the line and moves (by about √(2 · slack / 0.2 m) radians at the last).
    for ground in [1.276, 1.266001, 1.266000001] {
        let text = four_bar(ground);
        assert!(refusal_codes(&text).is_empty(), "ground {ground}");
        let (model, q) = assembled(&text);
        assert!(
            isolated(&model, &q).expect("evaluates").is_none(),
            "ground {ground}"
        );
        // The crank turns on a little, one way or the other, with the loop closed.
        let turned = [-1e-5, 1e-5].map(|change| closes_with(&model, &q, 0, change));
        assert!(turned.iter().any(Option::is_some), "ground {ground}: stuck");
    }
}

/// Mechanisms that start singular, or whose loops act at second order, and move: none is
/// isolated, and the sampled closed set agrees that each moves.
#[test]
fn mechanisms_that_move_from_singular_configurations_are_not_isolated() {
    let slider_crank_at_dead_centre = example_text(
        "slider_crank",
        &[(
            "crank.q = 1.0, coupler.q = -1.3 guess, slider.q = 3.4 guess, pin.q = 0.3 guess",
            "crank.q = 0 fixed, coupler.q = 0.1 guess, slider.q = 3.4 guess, pin.q = 0.1 guess",
        )],
    );
    let cases = [
        // One constraint acts at second order only, everywhere (first-order mobility 4, 3).
        ("maille1", example_text("maille1", &[])),
        ("maille2", example_text("maille2", &[])),
        // Two branches cross at the start; on each the loop moves, nothing bends.
        ("saliere", example_text("saliere", &[])),
        (
            "slider-crank at its dead centre",
            slider_crank_at_dead_centre,
        ),
        ("bennett", example_text("hard/bennett", &[])),
        ("bricard", example_text("hard/bricard", &[])),
        ("squeezer", example_text("hard/squeezer", &[])),
        (
            "four-bar held flat",
            std::fs::read_to_string("tests/golden/branch_singular.lsd").expect("readable"),
        ),
        (
            "Peaucellier from zeros",
            std::fs::read_to_string("tests/golden/branch_folded_linkage.lsd").expect("readable"),
        ),
    ];
    for (what, text) in cases {
        let (model, q) = assembled(&text);
        assert!(
            isolated(&model, &q).expect("evaluates").is_none(),
            "{what} taken for isolated"
        );
        let sampled = mobility(&model, &q).expect("evaluates");
        assert!(sampled.mobility > 0, "{what}: {sampled:?}");
    }
}

/// A planar mechanism whose in-plane rows are independent at a closed configuration moves
/// there (`moves_in_its_plane`, the implicit function theorem) and is not differentiated at
/// second order; the second-order test it is spared (`isolated_at_second_order`) agrees on
/// each, and where the rows are dependent (a chain stretched to the length it spans, a
/// four-bar held flat) the shortcut does not apply and both tests are the same one.
#[test]
fn the_planar_first_order_decision_agrees_with_the_second_order_test() {
    // Each with whether to sample its closed set (1 µm from the stretched line, the samples'
    // steps of 1e-3 would leave the neighbourhood the rank speaks of).
    let moving = [
        ("necklace of 4", necklace_program(4), true),
        ("necklace of 10", necklace_program(10), true),
        ("necklace of 40", necklace_program(40), false),
        ("ladder of 5", ladder_program(5), true),
        ("four-bar with 10 mm to spare", four_bar(1.276), true),
        ("four-bar with 1 µm to spare", four_bar(1.266001), false),
        ("four-bar example", example_text("four_bar", &[]), true),
    ];
    for (what, text, sample) in &moving {
        let (model, q) = assembled(text);
        assert!(moves_in_its_plane(&model, &q).expect("evaluates"), "{what}");
        assert!(isolated(&model, &q).expect("evaluates").is_none(), "{what}");
        let judged = isolated_at_second_order(&model, &q).expect("evaluates");
        assert!(
            judged.is_none(),
            "{what}: isolated at second order {judged:?}"
        );
        if *sample {
            // A second algorithm: the closed set sampled near q has the rank's dimension.
            let sampled = mobility(&model, &q).expect("evaluates");
            assert!(sampled.mobility > 0, "{what}: {sampled:?}");
            assert_eq!(
                sampled.mobility, sampled.first_order_mobility,
                "{what}: {sampled:?}"
            );
        }
    }
    let singular = [
        ("four-bar stretched", four_bar(1.266)),
        ("six-bar stretched", six_bar()),
        (
            "four-bar held flat",
            std::fs::read_to_string("tests/golden/branch_singular.lsd").expect("readable"),
        ),
    ];
    for (what, text) in &singular {
        let (model, q) = assembled(text);
        assert!(
            !moves_in_its_plane(&model, &q).expect("evaluates"),
            "{what}"
        );
        let (fast, full) = (isolated(&model, &q), isolated_at_second_order(&model, &q));
        let (fast, full) = (fast.expect("evaluates"), full.expect("evaluates"));
        assert_eq!(fast.is_some(), full.is_some(), "{what}");
        if let (Some(fast), Some(full)) = (fast, full) {
            assert_eq!(fast.first_order, full.first_order, "{what}");
            assert_eq!(fast.margin, full.margin, "{what}");
        }
    }
}
