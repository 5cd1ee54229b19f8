//! Tests of `src/testing/` (`lsdc test`): the comparison's interpolation and error measures
//! against values worked out by hand or in closed form, the manifests' located errors, and the
//! command's exit codes, `--update`, `--calibrate` and JUnit output on a small case.

use std::path::{Path, PathBuf};

use lsdc::studies::precision::Reference;
use lsdc::testing::compare::compare;
use lsdc::testing::manifest::{self, Measure};

use crate::common::lsdc;

fn table(csv: &str) -> Reference {
    Reference::from_csv(csv, "test").expect("a table")
}

/// A case of one variable `x` under this tolerance (TOML of `[[case]]`'s keys).
fn case_with(tolerance: &str) -> manifest::Case {
    let text = format!("[[case]]\nname = \"c\"\nprogram = \"p.lsd\"\n{tolerance}\n");
    let mut cases = manifest::parse(&text, Path::new("lsdtest.toml")).expect("a manifest");
    cases.remove(0)
}

#[test]
fn interpolation_between_rows_is_cubic_where_the_rate_is_a_column() {
    // x = sin t with its rate cos t, every 0.1: the cubic Hermite interpolant's error is below
    // h^4/384 · max|x''''| = 2.6e-7; linear interpolation's would be h^2/8 · max|x''| = 1.25e-3.
    let mut csv = String::from("time,x,x',y\n");
    for k in 0..=20 {
        let t = 0.1 * k as f64;
        csv += &format!("{t},{},{},{}\n", t.sin(), t.cos(), t.sin());
    }
    let reference = table(&csv);
    let mut worst = [0.0_f64; 2];
    for k in 0..200 {
        let t = 0.01 * k as f64 + 0.003;
        let values = reference.at(t).expect("inside the table");
        worst[0] = worst[0].max((values[0] - t.sin()).abs());
        worst[1] = worst[1].max((values[2] - t.sin()).abs());
    }
    assert!(worst[0] < 2.6e-7, "Hermite: {worst:?}");
    assert!(worst[1] > 1e-4 && worst[1] < 1.25e-3, "linear: {worst:?}");
    assert!(reference.at(2.05).is_none(), "no value past the last row");
}

#[test]
fn each_measure_finds_its_worst_place() {
    let reference = table("time,x\n0,1\n1,2\n2,4\n");
    let run = table("time,x\n0,1.1\n1,2\n2,4.2\n");
    let errors =
        |tolerance: &str| compare(&run, &reference, &case_with(tolerance)).expect("compared");

    // max: the worst margin, at t = 0: |1.1 - 1| = 0.1 against max(0, 0.01 · 1.1) = 0.011
    // (margin 9.1), where t = 2 has 0.2 against 0.042 (margin 4.8).
    let max = &errors("relative = 0.01")[0];
    assert_eq!((max.measure, max.time), (Measure::Max, 0.0));
    assert!((max.difference - 0.1).abs() < 1e-12 && (max.allowed - 0.011).abs() < 1e-12);
    assert!(max.fails());

    // final: the last time only; an absolute tolerance of 0.25 passes it.
    let last = &errors("absolute = 0.25\nmeasure = \"final\"")[0];
    assert_eq!(last.time, 2.0);
    assert!(!last.fails() && (last.margin - 0.8).abs() < 1e-12);

    // l2: rms of (0.1, 0, 0.2) = sqrt(0.05 / 3) against 0.1 · rms of (1.1, 2, 4.2).
    let l2 = &errors("relative = 0.1\nmeasure = \"l2\"")[0];
    let rms_difference = (0.05_f64 / 3.0).sqrt();
    let rms_scale = ((1.1_f64.powi(2) + 4.0 + 4.2_f64.powi(2)) / 3.0).sqrt();
    assert!((l2.difference - rms_difference).abs() < 1e-12);
    assert!((l2.allowed - 0.1 * rms_scale).abs() < 1e-12);
    assert!(!l2.fails());
}

#[test]
fn a_run_that_stops_early_cannot_be_compared() {
    let reference = table("time,x\n0,1\n1,2\n2,4\n");
    let run = table("time,x\n0,1\n1,2\n");
    let error = compare(&run, &reference, &case_with("relative = 0.1")).expect_err("too short");
    assert!(error.contains("t = 2"), "{error}");
}

#[test]
fn manifest_errors_give_file_line_and_column() {
    let bad = [
        ("[[case]]\nname = \"a\"\nprogram = \"a.lsd\"\nrelative = -1\n", (4, 12), "≥ 0"),
        ("[[case]]\nname = \"a\"\nprogram = \"a.lsd\"\nrelativ = 1e-6\n", (4, 1), "unknown field"),
        ("[[case]]\nname = \"a\"\nprogram = \"a.lsd\"\nset = [\"x\"]\n", (4, 8), "="),
        ("[[case]]\nname = \"a\"\nprogram = \"a.lsd\"\n[[case]]\nname = \"a\"\nprogram = \"b.lsd\"\n", (4, 1), "second case"),
    ];
    for (text, place, message) in bad {
        let error = manifest::parse(text, Path::new("dir/lsdtest.toml")).expect_err(text);
        assert_eq!(error.position, Some(place), "{error}");
        assert!(
            error.to_string().starts_with("dir/lsdtest.toml:"),
            "{error}"
        );
        assert!(error.message.contains(message), "{error}");
    }
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("lsdc-test-command-{name}-{}", std::process::id()));
    // Emptied first: a folder left by an earlier run whose process had the same id would hand
    // this test its recorded references.
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temporary folder");
    dir
}

