//! A run's limits and reports: the stiffness check during explicit runs (W0901), `--max-steps`,
//! the samples streamed as they come, SIGINT, and output paths refused before the run.

use std::io::{BufRead, BufReader};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use lsdc::driver::compile_text;
use lsdc::load::LoadOptions;
use lsdc::prepare::settings::SettingsChanges;
use lsdc::prepare::{prepare, Prepared, Settings};
use lsdc::simulate::run::{run, Simulation};

use crate::common::programs::prepared as example;

fn changed(mut prepared: Prepared, changes: SettingsChanges) -> Prepared {
    prepared.settings.apply(&changes).expect("valid changes");
    prepared
}

fn integrator(name: &str) -> lsdc::prepare::Integrator {
    use lsdc::prepare::Integrator;
    match name {
        "rk4" => Integrator::Rk4,
        _ => Integrator::DormandPrince,
    }
}

/// The governor (springs of 8e5 N/m, dampers of 4e4 N s/m) run for a short while with an
/// explicit integrator and an output interval.
fn explicit_governor(name: &str, every: f64, check: bool) -> Simulation {
    let changes = SettingsChanges {
        integrator: Some(integrator(name)),
        duration: Some(0.02),
        output: Some(every),
        no_stiffness_check: !check,
        ..SettingsChanges::default()
    };
    run(&changed(example("governor", &[]), changes), &mut |_| {})
}

#[test]
fn w0901_fires_for_a_stability_bound_explicit_run_whatever_the_output_interval() {
    for name in ["dopri5", "rk4"] {
        for every in [0.02, 0.01, 0.001, 1e-4] {
            let simulation = explicit_governor(name, every, true);
            let warning = lsdc::simulate::run::stiffness_warning(&simulation.report)
                .unwrap_or_else(|| panic!("{name}, every {every}: no W0901"));
            assert_eq!(warning.code, "W0901");
            let found = simulation.report.stiffness.expect("a stiffness report");
            assert!(
                found.element.as_deref().is_some_and(|e| e.contains("arm")),
                "{name}: the stiffest element is a spring or damper on an arm: {:?}",
                found.element
            );
            assert!(!warning.labels.is_empty(), "the element is shown");
            // The dampers' rate c/m is 4e4 / m; the estimate is the spectral radius.
            assert!(found.rate > 1e4, "{name}: rate {:e}", found.rate);
            assert_eq!(found.diverges, name == "rk4", "{name}: {found:?}");
        }
        let unchecked = explicit_governor(name, 0.01, false);
        assert!(unchecked.report.stiffness.is_none(), "--no-stiffness-check");
    }
}

/// The parallelogram four-bar of `examples/hard`, run for 10 s with RK4 at 1 ms, passes its
/// flat (singular) configuration twice a turn, and ends with an energy drift of 4.4e-8: the
/// step is well inside stability. W0901 said it diverged (at t = 4.722: a rate of 1.2e4 /s,
/// stable step 2.4e-4 s), the power iteration having found ∂f/∂y off the loop's constraints,
/// where it grows like the inverse of their conditioning near the flat passage and where the
/// projection leaves no motion. With a crank held by a torsion spring of 3e7 N m/rad (a mode
/// at √(k/J) = 9.5e3 /s, J = 1/3 kg m²), the same run is beyond the stable step, and says so.
#[test]
fn w0901_sees_only_the_motions_the_loops_allow() {
    let rk4 = |prepared: Prepared| {
        let changes = SettingsChanges {
            integrator: Some(integrator("rk4")),
            step: Some(1e-3),
            duration: Some(10.0),
            ..SettingsChanges::default()
        };
        run(&changed(prepared, changes), &mut |_| {})
    };
    let flat = rk4(example("hard/four_bar_row_1", &[]));
    assert!(flat.report.failure.is_none());
    assert!(
        flat.report.stiffness.is_none(),
        "{:?}",
        flat.report.stiffness
    );
    let drift = flat.report.energy_drift.expect("conservative");
    assert!(drift < 1e-6, "{drift}");
    let sprung = "let sprung = link(q) dof = q || z, torque = -3e7 * (q + pi / 2) * z end ;
        join [0 * L, 0, 0] ++ 1 @ earth and crank0 with sprung as c0 ;";
    let stiff = example(
        "hard/four_bar_row_1",
        &[(
            "join [0 * L, 0, 0] ++ 1 @ earth and crank0 with revolute(z) as c0 ;",
            sprung,
        )],
    );
    let found = rk4(stiff).report.stiffness.expect("W0901");
    assert!(found.diverges, "{found:?}");
    let expected = (3e7f64 / (1.0 / 3.0)).sqrt();
    assert!(
        (found.rate / expected - 1.0).abs() < 0.05,
        "{} against {expected}",
        found.rate
    );
}

