//! lsdc's recursive algorithms on URDF robots against Pinocchio's, from the reference values of
//! `tests/fixtures/pinocchio/*.json` (written by `bench/pinocchio_fixtures.py`, which has the
//! conventions; Pinocchio itself is not needed here).
//!
//! Each fixture names a URDF file copied from example-robot-data, whether its base floats, the
//! names of lsdc's positions and velocities, and states (q, v, a, tau) with Pinocchio's RNEA,
//! CRBA, ABA and body poses, all in lsdc's layout. The robot is loaded as every command loads a
//! `.urdf` file (fixed base), or through `import_urdf` with a floating base, and evaluated by the
//! code behind `lsdc eval`.
//!
//! The measure is the script's: for one quantity at one state,
//! `max |lsdc - pinocchio| / max(1, max |pinocchio|)` over its entries, at most 1e-10.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use lsdc::diag::render;
use lsdc::driver::{compile_files, compile_text, Compilation};
use lsdc::load::urdf::{import_urdf, ImportOptions};
use lsdc::load::LoadOptions;
use lsdc::prepare::{prepare, Prepared, Settings};
use lsdc::studies::batch::{evaluate_states, Evaluation, StateInput};
use serde_json::Value;

const TOLERANCE: f64 = 1e-10;
const FIXTURES: &str = "tests/fixtures/pinocchio";

/// The robots with a fixture, each checked by its own test below.
const ROBOTS: &[&str] = &[
    "double_pendulum",
    "kinova",
    "panda",
    "solo12",
    "talos_reduced",
    "ur5",
];

fn fixture(robot: &str) -> Value {
    let path = Path::new(FIXTURES).join(format!("{robot}.json"));
    let text = std::fs::read_to_string(&path)
        .unwrap_or_else(|e| panic!("cannot read `{}`: {e}", path.display()));
    serde_json::from_str(&text).unwrap_or_else(|e| panic!("`{}` is not JSON: {e}", path.display()))
}

fn numbers(value: &Value, what: &str) -> Vec<f64> {
    value
        .as_array()
        .unwrap_or_else(|| panic!("`{what}` is not a list"))
        .iter()
        .map(|x| {
            x.as_f64()
                .unwrap_or_else(|| panic!("`{what}` has an entry that is not a number: {x}"))
        })
        .collect()
}

fn strings(value: &Value, what: &str) -> Vec<String> {
    value
        .as_array()
        .unwrap_or_else(|| panic!("`{what}` is not a list"))
        .iter()
        .map(|x| {
            x.as_str()
                .unwrap_or_else(|| panic!("`{what}` has an entry that is not a string"))
                .to_string()
        })
        .collect()
}

fn checked(compilation: Compilation, robot: &str) -> Compilation {
    if compilation.has_errors() {
        panic!(
            "{robot}: the URDF does not compile:\n{}",
            render::to_text(&compilation.workspace.sources, &compilation.diagnostics)
        );
    }
    compilation
}

/// The robot as `lsdc eval` sees it: the URDF file itself, or the floating-base import.
fn load(robot: &str, fixture: &Value) -> Prepared {
    let urdf = fixture["urdf"]
        .as_str()
        .unwrap_or_else(|| panic!("{robot}: no `urdf` path"));
    let floating = fixture["floating_base"]
        .as_bool()
        .unwrap_or_else(|| panic!("{robot}: no `floating_base`"));
    let options = LoadOptions {
        library_dirs: Vec::new(),
        use_environment: false,
        scene: None,
    };
    let compilation = if floating {
        let xml = std::fs::read_to_string(urdf)
            .unwrap_or_else(|e| panic!("{robot}: cannot read `{urdf}`: {e}"));
        let imported = import_urdf(
            urdf,
            &xml,
            &ImportOptions {
                floating_base: true,
                gravity: true,
            },
        )
        .unwrap_or_else(|d| {
            panic!(
                "{robot}: the floating-base import fails: {}: {}",
                d.code, d.message
            )
        });
        compile_text(&format!("{robot}.lsd"), &imported.text, None, &options)
    } else {
        compile_files(&[PathBuf::from(urdf)], &options)
            .unwrap_or_else(|e| panic!("{robot}: cannot load `{urdf}`: {e}"))
    };
    let compilation = checked(compilation, robot);
    let mechanism = compilation
        .mechanism
        .as_ref()
        .expect("a compiled mechanism");
    prepare(mechanism, &[], &Settings::default()).unwrap_or_else(|diagnostics| {
        panic!(
            "{robot}: cannot prepare the model:\n{}",
            render::to_text(&compilation.workspace.sources, &diagnostics)
        )
    })
}