/// A folder with a manifest of one case, the pendulum example against `pendulum.csv` there.
fn pendulum_folder(name: &str, extra: &str) -> PathBuf {
    let dir = scratch(name);
    let program = std::fs::canonicalize("examples/pendulum.lsd").expect("the example");
    let text = format!(
        "[[case]]\nname = \"pendulum\"\nprogram = {:?}\nreference = \"pendulum.csv\"\nrelative = 1e-8\nabsolute = 1e-10\n{extra}",
        program.display().to_string()
    );
    std::fs::write(dir.join("lsdtest.toml"), text).expect("writes");
    dir
}

fn arg(path: &Path) -> &str {
    path.to_str().expect("utf-8")
}

#[test]
fn update_records_then_a_moved_value_fails_with_exit_1_and_junit() {
    let dir = pendulum_folder("update", "");
    let (code, stdout, stderr) = lsdc(&["test", "--update", arg(&dir)]);
    assert_eq!(code, 0, "{stderr}");
    assert!(stdout.contains("new reference, 101 rows"), "{stdout}");
    let (code, stdout, _) = lsdc(&["test", "--update", arg(&dir)]);
    assert_eq!(code, 0);
    assert!(
        stdout.contains("0 variables moved beyond their tolerance"),
        "{stdout}"
    );

    let reference = dir.join("pendulum.csv");
    let text = std::fs::read_to_string(&reference).expect("recorded");
    assert!(
        text.starts_with("# lsdc test reference: 12 significant digits\n"),
        "{text}"
    );
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    let mut cells: Vec<String> = lines[30].split(',').map(String::from).collect();
    let time = cells[0].clone();
    cells[1] = format!(
        "{:e}",
        cells[1].parse::<f64>().expect("a number") * (1.0 + 1e-3)
    );
    lines[30] = cells.join(",");
    std::fs::write(&reference, lines.join("\n")).expect("writes");

    let junit = dir.join("junit.xml");
    let (code, stdout, _) = lsdc(&["test", arg(&dir), "--junit", arg(&junit)]);
    assert_eq!(code, 1, "{stdout}");
    assert!(
        stdout.contains(&format!("worst: `swing.q` at t = {time}")),
        "{stdout}"
    );
    let xml = std::fs::read_to_string(&junit).expect("written");
    let document = roxmltree::Document::parse(&xml).expect("well-formed XML");
    let failure = (document.descendants().find(|n| n.has_tag_name("failure"))).expect("a failure");
    assert!(failure
        .attribute("message")
        .is_some_and(|m| m.contains("`swing.q`")));
    assert_eq!(document.root_element().attribute("failures"), Some("1"));

    let (code, stdout, _) = lsdc(&["test", arg(&dir), "--format", "json"]);
    let summary: serde_json::Value = serde_json::from_str(&stdout).expect("JSON");
    assert_eq!((code, summary["failed"].as_u64()), (1, Some(1)));
    assert_eq!(
        summary["cases"][0]["failed_variables"][0]["variable"],
        "swing.q"
    );
}

#[test]
fn calibrate_proposes_tolerances_the_manifest_reads() {
    let dir = pendulum_folder("calibrate", "");
    assert_eq!(lsdc(&["test", "--update", arg(&dir)]).0, 0);
    let (code, proposal, stderr) = lsdc(&["test", "--calibrate", arg(&dir)]);
    assert_eq!(code, 0, "{stderr}");
    let manifest = dir.join("lsdtest.toml");
    let text = std::fs::read_to_string(&manifest).expect("reads") + &proposal;
    let cases = manifest::parse(&text, &manifest).expect("the proposal is TOML of a manifest");
    let swing = cases[0].tolerance_of("swing.q");
    assert!(swing.absolute > 0.0 && swing.absolute < 1e-6, "{swing:?}");
    std::fs::write(&manifest, text).expect("writes");
    assert_eq!(
        lsdc(&["test", arg(&dir)]).0,
        0,
        "the run passes its proposed tolerances"
    );
    // The proposal covers the program's numbers moved by round-off: in other directions than
    // the calibration's (seeds 1 to 8) they pass, while a move of 1e-6 fails.
    assert!(proposal.contains("numbers by 1e-15 (8 runs)"), "{proposal}");
    let (code, stdout, _) = lsdc(&["test", "--perturb", "1e-15", "--seed", "9", arg(&dir)]);
    assert_eq!(code, 0, "{stdout}");
    let (code, stdout, _) = lsdc(&["test", "--perturb", "1e-6", arg(&dir)]);
    assert_eq!(code, 1, "{stdout}");
}