/// Every example that simulates as it is, with its own settings.
fn simulated_examples() -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir("examples")
        .expect("examples")
        .filter_map(|entry| {
            let path = entry.ok()?.path();
            (path.extension()? == "lsd").then(|| path.file_stem()?.to_str().map(String::from))?
        })
        .collect();
    names.sort();
    names
}

#[test]
fn w0901_never_fires_on_the_examples_that_are_not_stiff() {
    let options = LoadOptions {
        library_dirs: Vec::new(),
        use_environment: false,
        scene: None,
    };
    let mut checked = Vec::new();
    for name in simulated_examples() {
        let text = std::fs::read_to_string(format!("examples/{name}.lsd")).expect("reads");
        let compilation = compile_text(
            &format!("{name}.lsd"),
            &text,
            Some(std::path::Path::new("examples")),
            &options,
        );
        let Some(mechanism) = compilation.mechanism else {
            continue;
        };
        // Those without values for their unknowns do not simulate as they are.
        let Ok(mut prepared) = prepare(&mechanism, &[], &Settings::default()) else {
            continue;
        };
        // The governor (above) and the stiff spring pendulum are the stiff ones: dopri5 at the
        // pendulum's own tolerance says so; the others with each explicit integrator.
        if name == "governor" {
            continue;
        }
        if name == "stiff_spring_pendulum" {
            prepared.settings.integrator = integrator("dopri5");
            let found = run(&prepared, &mut |_| {}).report.stiffness;
            let element = found.and_then(|s| s.element).unwrap_or_default();
            assert!(element.contains("bob"), "{name}: {element}");
            continue;
        }
        // The Deltas braked by their shorted motors (c / J ~ 200 /s over a 10 s run) are
        // mildly stiff, which is why they run with the implicit integrator: dopri5 says so,
        // naming an arm, on which a brake acts.
        // The Delta driven along its nacelle's path moves as the kinematics of the path (its
        // rows hold every useful degree of freedom): nothing is integrated freely there.
        if name == "delta_isir88_path" {
            continue;
        }
        // (`delta_tolerances` is the Delta with nothing acting on it, at rest where it is
        // assembled: it goes through the explicit integrators below.)
        if name.starts_with("delta") && name != "delta_tolerances" {
            prepared.settings.integrator = integrator("dopri5");
            let stiffness = run(&prepared, &mut |_| {}).report.stiffness;
            let element = stiffness.and_then(|s| s.element).unwrap_or_default();
            assert!(element.contains("arm"), "{name}: {element}");
            continue;
        }
        for explicit in ["dopri5", "rk4"] {
            prepared.settings.integrator = integrator(explicit);
            let simulation = run(&prepared, &mut |_| {});
            assert!(
                simulation.report.stiffness.is_none(),
                "{name} with {explicit}: {:?}",
                simulation.report.stiffness
            );
        }
        checked.push(name);
    }
    assert!(checked.len() >= 15, "{checked:?}");
}

/// A planar tree of `rods` rods: a row of cranks pivoted on the ground, and a rod hanging from
/// the tip of each crank but the last (a row of four-bars with its closing joins removed).
fn rod_tree(rods: usize) -> String {
    let cranks = rods.div_ceil(2);
    let mut text = String::from(
        "let z = [0, 0, 1] ;\n\
         let hinge = link(q) dof = q || z end ;\n\
         let bar(l) = body mass = l, iframe = [l / 2, 0, 0] ++ 1, inertia = [1e-4 * l, l * l * l / 12, l * l * l / 12] end ;\n",
    );
    for k in 0..cranks {
        text += &format!("let crank{k} = bar(0.5) ;\njoin [{k}, 0, 0] ++ 1 @ earth and crank{k} with hinge as c{k} ;\n");
        text += &format!(
            "apply force value = [0, -9.81 * crank{k}.mass, 0], body = earth end on crank{k}.iframe ;\n"
        );
    }
    for k in 0..rods - cranks {
        text += &format!("let rod{k} = bar(1.0) ;\njoin [0.5, 0, 0] ++ 1 @ crank{k} and rod{k} with hinge as p{k} ;\n");
        text += &format!(
            "apply force value = [0, -9.81 * rod{k}.mass, 0], body = earth end on rod{k}.iframe ;\n"
        );
    }
    text += "initial c0.q' = 3.0 ;\n";
    text
}

#[test]
fn the_stiffness_check_does_not_hang_on_a_tree_of_100_planar_rods() {
    let options = LoadOptions {
        library_dirs: Vec::new(),
        use_environment: false,
        scene: None,
    };
    let compilation = compile_text("rods.lsd", &rod_tree(100), None, &options);
    assert!(!compilation.has_errors(), "{:?}", compilation.diagnostics);
    let mechanism = compilation.mechanism.expect("a mechanism");
    let mut prepared = prepare(&mechanism, &[], &Settings::default()).expect("prepares");
    assert_eq!(prepared.model.joints.len(), 100);
    for name in ["rk4", "dopri5"] {
        let changes = SettingsChanges {
            integrator: Some(integrator(name)),
            duration: Some(0.01),
            output: Some(0.005),
            ..SettingsChanges::default()
        };
        prepared.settings.apply(&changes).expect("valid changes");
        let simulation = run(&prepared, &mut |_| {});
        let report = &simulation.report;
        assert!(report.failure.is_none(), "{name}: {:?}", report.failure);
        assert!(report.steps >= 1, "{name}");
        assert_eq!(simulation.samples.len(), 3, "{name}");
    }
}

