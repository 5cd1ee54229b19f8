//! Regression over the example mechanisms, through `lsdc test` as a user runs it: every example
//! is a case of `examples/lsdtest.toml`, simulated and compared with its reference
//! (`tests/expected/NAME.csv`) within the per-variable tolerances `lsdc test --calibrate`
//! proposed, or expected to fail where it does not simulate. After an intended change of the
//! results, `lsdc test --update examples/` re-records the references and says what moved.
//!
//! The other tests here show that these comparisons can fail: a reference value moved by 1e-3,
//! a parameter moved by 1e-6, while a parameter moved by 1e-14, or every decimal number moved by
//! 1e-15 (the size of a reordering of floating-point operations), still passes on the
//! round-off-sensitive examples.

use std::path::{Path, PathBuf};

use lsdc::testing::{self, Case, Outcome, Status};

use crate::common::lsdc;

const MANIFEST: &str = "examples/lsdtest.toml";

/// A folder of its own under the system's temporary folder.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("lsdc-regression-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temporary folder");
    dir
}

/// The case of the examples' manifest named `name`.
fn example_case(name: &str) -> Case {
    let cases = testing::load(&[PathBuf::from(MANIFEST)]).expect("the examples' manifest reads");
    (cases.into_iter().find(|c| c.name == name)).expect("a case of the examples")
}

#[test]
fn every_example_passes_lsdc_test() {
    let junit = scratch("junit").join("examples.xml");
    let junit_arg = junit.to_str().expect("utf-8");
    let (code, stdout, stderr) = lsdc(&[
        "test",
        "examples/",
        "-j",
        "2",
        "--format",
        "json",
        "--junit",
        junit_arg,
    ]);
    assert_eq!(code, 0, "{stdout}{stderr}");
    let summary: serde_json::Value = serde_json::from_str(&stdout).expect("JSON");
    let cases = summary["cases"].as_array().expect("cases");
    assert_eq!(summary["passed"].as_u64(), Some(cases.len() as u64));
    let programs: Vec<PathBuf> = (testing::load(&[PathBuf::from(MANIFEST)]).expect("reads"))
        .into_iter()
        .map(|c| c.program)
        .collect();
    for example in std::fs::read_dir("examples")
        .expect("examples")
        .map(|e| e.expect("entry").path())
    {
        if example.extension().is_some_and(|e| e == "lsd") {
            let name = example.file_name().expect("a file");
            let is_case = programs.iter().any(|p| p.file_name() == Some(name));
            assert!(is_case, "{} is no case of {MANIFEST}", example.display());
        }
    }
    let xml = std::fs::read_to_string(&junit).expect("the JUnit file is written");
    let document = roxmltree::Document::parse(&xml).expect("well-formed XML");
    let root = document.root_element();
    assert_eq!(root.tag_name().name(), "testsuites");
    assert_eq!(
        root.attribute("tests"),
        Some(cases.len().to_string().as_str())
    );
    assert_eq!(root.attribute("failures"), Some("0"));
    let testcases = root
        .descendants()
        .filter(|n| n.has_tag_name("testcase"))
        .count();
    assert_eq!(testcases, cases.len());
}

#[test]
fn a_reference_value_moved_by_1e_3_fails_with_its_variable_time_and_margin() {
    let mut case = example_case("maille1");
    let original =
        std::fs::read_to_string(case.reference.as_ref().expect("a reference")).expect("reads");
    let (row, column) = (120, 3);
    let mut lines: Vec<String> = original.lines().map(String::from).collect();
    let header = lines
        .iter()
        .position(|l| l.starts_with("time,"))
        .expect("a header");
    let variable = lines[header]
        .split(',')
        .nth(column)
        .expect("a column")
        .to_string();
    let mut cells: Vec<String> = lines[header + 1 + row]
        .split(',')
        .map(String::from)
        .collect();
    let time: f64 = cells[0].parse().expect("a time");
    let value: f64 = cells[column].parse().expect("a value");
    cells[column] = format!("{:e}", value * (1.0 + 1e-3));
    lines[header + 1 + row] = cells.join(",");
    let perturbed = scratch("moved").join("maille1.csv");
    std::fs::write(&perturbed, lines.join("\n")).expect("writes");
    case.reference = Some(perturbed);

    let outcome = testing::run_case(&case);
    assert_eq!(outcome.status, Status::Failed, "{:?}", outcome.failures);
    assert_eq!(
        outcome.failed_variables.len(),
        1,
        "{:?}",
        outcome.failed_variables
    );
    let worst = &outcome.failed_variables[0];
    assert_eq!(worst.variable, variable);
    assert_eq!(worst.time, time);
    assert!(worst.margin > 100.0, "{worst:?}");
    assert!(
        outcome.failures[0].contains(&format!("`{variable}`")),
        "{:?}",
        outcome.failures
    );
}

