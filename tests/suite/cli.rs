//! The `lsdc` binary: exit codes, summary, JSON diagnostics, library search path.

use crate::common::lsdc;
use std::path::Path;
use std::process::Command;

#[test]
fn clean_program_exits_zero_with_a_summary() {
    let (code, stdout, stderr) = lsdc(&["check", "examples/satellite.lsd"]);
    assert_eq!(code, 0, "{stderr}");
    assert!(
        stdout.contains("bodies    4 (satellite, bras_primaire, bras_secondaire, reflecteur)"),
        "{stdout}"
    );
    assert!(stdout.contains("2 scalars (?s)"), "{stdout}");
    assert!(stdout.contains("3 functions (?f)"), "{stdout}");
}

#[test]
fn program_errors_exit_one() {
    let (code, _, stderr) = lsdc(&["check", "tests/golden/wrong_field.lsd"]);
    assert_eq!(code, 1);
    assert!(
        stderr.contains("tests/golden/wrong_field.lsd:2:47"),
        "{stderr}"
    );
}

#[test]
fn usage_errors_exit_two() {
    assert_eq!(lsdc(&["check"]).0, 2);
    assert_eq!(lsdc(&["frobnicate"]).0, 2);
    let (code, _, stderr) = lsdc(&["check", "no/such/file.lsd"]);
    assert_eq!(code, 2);
    assert!(stderr.contains("cannot read"), "{stderr}");
}

#[test]
fn json_format_reports_diagnostics_and_summaries() {
    let (code, stdout, _) = lsdc(&[
        "check",
        "--format",
        "json",
        "examples/satellite.lsd",
        "tests/golden/unknown_name_thesis.lsd",
    ]);
    assert_eq!(code, 1);
    let value: serde_json::Value = serde_json::from_str(&stdout).expect("valid JSON");
    assert_eq!(value["ok"], false);
    assert_eq!(value["files"][0]["summary"]["bodies"], 4);
    let diagnostic = &value["files"][1]["diagnostics"][0];
    assert_eq!(diagnostic["code"], "E0301");
    assert_eq!(
        (diagnostic["line"].as_u64(), diagnostic["column"].as_u64()),
        (Some(4), Some(6))
    );
    assert!(diagnostic["help"]
        .as_str()
        .is_some_and(|h| h.contains("satellite")));
}