#[test]
fn exit_2_for_what_cannot_be_run() {
    let dir = scratch("usage");
    std::fs::write(
        dir.join("lsdtest.toml"),
        "[[case]]\nname = \"a\"\nprogram = \"a.lsd\"\nrelative = \"x\"\n",
    )
    .expect("writes");
    let (code, _, stderr) = lsdc(&["test", arg(&dir)]);
    assert_eq!(code, 2);
    assert!(stderr.contains("lsdtest.toml:4:12:"), "{stderr}");
    let (code, _, stderr) = lsdc(&["test", arg(&dir.join("absent"))]);
    assert_eq!(code, 2);
    assert!(stderr.contains("no such file or folder"), "{stderr}");
}

#[test]
fn an_expected_failure_passes_and_a_missing_one_fails() {
    let dir = scratch("expected");
    let program = std::fs::canonicalize("examples/runaway.lsd").expect("the example");
    let manifest = format!(
        "[[case]]\nname = \"stops\"\nprogram = {0:?}\nchecks = {{ expect_failure = \"the step size fell\" }}\n\n\
         [[case]]\nname = \"wrong reason\"\nprogram = {0:?}\nchecks = {{ expect_failure = \"singular\" }}\n",
        program.display().to_string()
    );
    std::fs::write(dir.join("lsdtest.toml"), manifest).expect("writes");
    let (code, stdout, _) = lsdc(&["test", arg(&dir), "-j", "1"]);
    assert_eq!(code, 1, "{stdout}");
    assert!(stdout.contains("ok    stops"), "{stdout}");
    assert!(
        stdout.contains("FAIL  wrong reason")
            && stdout.contains("expected a failure saying `singular`"),
        "{stdout}"
    );
}

#[test]
fn the_manifest_of_the_documentation_reads() {
    let commands = std::fs::read_to_string("docs/commands.md").expect("the documentation");
    let section = &commands[commands.find("### Manifests").expect("the section")..];
    let start = section.find("```toml\n").expect("a TOML block") + "```toml\n".len();
    let text = &section[start..start + section[start..].find("```").expect("its end")];
    let cases = manifest::parse(text, Path::new("lsdtest.toml")).expect("the example reads");
    let four_bar = &cases[0];
    assert_eq!(
        (four_bar.name.as_str(), four_bar.overrides.len()),
        ("four_bar", 2)
    );
    assert_eq!(four_bar.tolerance_of("crank.q").absolute, 3e-9);
    assert_eq!(four_bar.tolerance_of("crank.q").relative, 1e-6);
    assert_eq!(four_bar.tolerance_of("rocker.q'").measure, Measure::L2);
    assert_eq!(four_bar.checks.mobility, Some(1));
}

#[test]
fn update_creates_the_references_folder_and_records_what_passes_a_fine_tolerance() {
    let dir = scratch("fine");
    let program = std::fs::canonicalize("examples/pendulum.lsd").expect("the example");
    let text = format!(
        "[[case]]\nname = \"pendulum\"\nprogram = {:?}\nreference = \"expected/pendulum.csv\"\nrelative = 1e-14\nabsolute = 1e-14\n",
        program.display().to_string()
    );
    std::fs::write(dir.join("lsdtest.toml"), text).expect("writes");
    let (code, stdout, stderr) = lsdc(&["test", "--update", arg(&dir)]);
    assert_eq!(code, 0, "{stdout}{stderr}");
    let reference = dir.join("expected/pendulum.csv");
    let recorded = std::fs::read_to_string(&reference).expect("recorded in expected/");
    assert!(
        recorded.starts_with(
            "# lsdc test reference: 12 significant digits, in full where a tolerance is finer\n"
        ),
        "{recorded}"
    );
    let (code, stdout, _) = lsdc(&["test", arg(&dir)]);
    assert_eq!(code, 0, "the reference just recorded passes: {stdout}");

    // The same values rounded to 12 digits: the failure says that the rounding is the cause.
    let rounded: Vec<String> = (recorded.lines().skip(1))
        .map(|line| match line.starts_with("time") {
            true => line.to_string(),
            false => (line.split(','))
                .map(|cell| format!("{:.11e}", cell.parse::<f64>().expect("a number")))
                .collect::<Vec<_>>()
                .join(","),
        })
        .collect();
    let text = "# lsdc test reference: 12 significant digits\n".to_string() + &rounded.join("\n");
    std::fs::write(&reference, text).expect("writes");
    let (code, stdout, _) = lsdc(&["test", arg(&dir)]);
    assert_eq!(code, 1, "{stdout}");
    assert!(
        stdout.contains("no more than the reference's rounding to 12 significant digits"),
        "{stdout}"
    );
}