fn lsdc() -> Command {
    let mut command = Command::new(env!("CARGO_BIN_EXE_lsdc"));
    command.env_remove("LSD_PATH");
    command
}

fn temp_path(name: &str) -> std::path::PathBuf {
    std::env::temp_dir().join(format!("lsdc-runs-{}-{name}", std::process::id()))
}

#[test]
fn max_steps_stops_the_run_with_its_outputs_and_says_so() {
    let out = temp_path("max-steps.csv");
    let output = lsdc()
        .args([
            "simulate",
            "examples/pendulum.lsd",
            "--max-steps",
            "50",
            "-o",
        ])
        .arg(&out)
        .output()
        .expect("runs");
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("limit of 50 steps"), "{stderr}");
    let csv = std::fs::read_to_string(&out).expect("the samples");
    let _ = std::fs::remove_file(&out);
    assert!(csv.lines().count() > 2, "outputs before the limit are kept");
    assert!(csv
        .trim_end()
        .lines()
        .last()
        .unwrap()
        .starts_with("# the run failed"));
    let zero = lsdc()
        .args(["simulate", "examples/pendulum.lsd", "--max-steps", "0"])
        .output()
        .expect("runs");
    assert_eq!(zero.status.code(), Some(2));
}

#[test]
fn bad_output_paths_are_refused_before_the_run() {
    for args in [
        &["-o", "/nonexistent-folder/samples.csv"][..],
        &["--plot", "/nonexistent-folder/plot.svg"],
        &["--plot", "plot.txt"],
    ] {
        let output = lsdc()
            .args(["simulate", "examples/pendulum.lsd"])
            .args(args)
            .output()
            .expect("runs");
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(output.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(
            stderr.contains("cannot write") || stderr.contains("cannot draw"),
            "{args:?}: {stderr}"
        );
        assert!(!stderr.contains("steps"), "no run: {stderr}");
        assert!(output.stdout.is_empty(), "no samples");
    }
}

#[test]
fn sigint_ends_the_csv_with_a_marker_and_writes_the_report() {
    let out = temp_path("interrupted.csv");
    let mut child = lsdc()
        .args([
            "simulate",
            "examples/double_pendulum.lsd",
            "--duration",
            "10000",
            "--every",
            "0.01",
            "-o",
        ])
        .arg(&out)
        .stderr(Stdio::piped())
        .spawn()
        .expect("starts");
    // Rows reach the file as the run goes: wait for some before interrupting.
    let started = Instant::now();
    while std::fs::read_to_string(&out).map_or(0, |t| t.lines().count()) < 100 {
        let ended = child.try_wait().expect("waits");
        assert!(ended.is_none(), "ended before the signal: {ended:?}");
        assert!(
            started.elapsed() < Duration::from_secs(120),
            "no rows written"
        );
        std::thread::sleep(Duration::from_millis(50));
    }
    let pid = child.id() as libc::pid_t;
    // SAFETY: a plain system call on the process this test started.
    assert_eq!(unsafe { libc::kill(pid, libc::SIGINT) }, 0);
    let stderr = child.stderr.take().expect("stderr");
    let report: Vec<String> = BufReader::new(stderr)
        .lines()
        .map_while(Result::ok)
        .collect();
    let status = child.wait().expect("ends");
    assert_eq!(status.code(), Some(130), "{report:?}");
    let report = report.join("\n");
    assert!(
        report.contains("CPU time") && report.contains("wall time"),
        "{report}"
    );
    assert!(report.contains("INTERRUPTED"), "{report}");
    let csv = std::fs::read_to_string(&out).expect("the samples");
    let _ = std::fs::remove_file(&out);
    let mut lines: Vec<&str> = csv.lines().collect();
    let marker = lines.pop().expect("a last line");
    assert!(
        marker.starts_with("# interrupted by SIGINT at t = "),
        "{marker}"
    );
    let header = lines.remove(0);
    let columns = header.split(',').count();
    assert!(lines.len() >= 100);
    let mut previous = -1.0;
    for line in &lines {
        let values: Vec<f64> = line
            .split(',')
            .map(|v| v.parse().expect("a number"))
            .collect();
        assert_eq!(values.len(), columns, "{line}");
        assert!(values[0] > previous, "times increase: {line}");
        previous = values[0];
    }
}