#[test]
fn library_directories_come_from_flags() {
    let dir = std::env::temp_dir().join(format!("lsdc-cli-{}", std::process::id()));
    std::fs::create_dir_all(dir.join("libs")).expect("temp dir");
    std::fs::write(
        dir.join("libs/hinges.lsd"),
        "let hinge = link(q) dof = q || [0,0,1] end;\n",
    )
    .expect("write");
    std::fs::write(
        dir.join("main.lsd"),
        "import hinges;\nlet a = body end;\njoin earth and a with hinge;\n",
    )
    .expect("write");
    let main = dir.join("main.lsd");
    let main = main.to_str().expect("utf-8");
    assert_eq!(lsdc(&["check", main]).0, 1, "not found without -L");
    let libs = dir.join("libs");
    let (code, _, stderr) = lsdc(&["check", "-L", libs.to_str().expect("utf-8"), main]);
    assert_eq!(code, 0, "{stderr}");
    let status = Command::new(env!("CARGO_BIN_EXE_lsdc"))
        .args(["check", main])
        .env("LSD_PATH", libs.to_str().expect("utf-8"))
        .status()
        .expect("runs");
    assert_eq!(status.code(), Some(0), "found through LSD_PATH");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn parse_prints_the_syntax_tree() {
    let (code, stdout, _) = lsdc(&["parse", "examples/link_forms.lsd"]);
    assert_eq!(code, 0);
    assert!(stdout.contains("Join"), "{stdout}");
}

#[test]
fn simulate_writes_csv_samples_and_a_report() {
    let (code, stdout, stderr) = lsdc(&["simulate", "examples/pendulum.lsd"]);
    assert_eq!(code, 0, "{stderr}");
    assert!(
        stdout.starts_with("time,swing.q,swing.q',kinetic_energy,potential_energy\n"),
        "{stdout}"
    );
    assert_eq!(
        stdout.lines().count(),
        1 + 101,
        "a header and one row per output"
    );
    assert!(
        stderr.contains("dopri5:") && stderr.contains("energy drift"),
        "{stderr}"
    );
}

#[test]
fn simulate_takes_values_and_overrides_from_the_command_line() {
    let (code, stdout, stderr) = lsdc(&[
        "simulate",
        "tests/golden/../../examples/pendulum.lsd",
        "--duration",
        "0.5",
        "--every",
        "0.25",
        "--integrator",
        "rk4",
        "--step",
        "0.001",
        "--format",
        "json",
        "--report",
        "json",
    ]);
    assert_eq!(code, 0, "{stderr}");
    let value: serde_json::Value = serde_json::from_str(&stdout).expect("JSON samples");
    assert_eq!(value["samples"].as_array().map(Vec::len), Some(3));
    let report: serde_json::Value = serde_json::from_str(&stderr).expect("JSON report");
    assert_eq!(report["integrator"], "rk4");
    assert_eq!(report["steps"], 500);
}

#[test]
fn simulate_lists_every_missing_value() {
    let (code, _, stderr) = lsdc(&["simulate", "examples/satellite.lsd"]);
    assert_eq!(code, 1);
    for missing in [
        "mass(satellite)",
        "inertia_x(satellite)",
        "v1T_1_2_z",
        "v4T_4_G_z",
        "cL2_x",
        "fL3_y",
        "cL4_y",
    ] {
        assert!(stderr.contains(missing), "{missing} not listed:\n{stderr}");
    }
    let (code, _, stderr) = lsdc(&["simulate", "examples/pendulum.lsd", "--set", "nonsense=1"]);
    assert_eq!(code, 1);
    assert!(stderr.contains("no unknown of that name"), "{stderr}");
    assert_eq!(
        lsdc(&["simulate", "examples/pendulum.lsd", "--set", "oops"]).0,
        2
    );
}

#[test]
fn a_failing_simulation_keeps_its_output_and_says_so() {
    let (code, stdout, stderr) = lsdc(&["simulate", "examples/runaway.lsd"]);
    assert_eq!(code, 1);
    let last = stdout.lines().last().expect("output");
    assert!(last.starts_with("# the run failed at t = 1.55"), "{last}");
    assert!(
        stdout.lines().count() > 150,
        "rows before the failure are kept"
    );
    assert!(
        stderr.contains("FAILED") && stderr.contains("`slide.x`"),
        "{stderr}"
    );
}

#[test]
fn statics_prints_the_holding_efforts() {
    let args = [
        "statics",
        "examples/delta_isir88_reduced.lsd",
        "--actuate",
        "A1.q",
        "--actuate",
        "A2.q",
        "--actuate",
        "A3.q",
    ];
    let (code, stdout, stderr) = lsdc(&args);
    assert_eq!(code, 0, "{stderr}");
    assert_eq!(stdout.matches("-2.31009").count(), 3, "{stdout}");
    let (code, _, stderr) = lsdc(&[
        "statics",
        "examples/delta_isir88_reduced.lsd",
        "--actuate",
        "A1.z",
    ]);
    assert_eq!(code, 2);
    assert!(stderr.contains("did you mean `A1.q`?"), "{stderr}");
}

#[test]
fn loop_simulations_report_their_constraints_and_reactions() {
    let args = [
        "simulate",
        "examples/slider_crank.lsd",
        "--duration",
        "0.1",
        "--reactions",
        "--report",
        "json",
    ];
    let (code, stdout, stderr) = lsdc(&args);
    assert_eq!(code, 0, "{stderr}");
    let header = stdout.lines().next().expect("header");
    assert!(header.ends_with("pin.reaction.mx,pin.reaction.my,pin.reaction.mz,pin.reaction.fx,pin.reaction.fy,pin.reaction.fz"), "{header}");
    let report: serde_json::Value = serde_json::from_str(&stderr).expect("JSON report");
    let constraints = &report["constraints"];
    assert_eq!(constraints["rank"], 3);
    assert_eq!(constraints["redundant"].as_array().map(Vec::len), Some(3));
    assert!(constraints["position_residual"].as_f64().expect("number") < 1e-12);
}

#[test]
fn eval_reports_a_singular_mass_matrix_for_aba_only() {
    let dir = std::env::temp_dir().join(format!("lsdc-cli-eval-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    // The wrist turns a massless body: the mass matrix is singular, ABA has no answer.
    let program = "import joints ;\n\
        let upper = body mass = 1, iframe = [0.5, 0, 0] ++ 1, inertia = [0.1, 0.2, 0.3] end ;\n\
        let tip = body mass = 0, inertia = 0 end ;\n\
        join earth and upper with revolute([0, 0, 1]) as shoulder ;\n\
        join [1, 0, 0] ++ 1 @ upper and tip with revolute([0, 0, 1]) as wrist ;\n";
    std::fs::write(dir.join("arm.lsd"), program).expect("write");
    let states =
        r#"{"states": [{"q": [0.5, 0], "v": [1, 0], "a": [1, 0], "tau": [1, 0]}, {"q": [0, 0]}]}"#;
    std::fs::write(dir.join("states.json"), states).expect("write");
    let (file, states_file) = (dir.join("arm.lsd"), dir.join("states.json"));
    let args = [
        "eval",
        file.to_str().expect("utf-8"),
        "--states",
        states_file.to_str().expect("utf-8"),
    ];
    let (code, stdout, stderr) = lsdc(&args);
    assert_eq!(code, 0, "{stderr}");
    let value: serde_json::Value = serde_json::from_str(&stdout).expect("JSON");
    assert_eq!(
        value["positions"],
        serde_json::json!(["shoulder.q", "wrist.q"])
    );
    let first = &value["states"][0];
    assert!(
        first["aba"].is_null() && first.as_object().is_some_and(|o| o.contains_key("aba")),
        "{first}"
    );
    let reason = first["errors"]["aba"].as_str().expect("the reason");
    assert!(
        reason.contains("singular") && reason.contains("`wrist`"),
        "{reason}"
    );
    assert_eq!(
        first["errors"].as_object().map(|o| o.len()),
        Some(1),
        "{first}"
    );
    // RNEA, CRBA and the frames are kept: M = [[0.3 + 1 * 0.5², 0], [0, 0]], τ = M a.
    let rnea: Vec<f64> = first["rnea"]
        .as_array()
        .expect("rnea")
        .iter()
        .filter_map(|x| x.as_f64())
        .collect();
    assert!(
        (rnea[0] - 0.55).abs() < 1e-12 && rnea[1].abs() < 1e-12,
        "{rnea:?}"
    );
    assert!(
        (first["crba"][0][0].as_f64().expect("number") - 0.55).abs() < 1e-12,
        "{first}"
    );
    assert_eq!(first["frames"].as_array().map(Vec::len), Some(2), "{first}");
    let tip = first["frames"][1]["translation"][0]
        .as_f64()
        .expect("number");
    assert!((tip - 0.5f64.cos()).abs() < 1e-12, "{tip}");
    // The second state asks for neither: no `rnea`, no `aba`, no `errors`.
    let second = value["states"][1].as_object().expect("a state");
    assert!(
        !second.contains_key("aba")
            && !second.contains_key("rnea")
            && !second.contains_key("errors"),
        "{second:?}"
    );
    let warnings: Vec<&str> = stderr
        .lines()
        .filter(|l| l.starts_with("warning: state"))
        .collect();
    assert_eq!(warnings.len(), 1, "{stderr}");
    assert!(
        warnings[0].starts_with("warning: state 0: aba: the mass matrix is singular"),
        "{stderr}"
    );

    // A wrong input still fails, with the state's index.
    std::fs::write(&states_file, r#"[{"q": [0, 0]}, {"q": [0]}]"#).expect("write");
    let (code, stdout, stderr) = lsdc(&args);
    assert_eq!(code, 1, "{stdout}");
    assert!(
        stderr.contains("error: state 1: `q` has 1 entries, the mechanism has 2"),
        "{stderr}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn an_rk4_step_too_long_for_the_tolerances_is_warned_not_silent() {
    // The squeezer's stiff spring at h = 1e-3 puts RK4 near its stability limit: the run exits
    // with 0 but its positions are 0.8 rad off the test set's reference at t = 0.03.
    let squeezer = [
        "simulate",
        "examples/hard/squeezer.lsd",
        "--integrator",
        "rk4",
    ];
    let long = [&squeezer[..], &["--step", "1e-3", "--tolerance", "1e-8"]].concat();
    let (code, _, stderr) = lsdc(&long);
    assert_eq!(code, 0, "{stderr}");
    assert!(stderr.contains("warning[W0902]"), "{stderr}");
    assert!(
        stderr.contains("largest local error estimate of a step"),
        "{stderr}"
    );
    let json = [&long[..], &["--report", "json"]].concat();
    let (_, stdout, stderr) = lsdc(&json);
    let report: serde_json::Value = serde_json::from_str(&stderr).expect("the report is JSON");
    assert_eq!(report["warnings"][0]["code"], "W0902", "{stderr}");
    assert!(report["step_error"]["largest"].as_f64().unwrap() > 1.0);
    assert!(
        stdout.starts_with("time,"),
        "the samples alone on standard output"
    );
    // A hundred times shorter, the same run meets its tolerances and says nothing (at 1e-4 its
    // estimate is still 9 times the tolerance, and its error 7.8e-6 against the reference).
    let short = [&squeezer[..], &["--step", "1e-5", "--tolerance", "1e-6"]].concat();
    let (code, _, stderr) = lsdc(&short);
    assert_eq!(code, 0, "{stderr}");
    assert!(!stderr.contains("W0902"), "{stderr}");
}

#[test]
fn a_run_ending_inside_a_singular_passage_warns_about_its_last_outputs() {
    // The row of ten four-bars sets rows aside at its first flat configuration (t ≈ 0.139);
    // a run ending there cannot interpolate the outputs inside the passage between states on
    // the branch, and says so (W0903). Ending just after the passage, it says nothing. (With
    // each loop's rows scaled by its own length, no step up to t = 0.13905 comes within
    // `PASSAGE_ENTERED`, the smallest conditioning there 1.4e-5: a run ending at 0.13905 sets
    // no row aside; ending at 0.1391, at 2.4e-6, it has.)
    let run = |duration: &str| {
        lsdc(&[
            "simulate",
            "examples/hard/four_bar_row_10.lsd",
            "--integrator",
            "dopri5",
            "--tolerance",
            "1e-11",
            "--step",
            "1e-4",
            "--every",
            "1e-5",
            "--duration",
            duration,
            "--report",
            "json",
        ])
    };
    let (code, _, stderr) = run("0.1391");
    assert_eq!(code, 0, "{stderr}");
    let report: serde_json::Value = serde_json::from_str(&stderr).expect("the report is JSON");
    assert_eq!(report["warnings"][0]["code"], "W0903", "{stderr}");
    assert!(!report["constraints"]["outputs_off_branch"]
        .as_array()
        .unwrap()
        .is_empty());
    let (code, _, stderr) = run("0.1395");
    assert_eq!(code, 0, "{stderr}");
    assert!(!stderr.contains("W0903"), "{stderr}");
}

/// `simulate --plot-columns`: the chosen columns only, a panel per option (the Delta's
/// documented commands plot errors and torques so); a misspelt name stops the command before
/// the run (its golden file: `tests/golden/commands/simulate_plot_unknown_column`).
#[test]
fn simulate_plots_the_chosen_columns() {
    let plot = std::env::temp_dir().join(format!("lsdc-columns-{}.svg", std::process::id()));
    let plot_name = plot.display().to_string();
    let example = "examples/control/discrete_pd_pendulum.lsd";
    let args = [
        "simulate",
        example,
        "--duration",
        "0.5",
        "-o",
        "/dev/null",
        "--plot",
        &plot_name,
        "--plot-columns",
        "swing.q",
        "--plot-columns",
        "u,kinetic_energy",
    ];
    let (code, _, stderr) = lsdc(&args);
    assert_eq!(code, 0, "{stderr}");
    let svg = std::fs::read_to_string(&plot).expect("the plot is written");
    let _ = std::fs::remove_file(&plot);
    // The SVG's texts (a line each): captions and legends of the two panels, and nothing of
    // the standard plot's.
    let texts: Vec<&str> = svg.lines().filter(|l| !l.starts_with('<')).collect();
    let count = |wanted: &str| texts.iter().filter(|&&t| t == wanted).count();
    assert_eq!(count("swing.q"), 2, "{texts:?}");
    assert_eq!(count("u, kinetic_energy"), 1, "{texts:?}");
    assert_eq!((count("u"), count("kinetic_energy")), (1, 1), "{texts:?}");
    assert_eq!(
        count("swing.q&apos;") + count("Energy") + count("kinetic"),
        0
    );
    let misspelt = [
        "simulate",
        example,
        "--plot",
        &plot_name,
        "--plot-columns",
        "swing.q'',u",
    ];
    let (code, stdout, stderr) = lsdc(&misspelt);
    assert_eq!((code, stdout.as_str()), (2, ""), "{stderr}");
    assert!(stderr.contains("did you mean `swing.q'`?"), "{stderr}");
    assert!(!plot.exists(), "nothing drawn");
}

#[test]
fn precision_errors_decrease_with_the_tolerance_and_its_json_is_a_table() {
    let plot = std::env::temp_dir().join(format!("lsdc-precision-{}.svg", std::process::id()));
    let plot_name = plot.display().to_string();
    let args = [
        "precision",
        "examples/pendulum.lsd",
        "--integrators",
        "dopri5,dop853",
        "--tolerances",
        "1e-4,1e-7,1e-10",
        "--repeats",
        "2",
        "--accuracy",
        "1e-6",
        "--format",
        "json",
        "--plot",
        &plot_name,
    ];
    let (code, stdout, stderr) = lsdc(&args);
    assert_eq!(code, 0, "{stderr}");
    let table: serde_json::Value = serde_json::from_str(&stdout).expect("valid JSON");
    let measurements = table["measurements"].as_array().expect("measurements");
    assert_eq!(measurements.len(), 6);
    for integrator in ["dopri5", "dop853"] {
        let errors: Vec<f64> = measurements
            .iter()
            .filter(|m| m["integrator"] == integrator)
            .map(|m| m["errors"]["position"].as_f64().expect("an error"))
            .collect();
        assert!(
            errors.windows(2).all(|pair| pair[1] < pair[0] / 10.0),
            "{integrator}: {errors:?}"
        );
        for m in measurements
            .iter()
            .filter(|m| m["integrator"] == integrator)
        {
            assert_eq!(m["repeats"], 2);
            assert!(m["cpu_seconds_min"].as_f64() <= m["cpu_seconds_median"].as_f64());
            assert_eq!(m["errors"]["compared_outputs"], 101);
        }
    }
    assert_eq!(table["reference"]["kind"], "computed");
    let recommended = table["recommendation"]["measurement"]
        .as_u64()
        .expect("one");
    let chosen = &measurements[recommended as usize];
    assert!(chosen["errors"]["position"].as_f64().expect("an error") <= 1e-6);
    let svg = std::fs::read_to_string(&plot).expect("the plot is written");
    let _ = std::fs::remove_file(&plot);
    assert!(svg.contains("<svg") && svg.contains("dop853"), "{svg}");

    let (code, stdout, stderr) = lsdc(&["precision", "examples/pendulum.lsd", "--repeats", "1"]);
    assert_eq!(code, 0, "{stderr}");
    assert!(
        stdout.contains("| method | setting | position error"),
        "{stdout}"
    );
    assert_eq!(stdout.matches("| dop853 | tol").count(), 4, "{stdout}");
}

#[test]
fn precision_compares_with_a_reference_file_and_refuses_bad_ones() {
    let directory = std::env::temp_dir();
    let reference = directory.join(format!("lsdc-reference-{}.csv", std::process::id()));
    // The pendulum's closed-form state at t = 1 s is not needed: a row far off shows as the error.
    std::fs::write(&reference, "time,swing.q\n# a comment\n1,0.5\n").expect("written");
    let name = reference.display().to_string();
    let args = ["precision", "examples/pendulum.lsd", "--reference", &name];
    let (code, stdout, stderr) =
        lsdc(&[&args[..], &["--format", "json", "--repeats", "1"]].concat());
    assert_eq!(code, 0, "{stderr}");
    let table: serde_json::Value = serde_json::from_str(&stdout).expect("valid JSON");
    let first = &table["measurements"][0];
    assert_eq!(first["errors"]["compared_outputs"], 1);
    assert_eq!(first["errors"]["velocity"], 0.0);
    assert!(first["errors"]["position"].as_f64().expect("an error") > 0.1);

    std::fs::write(&reference, "time,nothing.q\n1,0.5\n").expect("written");
    let (code, _, stderr) = lsdc(&args);
    assert_eq!(code, 1);
    assert!(stderr.contains("no column of the reference"), "{stderr}");
    std::fs::write(&reference, "time,swing.q\n1,x\n").expect("written");
    let (code, _, stderr) = lsdc(&args);
    assert_eq!(code, 1);
    assert!(
        stderr.contains("line 2 of the reference: not a number"),
        "{stderr}"
    );
    let _ = std::fs::remove_file(&reference);

    let (code, _, stderr) = lsdc(&["precision", "examples/pendulum.lsd", "--tolerances", "0"]);
    assert_eq!(code, 2);
    assert!(
        stderr.contains("`--tolerances` must be positive numbers"),
        "{stderr}"
    );
    let (code, _, stderr) = lsdc(&["precision", "examples/pendulum.lsd", "--plot", "a.txt"]);
    assert_eq!(code, 2);
    assert!(stderr.contains(".svg"), "{stderr}");
}

/// `lsdc` with standard output or standard error on `/dev/full`, where every write fails.
fn lsdc_on_full(args: &[&str], full_stdout: bool) -> (i32, String) {
    let full = || std::fs::OpenOptions::new().write(true).open("/dev/full");
    let mut command = Command::new(env!("CARGO_BIN_EXE_lsdc"));
    command.args(args).env_remove("LSD_PATH");
    match full_stdout {
        true => command.stdout(full().expect("/dev/full")),
        false => command.stderr(full().expect("/dev/full")),
    };
    let output = command.output().expect("lsdc runs");
    let message = String::from_utf8_lossy(&output.stderr).into_owned();
    (output.status.code().unwrap_or(-1), message)
}

#[test]
fn a_full_standard_output_is_an_error_and_a_full_standard_error_no_panic() {
    if !Path::new("/dev/full").exists() {
        eprintln!("skipped: this system has no /dev/full");
        return;
    }
    let dir = std::env::temp_dir().join(format!("lsdc-cli-full-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("folder");
    let path = dir.join("path.csv");
    std::fs::write(&path, "x,y\n0.5,0.5\n").expect("path");
    let unformatted = dir.join("unformatted.lsd");
    std::fs::write(&unformatted, "let   a = 1 ;\n").expect("program");
    let (path, unformatted) = (path.to_str().unwrap(), unformatted.to_str().unwrap());
    let pendulum = "examples/pendulum.lsd";
    let commands: [&[&str]; 13] = [
        &["check", pendulum],
        &["tree", pendulum],
        &["assemble", pendulum],
        &["parse", pendulum],
        &["compile", "--emit", "notation", pendulum],
        &["export-urdf", pendulum],
        &[
            "statics",
            "examples/delta_isir88_reduced.lsd",
            "--actuate",
            "A1.q",
        ],
        &["simulate", pendulum, "--format", "json"],
        &["simulate", pendulum],
        &["precision", pendulum, "--repeats", "1"],
        &[
            "drag",
            "examples/four_bar.lsd",
            "--point",
            "coupler_point",
            "--path",
            path,
        ],
        &["import-urdf", "tests/fixtures/urdf/double_pendulum.urdf"],
        &["fmt", "--check", unformatted],
    ];
    for args in commands {
        let (code, stderr) = lsdc_on_full(args, true);
        assert!(
            code != 0 && stderr.contains("cannot write standard output"),
            "{args:?}: exit {code}, {stderr}"
        );
        let (code, _) = lsdc_on_full(args, false);
        assert!(
            (0..=2).contains(&code),
            "{args:?} with a full standard error: exit {code}"
        );
    }
    let (code, _) = lsdc_on_full(&["check", "no/such/file.lsd"], false);
    assert_eq!(code, 2, "an error not printed is still an error");
}

#[test]
fn precision_ranks_by_time_only_over_enough_repeats() {
    let args = |repeats| {
        let mut args = vec![
            "precision",
            "examples/pendulum.lsd",
            "--integrators",
            "dopri5,dop853",
        ];
        args.extend(["--tolerances", "1e-8,1e-10", "--accuracy", "1e-5"]);
        args.extend(["--format", "json", "--repeats", repeats]);
        args.iter().map(|a| a.to_string()).collect::<Vec<_>>()
    };
    let run = |repeats| {
        let args = args(repeats);
        let (code, stdout, stderr) = lsdc(&args.iter().map(String::as_str).collect::<Vec<_>>());
        assert_eq!(code, 0, "{stderr}");
        let table: serde_json::Value = serde_json::from_str(&stdout).expect("JSON");
        table
    };
    let table = run("1");
    let message = table["recommendation"]["message"]
        .as_str()
        .expect("a message");
    assert!(
        message.contains("not by CPU time: 1 repeat(s) cannot tell"),
        "{message}"
    );
    // Ranked by function evaluations: the fewest among the runs that reached the accuracy.
    let measurements = table["measurements"].as_array().expect("measurements");
    let chosen = table["recommendation"]["measurement"]
        .as_u64()
        .expect("one") as usize;
    let evaluations = |m: &serde_json::Value| m["function_evaluations"].as_u64().expect("a count");
    let fewest = (measurements.iter())
        .filter(|m| m["errors"]["position"].as_f64().expect("an error") <= 1e-5)
        .map(evaluations)
        .min();
    assert_eq!(Some(evaluations(&measurements[chosen])), fewest);
}

#[test]
fn fmt_check_shows_what_formatting_would_change() {
    let dir = std::env::temp_dir().join(format!("lsdc-cli-fmt-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("folder");
    let file = dir.join("spaced.lsd");
    let text = "let a = 1 ;\nlet   b = 2 ;\nlet c = 3 ;\n";
    std::fs::write(&file, text).expect("program");
    let name = file.to_str().expect("utf-8");
    let (code, stdout, stderr) = lsdc(&["fmt", "--check", name]);
    assert_eq!(code, 1, "{stderr}");
    let expected = format!(
        "{name}: not formatted\n--- {name}\n+++ {name} (formatted)\n@@ -1,3 +1,3 @@\n let a = 1 ;\n-let   b = 2 ;\n+let b = 2 ;\n let c = 3 ;\n"
    );
    assert_eq!(stdout, expected);
    assert_eq!(std::fs::read_to_string(&file).expect("kept"), text);
}

#[test]
fn rk4_in_place_of_a_programs_adaptive_settings_warns_once_per_run() {
    // Programs written for an adaptive method (their own `tolerance`) run with `--integrator
    // rk4` at its default step: the step too long for their tolerances is one warning after
    // the run with its largest estimate, never one per step or per output.
    for program in ["examples/slider_crank.lsd", "examples/heavy_top.lsd"] {
        let (code, _, stderr) = lsdc(&["simulate", program, "--integrator", "rk4"]);
        assert_eq!(code, 0, "{program}: {stderr}");
        assert_eq!(
            stderr.matches("warning[W0902]").count(),
            1,
            "{program}: {stderr}"
        );
    }
}

/// Each command's arguments are built only when it runs (`#[command(defer = true)]` in
/// main.rs): its help must still open with the command's own description, the one `lsdc --help`
/// lists, not the description of an argument struct flattened into it.
#[test]
fn every_commands_help_opens_with_its_description() {
    let (code, listing, _) = lsdc(&["--help"]);
    assert_eq!(code, 0);
    let commands: Vec<(&str, &str)> = (listing.lines())
        .skip_while(|line| !line.starts_with("Commands:"))
        .skip(1)
        .take_while(|line| line.starts_with("  "))
        .filter_map(|line| line.trim().split_once(' '))
        .filter(|(name, _)| *name != "help")
        .map(|(name, description)| (name, description.trim()))
        .collect();
    assert!(commands.len() > 20, "{listing}");
    for (name, description) in commands {
        let (code, help, stderr) = lsdc(&[name, "--help"]);
        assert_eq!(code, 0, "{name}: {stderr}");
        let first = help.lines().next().unwrap_or_default();
        assert_eq!(first, description, "`lsdc {name} --help`");
    }
}
