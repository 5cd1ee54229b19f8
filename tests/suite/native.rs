//! `simulate --compiled`: the generated forward dynamics compiled by the C compiler, cached, and
//! used only where it agrees with the simulator's own evaluation; a clean fallback otherwise.

use crate::common::{c_compiler, lsdc_with};
use std::path::{Path, PathBuf};

/// Runs `lsdc ARGS` with the cache in `cache` and `CC` set to `compiler`: exit code, standard
/// output and standard error.
fn lsdc_native(args: &[&str], cache: &Path, compiler: &str) -> (i32, String, String) {
    let environment = [
        ("LSDC_CACHE_DIR", cache.as_os_str()),
        ("CC", std::ffi::OsStr::new(compiler)),
    ];
    lsdc_with(args, &environment)
}

/// `lsdc simulate FILE ARGS` as `lsdc_native` runs it: exit code, samples (CSV) and standard
/// error.
fn simulate(file: &str, args: &[&str], cache: &Path, compiler: &str) -> (i32, String, String) {
    let arguments: Vec<&str> = ["simulate", file]
        .into_iter()
        .chain(args.iter().copied())
        .collect();
    lsdc_native(&arguments, cache, compiler)
}

fn fresh_cache(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("lsdc-native-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

/// The largest difference between two CSV outputs of the same run, relative to 1 + |value|.
fn csv_difference(a: &str, b: &str) -> f64 {
    let rows = |text: &str| -> Vec<Vec<f64>> {
        text.lines()
            .skip(1)
            .map(|l| l.split(',').filter_map(|x| x.parse().ok()).collect())
            .collect()
    };
    let (a, b) = (rows(a), rows(b));
    assert_eq!(a.len(), b.len(), "as many samples");
    a.iter()
        .flatten()
        .zip(b.iter().flatten())
        .map(|(x, y)| (x - y).abs() / (1.0 + y.abs()))
        .fold(0.0, f64::max)
}

fn libraries_in(cache: &Path) -> Vec<PathBuf> {
    let extension = std::env::consts::DLL_EXTENSION;
    std::fs::read_dir(cache)
        .map(|entries| {
            entries
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.extension().is_some_and(|x| x == extension))
                .collect()
        })
        .unwrap_or_default()
}

#[test]
fn compiled_runs_give_the_interpreted_motion_and_reuse_the_cache() {
    let Some(compiler) = c_compiler() else {
        crate::common::skip("no C compiler found (CC, cc, gcc, clang), --compiled is not checked");
        return;
    };
    let cache = fresh_cache("reuse");
    let file = "examples/double_pendulum.lsd";
    let args = ["--duration", "2"];
    let (code, interpreted, _) = simulate(file, &args, &cache, &compiler);
    assert_eq!(code, 0);
    let compiled_args = ["--duration", "2", "--compiled"];
    let (code, compiled, stderr) = simulate(file, &compiled_args, &cache, &compiler);
    assert_eq!(code, 0, "{stderr}");
    assert!(
        !stderr.contains("W0904"),
        "the native code serves: {stderr}"
    );
    // The same equations, summed otherwise: the runs part by round-off amplified by a chaotic
    // motion over 2 s, far below the tolerance's effect.
    let difference = csv_difference(&compiled, &interpreted);
    assert!(
        difference < 1e-7,
        "compiled and interpreted runs differ by {difference:e}"
    );
    let libraries = libraries_in(&cache);
    assert_eq!(libraries.len(), 1, "one library cached: {libraries:?}");
    let built = std::fs::metadata(&libraries[0])
        .and_then(|m| m.modified())
        .expect("mtime");
    let (code, again, _) = simulate(file, &compiled_args, &cache, &compiler);
    assert_eq!(code, 0);
    assert_eq!(again, compiled, "the cached library gives the same run");
    let reused = std::fs::metadata(&libraries[0])
        .and_then(|m| m.modified())
        .expect("mtime");
    assert_eq!(built, reused, "the second run loads the cached library");
    let _ = std::fs::remove_dir_all(&cache);
}

#[test]
fn without_a_compiler_the_run_goes_on_and_says_why() {
    let cache = fresh_cache("none");
    let file = "examples/pendulum.lsd";
    let (code, compiled, stderr) = simulate(file, &["--compiled"], &cache, "/no/such/compiler-cc");
    assert_eq!(code, 0, "{stderr}");
    assert!(stderr.contains("warning[W0904]"), "{stderr}");
    assert!(stderr.contains("no C compiler"), "{stderr}");
    let (_, interpreted, _) = simulate(file, &[], &cache, "/no/such/compiler-cc");
    assert_eq!(compiled, interpreted, "the run is the interpreted one");
    let _ = std::fs::remove_dir_all(&cache);
}

#[test]
fn loops_not_projected_and_imposed_motions_are_declined_by_name() {
    let cache = fresh_cache("declined");
    let compiler = c_compiler().unwrap_or_else(|| "cc".to_string());
    for (file, extra, why) in [
        // Baumgarte's feedback is in the interpreted accelerations only.
        (
            "examples/four_bar.lsd",
            &["--stabilisation", "baumgarte"][..],
            "other means than the projection",
        ),
        // Motions imposed in time, which the native code would leave out.
        (
            "examples/bead_on_spinning_rod.lsd",
            &[][..],
            "motions imposed in time",
        ),
        (
            "tests/fixtures/driven_pendulum.lsd",
            &[][..],
            "motions imposed in time",
        ),
    ] {
        let args = [&["--compiled", "--duration", "0.1"][..], extra].concat();
        let (code, _, stderr) = simulate(file, &args, &cache, &compiler);
        assert_eq!(code, 0, "{file}: {stderr}");
        assert!(
            stderr.contains("W0904") && stderr.contains(why),
            "{file}: {stderr}"
        );
    }
    let _ = std::fs::remove_dir_all(&cache);
}

#[test]
fn non_conservative_efforts_are_said_to_leave_the_balance_out() {
    let Some(compiler) = c_compiler() else {
        crate::common::skip("no C compiler found (CC, cc, gcc, clang), --compiled is not checked");
        return;
    };
    let cache = fresh_cache("work");
    let args = ["--compiled", "--duration", "0.2"];
    let (code, _, stderr) = simulate("examples/elastic_pendulum.lsd", &args, &cache, &compiler);
    assert_eq!(code, 0, "{stderr}");
    assert!(stderr.contains("W0905"), "{stderr}");
    let _ = std::fs::remove_dir_all(&cache);
}

/// `lsdc sweep ARGS` as `lsdc_native` runs it: exit code, the rows (CSV on standard output)
/// and standard error.
fn sweep(args: &[&str], cache: &Path, compiler: &str) -> (i32, String, String) {
    let arguments: Vec<&str> = ["sweep"].into_iter().chain(args.iter().copied()).collect();
    lsdc_native(&arguments, cache, compiler)
}

/// `sweep --compiled`: runs that share one prepared mechanism (only initial values vary) share
/// one native library, built once, and give the interpreted runs' rows; runs that each prepare
/// their own mechanism run without it, and a warning says why.
#[test]
fn a_sweep_compiles_once_for_the_runs_that_share_a_mechanism() {
    let Some(compiler) = c_compiler() else {
        crate::common::skip(
            "no C compiler found (CC, cc, gcc, clang), `sweep --compiled` is not checked",
        );
        return;
    };
    let cache = fresh_cache("sweep");
    let design = [
        "examples/double_pendulum.lsd",
        "--grid",
        "shoulder.q=1:2:4",
        "--duration",
        "1",
        "-j",
        "2",
    ];
    let (code, interpreted, stderr) = sweep(&design, &cache, &compiler);
    assert_eq!(code, 0, "{stderr}");
    let compiled_design: Vec<&str> = design.iter().copied().chain(["--compiled"]).collect();
    let (code, compiled, stderr) = sweep(&compiled_design, &cache, &compiler);
    assert_eq!(code, 0, "{stderr}");
    assert!(
        !stderr.contains("W0904"),
        "the native code serves: {stderr}"
    );
    assert_eq!(libraries_in(&cache).len(), 1, "one library for the 4 runs");
    // The rows' end values and extremes: the same equations summed otherwise. (The text
    // columns, `status` and `failure`, are not numbers and are left out: every run is ok.)
    assert_eq!(compiled.matches(",ok,").count(), 4, "{compiled}");
    let difference = csv_difference(&compiled, &interpreted);
    assert!(
        difference < 1e-8,
        "compiled and interpreted sweeps differ by {difference:e}"
    );

    // A value of the program varies: each run prepares its own mechanism.
    let (code, rows, stderr) = sweep(
        &[
            "examples/four_bar_grashof.lsd",
            "--grid",
            "l1=0.9:1.1:2",
            "--duration",
            "0.1",
            "--compiled",
        ],
        &cache,
        &compiler,
    );
    assert_eq!(code, 0, "{stderr}");
    assert!(stderr.contains("warning[W0904]"), "{stderr}");
    assert!(
        stderr.contains("do not share one prepared mechanism"),
        "{stderr}"
    );
    assert_eq!(rows.lines().count(), 3, "a header and two runs: {rows}");
    let _ = std::fs::remove_dir_all(&cache);
}

/// The last JSON object of standard error: the report of `--report json`.
fn report(stderr: &str) -> serde_json::Value {
    let start = match stderr.starts_with('{') {
        true => 0,
        false => stderr.rfind("\n{").expect("a report") + 1,
    };
    serde_json::from_str(&stderr[start..]).expect("JSON report")
}

/// Spherical and free joints on a tree run natively in the simulator's own state (the
/// quaternion as the position, the body twist as the rates: `symbolic::quaternion_joints`):
/// the free asymmetric body that flips over (the middle Bryant angle through ±π/2, where the
/// declared angles are singular) and the heavy top. The native runs give the interpreted
/// motion (measured over 10 s: 1.2e-12 and 6.0e-13, relative to 1 + |value|) and conserve
/// what the simulator computes from the state alone, independently of the accelerations: the
/// energy, and for the free body the linear and angular momenta (measured: 9.4e-13, 6.1e-12,
/// 4.9e-12; 1.6e-12 for the top's energy).
#[test]
fn quaternion_states_run_natively_as_interpreted_and_conserve_energy() {
    let Some(compiler) = c_compiler() else {
        crate::common::skip("no C compiler found (CC, cc, gcc, clang), --compiled is not checked");
        return;
    };
    let cache = fresh_cache("quaternions");
    for file in ["examples/free_body.lsd", "examples/heavy_top.lsd"] {
        let args = ["--report", "json"];
        let (code, interpreted, stderr) = simulate(file, &args, &cache, &compiler);
        assert_eq!(code, 0, "{file}: {stderr}");
        let compiled_args = ["--report", "json", "--compiled"];
        let (code, compiled, stderr) = simulate(file, &compiled_args, &cache, &compiler);
        assert_eq!(code, 0, "{file}: {stderr}");
        assert!(
            !stderr.contains("W0904"),
            "{file}: the native code serves: {stderr}"
        );
        let difference = csv_difference(&compiled, &interpreted);
        assert!(
            difference < 1e-10,
            "{file}: compiled and interpreted runs differ by {difference:e}"
        );
        let report = report(&stderr);
        let drift = report["energy_drift"].as_f64().expect("an energy drift");
        assert!(drift < 1e-10, "{file}: energy drift {drift:e} natively");
        if file.contains("free_body") {
            for kind in ["linear", "angular"] {
                let drift = report["momentum_drift"][kind]
                    .as_f64()
                    .expect("a momentum drift");
                assert!(
                    drift < 1e-10,
                    "{file}: {kind} momentum drift {drift:e} natively"
                );
            }
        }
    }
    let _ = std::fs::remove_dir_all(&cache);
}

/// A ball joint whose declared angles an effort reads: the simulator recovers them from its
/// quaternion, the equations in its state have no such variables, and the run says so.
#[test]
fn an_effort_on_a_ball_joints_declared_angles_is_declined_by_name() {
    let cache = fresh_cache("ball-angles");
    let compiler = c_compiler().unwrap_or_else(|| "cc".to_string());
    let text = std::fs::read_to_string("examples/heavy_top.lsd").expect("example");
    let spring = "apply torque value = [-0.1 * pivot.a, 0, 0], body = earth end on top ;\n";
    let directory = fresh_cache("ball-angles-program");
    std::fs::create_dir_all(&directory).expect("a directory");
    let file = directory.join("top_with_spring.lsd");
    std::fs::write(&file, text + spring).expect("written");
    let file = file.to_str().expect("a path");
    let (code, _, stderr) = simulate(
        file,
        &["--compiled", "--duration", "0.1"],
        &cache,
        &compiler,
    );
    assert_eq!(code, 0, "{stderr}");
    assert!(
        stderr.contains("W0904") && stderr.contains("declared angles of `pivot`"),
        "{stderr}"
    );
    let _ = std::fs::remove_dir_all(&cache);
    let _ = std::fs::remove_dir_all(&directory);
}