fn inputs(robot: &str, fixture: &Value) -> Vec<StateInput> {
    let states = fixture["states"]
        .as_array()
        .unwrap_or_else(|| panic!("{robot}: no `states`"));
    states
        .iter()
        .enumerate()
        .map(|(i, s)| StateInput {
            q: numbers(&s["q"], &format!("{robot} state {i} q")),
            v: Some(numbers(&s["v"], &format!("{robot} state {i} v"))),
            a: Some(numbers(&s["a"], &format!("{robot} state {i} a"))),
            tau: Some(numbers(&s["tau"], &format!("{robot} state {i} tau"))),
        })
        .collect()
}

/// Labelled entries of one quantity, the same way on both sides.
type Entries = Vec<(String, f64)>;

/// Compares one quantity; panics with the worst entry when the disagreement is too large.
fn compare(robot: &str, state: usize, quantity: &str, mine: &Entries, reference: &Entries) {
    assert_eq!(
        mine.len(),
        reference.len(),
        "{robot}, state {state}, {quantity}: lsdc has {} entries, Pinocchio {}",
        mine.len(),
        reference.len()
    );
    let scale = reference.iter().fold(1.0_f64, |m, (_, y)| m.max(y.abs()));
    let mut worst: Option<(f64, usize)> = None;
    for (k, ((label, x), (other, y))) in mine.iter().zip(reference).enumerate() {
        assert_eq!(
            label, other,
            "{robot}, state {state}, {quantity}: entries in different orders"
        );
        let d = if x.is_finite() && y.is_finite() {
            (x - y).abs() / scale
        } else {
            f64::INFINITY
        };
        if worst.is_none_or(|(w, _)| d > w) {
            worst = Some((d, k));
        }
    }
    if let Some((d, k)) = worst {
        let (label, x) = &mine[k];
        let y = reference[k].1;
        assert!(
            d <= TOLERANCE,
            "{robot}, state {state}, {quantity}, entry {label}: lsdc {x:?}, Pinocchio {y:?} \
             (|difference| / max(1, max |Pinocchio|) = {d:e} > {TOLERANCE:e})"
        );
    }
}

fn vector_entries(names: &[String], values: &[f64]) -> Entries {
    names.iter().cloned().zip(values.iter().copied()).collect()
}

fn matrix_entries(names: &[String], rows: &[Vec<f64>]) -> Entries {
    rows.iter()
        .enumerate()
        .flat_map(|(i, row)| {
            row.iter()
                .enumerate()
                .map(move |(j, &x)| (format!("[{}, {}]", names[i], names[j]), x))
        })
        .collect()
}

fn pose_entries(body: &str, translation: &[f64], rotation: &[Vec<f64>]) -> Entries {
    let mut entries: Entries = translation
        .iter()
        .enumerate()
        .map(|(k, &x)| (format!("{body}.translation[{k}]"), x))
        .collect();
    for (r, row) in rotation.iter().enumerate() {
        entries.extend(
            row.iter()
                .enumerate()
                .map(|(c, &x)| (format!("{body}.rotation[{r}][{c}]"), x)),
        );
    }
    entries
}