/// The example `name` with the text `from` of its program replaced by `to`, run as its case of
/// the examples' manifest.
fn with_change(name: &str, from: &str, to: &str) -> Case {
    let mut case = example_case(name);
    let text = std::fs::read_to_string(&case.program).expect("reads");
    assert!(text.contains(from), "{name} has `{from}`");
    let folder = scratch(&format!(
        "{name}-{}",
        to.replace(|c: char| !c.is_alphanumeric(), "_")
    ));
    copy_folder(Path::new("examples/lib"), &folder.join("lib"));
    case.program = folder.join(format!("{name}.lsd"));
    std::fs::write(&case.program, text.replace(from, to)).expect("writes");
    case
}

fn copy_folder(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).expect("a folder");
    for entry in std::fs::read_dir(from).expect("reads") {
        let path = entry.expect("entry").path();
        std::fs::copy(&path, to.join(path.file_name().expect("a file"))).expect("copies");
    }
}

/// `value` moved by a relative `change`, as a program's number.
fn moved(value: f64, change: f64) -> String {
    format!("{:?}", value * (1.0 + change))
}

/// The round-off-sensitive examples (second-order closure conditions, the full Delta) with one
/// of their parameters moved by a relative `change`: a length their tolerances were calibrated
/// against (`calibrated`), or one they were not (the driving torque of the meshes, the Delta's
/// arm length).
fn sensitive_examples(change: f64, calibrated: bool) -> Vec<Outcome> {
    let cases = match calibrated {
        true => vec![
            with_change(
                "maille1",
                "let L = 1.0 ;",
                &format!("let L = {} ;", moved(1.0, change)),
            ),
            with_change(
                "maille2",
                "let L = 1.0 ;",
                &format!("let L = {} ;", moved(1.0, change)),
            ),
            with_change(
                "delta_isir88",
                "let l2 = 0.300 ;",
                &format!("let l2 = {} ;", moved(0.3, change)),
            ),
        ],
        false => vec![
            with_change(
                "maille1",
                "driven(z, -1)",
                &format!("driven(z, {})", moved(-1.0, change)),
            ),
            with_change(
                "maille2",
                "driven(z, -1)",
                &format!("driven(z, {})", moved(-1.0, change)),
            ),
            with_change(
                "delta_isir88",
                "let l1 = 0.200 ;",
                &format!("let l1 = {} ;", moved(0.2, change)),
            ),
        ],
    };
    testing::run_all(&cases, 2).expect("threads start")
}

fn assert_all_pass(outcomes: Vec<Outcome>) {
    for outcome in outcomes {
        assert_eq!(
            outcome.status,
            Status::Passed,
            "{}: {:?}",
            outcome.name,
            outcome.failures
        );
    }
}

#[test]
fn round_off_sized_changes_pass_the_sensitive_examples() {
    assert_all_pass(sensitive_examples(1e-14, false));
}

/// Every decimal number of the round-off-sensitive examples moved by 1e-15 of itself, in
/// directions other than those `--calibrate` probed (its seeds are 1 to 8): the tolerances it
/// proposed hold.
#[test]
fn numbers_moved_by_round_off_pass_the_sensitive_examples() {
    let cases: Vec<Case> = ["maille1", "maille2", "delta_isir88"]
        .into_iter()
        .map(|name| Case {
            numbers: Some(lsdc::elab::Perturbation {
                relative: 1e-15,
                seed: 11,
            }),
            ..example_case(name)
        })
        .collect();
    assert_all_pass(testing::run_all(&cases, 2).expect("threads start"));
}

#[test]
fn a_parameter_moved_by_1e_6_fails_the_sensitive_examples() {
    for outcome in sensitive_examples(1e-6, true) {
        assert_eq!(outcome.status, Status::Failed, "{}", outcome.name);
        let worst = outcome
            .failed_variables
            .first()
            .expect("a variable beyond its tolerance");
        assert!(worst.margin > 1.0, "{}: {worst:?}", outcome.name);
    }
}
