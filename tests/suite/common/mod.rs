//! Helpers shared by the integration tests.
#![allow(dead_code)]

pub mod contact_rows;
pub mod noise;
pub mod programs;
pub mod symbolic;
pub mod trees;

/// The largest |a_i − b_i| over two vectors of the same length.
pub fn max_difference(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

/// A directory for a test's files, `lsdc-NAME-PID` under the system's temporary directory.
pub fn scratch_dir(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("lsdc-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("a temporary directory");
    dir
}

/// A path as a command line's argument.
pub fn path_text(p: &std::path::Path) -> &str {
    p.to_str().expect("a path")
}

/// The paths of the programs `examples/*.lsd`, sorted.
pub fn example_paths() -> Vec<std::path::PathBuf> {
    let mut found: Vec<std::path::PathBuf> = std::fs::read_dir("examples")
        .expect("examples")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "lsd"))
        .collect();
    found.sort();
    found
}

/// Whether this process is the one where test `name` runs alone. The first time (in the suite's
/// process, beside other tests) it starts the suite's binary again to run that test only, with
/// `environment` set, waits for it to pass, and answers false: the caller returns. In that
/// second process it answers true: the caller does its work there. For tests that measure or set
/// what is the whole process's (its mapped memory, its environment), which tests running beside
/// them would disturb or be disturbed by.
pub fn alone(name: &str, environment: &[(&str, &std::ffi::OsStr)]) -> bool {
    const MARK: &str = "LSDC_TEST_ALONE";
    if std::env::var_os(MARK).is_some_and(|running| running == name) {
        return true;
    }
    let exe = std::env::current_exe().expect("the suite's binary");
    let out = std::process::Command::new(exe)
        .args(["--exact", name, "--test-threads=1", "--nocapture"])
        .env(MARK, name)
        .envs(environment.iter().copied())
        .output()
        .expect("the suite's binary starts");
    let printed = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success() && printed.contains("1 passed"),
        "{name}, alone, failed:\n{printed}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    false
}

/// A test whose tool is missing says so and passes (a developer's machine), or fails where the
/// environment variable `CI` is set: CI installs every tool (`.ci/run`), so a skip there is a
/// fault, never a silent pass.
pub fn skip(reason: &str) {
    if std::env::var_os("CI").is_some() {
        panic!("CI is set but {reason}: `.ci/run` installs it");
    }
    eprintln!("SKIPPED: {reason}");
}

/// The first C compiler found: `CC`, `cc`, `gcc`, `clang`.
pub fn c_compiler() -> Option<String> {
    let candidates = std::env::var("CC")
        .into_iter()
        .chain(["cc", "gcc", "clang"].map(String::from));
    candidates.into_iter().find(|c| {
        std::process::Command::new(c)
            .arg("--version")
            .output()
            .is_ok_and(|o| o.status.success())
    })
}

/// Runs the `lsdc` binary with `args` (no library path from the environment): exit code,
/// standard output and standard error.
pub fn lsdc(args: &[&str]) -> (i32, String, String) {
    lsdc_with(args, &[])
}

/// `lsdc` with these environment variables set.
pub fn lsdc_with(args: &[&str], environment: &[(&str, &std::ffi::OsStr)]) -> (i32, String, String) {
    let output = std::process::Command::new(env!("CARGO_BIN_EXE_lsdc"))
        .args(args)
        .env_remove("LSD_PATH")
        .envs(environment.iter().copied())
        .output()
        .expect("lsdc runs");
    (
        output.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&output.stdout).into_owned(),
        String::from_utf8_lossy(&output.stderr).into_owned(),
    )
}

/// Checks each diagnostic case of a command against its golden file: in `folder`, `NAME.args`
/// holds the arguments after `lsdc COMMAND` and `NAME.stderr` what it prints on standard error
/// (exit code 1 or 2); `UPDATE_GOLDEN=1` rewrites the `.stderr` files. At least `fewest` cases.
pub fn check_command_goldens(command: &str, folder: &str, fewest: usize) {
    let folder = std::path::Path::new(folder);
    let mut cases: Vec<_> = std::fs::read_dir(folder)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "args"))
        .collect();
    cases.sort();
    assert!(cases.len() >= fewest, "{cases:?}");
    for case in cases {
        let arguments = std::fs::read_to_string(&case).unwrap();
        let mut args = vec![command];
        args.extend(arguments.split_whitespace());
        let (code, _, stderr) = lsdc(&args);
        assert!(code == 1 || code == 2, "{}: exit {code}", case.display());
        let expected_path = case.with_extension("stderr");
        if std::env::var_os("UPDATE_GOLDEN").is_some() {
            std::fs::write(&expected_path, &stderr).unwrap();
            continue;
        }
        let expected = std::fs::read_to_string(&expected_path).unwrap_or_default();
        assert_eq!(stderr, expected, "{}", case.display());
    }
}