fn check_robot(robot: &str) {
    let fixture = fixture(robot);
    let prepared = load(robot, &fixture);
    let states = inputs(robot, &fixture);
    assert!(!states.is_empty(), "{robot}: the fixture has no states");
    let evaluation: Evaluation =
        evaluate_states(&prepared, &states).unwrap_or_else(|e| panic!("{robot}: {e}"));

    let positions = strings(&fixture["positions"], "positions");
    let velocities = strings(&fixture["velocities"], "velocities");
    assert_eq!(evaluation.positions, positions, "{robot}: lsdc's positions are not the fixture's (rerun bench/pinocchio_fixtures.py if the order changed on purpose)");
    assert_eq!(
        evaluation.velocities, velocities,
        "{robot}: lsdc's velocities are not the fixture's"
    );

    let expected_states = fixture["states"].as_array().expect("states");
    for (index, (output, expected)) in evaluation.states.iter().zip(expected_states).enumerate() {
        let rnea = output.rnea.as_ref().expect("rnea, since a is given");
        let aba = output.aba.as_ref().expect("aba, since tau is given");
        let reference_rnea = numbers(&expected["rnea"], "rnea");
        let reference_aba = numbers(&expected["aba"], "aba");
        let reference_crba: Vec<Vec<f64>> = expected["crba"]
            .as_array()
            .expect("crba rows")
            .iter()
            .map(|row| numbers(row, "crba row"))
            .collect();
        compare(
            robot,
            index,
            "rnea",
            &vector_entries(&velocities, rnea),
            &vector_entries(&velocities, &reference_rnea),
        );
        compare(
            robot,
            index,
            "crba",
            &matrix_entries(&velocities, &output.crba),
            &matrix_entries(&velocities, &reference_crba),
        );
        compare(
            robot,
            index,
            "aba",
            &vector_entries(&velocities, aba),
            &vector_entries(&velocities, &reference_aba),
        );

        let frames = expected["frames"].as_object().expect("frames by body");
        let mine: BTreeSet<&str> = output.frames.iter().map(|f| f.body.as_str()).collect();
        let theirs: BTreeSet<&str> = frames.keys().map(String::as_str).collect();
        assert_eq!(
            mine, theirs,
            "{robot}, state {index}: lsdc's bodies are not the fixture's"
        );
        let mut lsdc_poses = Entries::new();
        let mut reference_poses = Entries::new();
        for frame in &output.frames {
            let rotation: Vec<Vec<f64>> = frame.rotation.iter().map(|row| row.to_vec()).collect();
            lsdc_poses.extend(pose_entries(&frame.body, &frame.translation, &rotation));
            let pose = &frames[&frame.body];
            let translation = numbers(&pose["translation"], "translation");
            let rotation: Vec<Vec<f64>> = pose["rotation"]
                .as_array()
                .expect("rotation rows")
                .iter()
                .map(|row| numbers(row, "rotation row"))
                .collect();
            reference_poses.extend(pose_entries(&frame.body, &translation, &rotation));
        }
        compare(robot, index, "frames", &lsdc_poses, &reference_poses);
    }
}

#[test]
fn every_fixture_is_checked() {
    let mut found: Vec<String> = std::fs::read_dir(FIXTURES)
        .expect("the fixtures directory")
        .filter_map(|entry| {
            let path = entry.ok()?.path();
            (path.extension()? == "json").then(|| path.file_stem()?.to_str().map(str::to_string))?
        })
        .collect();
    found.sort();
    assert_eq!(
        found, ROBOTS,
        "each fixture of {FIXTURES} needs its test in tests/suite/pinocchio_fixtures.rs"
    );
}

#[test]
fn ur5_matches_pinocchio() {
    check_robot("ur5");
}

#[test]
fn panda_with_prismatic_fingers_matches_pinocchio() {
    check_robot("panda");
}

#[test]
fn kinova_with_continuous_joints_matches_pinocchio() {
    check_robot("kinova");
}

#[test]
fn double_pendulum_matches_pinocchio() {
    check_robot("double_pendulum");
}

#[test]
fn talos_reduced_on_a_floating_base_matches_pinocchio() {
    check_robot("talos_reduced");
}

#[test]
fn solo12_on_a_floating_base_matches_pinocchio() {
    check_robot("solo12");
}
