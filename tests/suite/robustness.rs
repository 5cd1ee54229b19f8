//! No panic, no silent wrong answer: degenerate mechanisms, the nesting limit, values checked
//! where they are written or given, and a few hundred semantic mutants of the examples run
//! through the whole back end without a panic or a hang.

use std::path::PathBuf;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{mpsc, Arc};
use std::time::{Duration, Instant};

use lsdc::api::{run, Error, Override, Program, SettingsChanges};
use lsdc::prepare::Integrator;

use crate::mutants::{exercise, mutate, Choices};

/// Every integrator the registry knows, so that a new one is exercised too.
fn integrators() -> impl Iterator<Item = Integrator> {
    lsdc::integrators::INTEGRATORS
        .iter()
        .map(|entry| entry.integrator.clone())
}

fn codes(program: &Program) -> Vec<&str> {
    program.diagnostics().iter().map(|d| d.code).collect()
}

/// A program with nothing to move (no body, or one welded to the earth) simulates to its end
/// with every integrator.
#[test]
fn mechanisms_without_coordinates_simulate() {
    let welded = "import joints ;\nlet b = body mass = 1, iframe = 1, inertia = [1, 1, 1] end ;\njoin earth and b with weld as w ;\n";
    for text in ["", welded] {
        let program = Program::from_text("still.lsd", text, None, &Default::default());
        for integrator in integrators() {
            let name = format!("{integrator:?}");
            let changes = SettingsChanges {
                integrator: Some(integrator),
                duration: Some(0.01),
                ..Default::default()
            };
            let prepared = program.prepare(&[], &changes).expect("prepares");
            let mut times = Vec::new();
            let simulation = run(&prepared, &mut |s| times.push(s.time));
            assert!(simulation.report.failure.is_none(), "{text:?} {name}");
            assert_eq!(times.last(), Some(&0.01), "{text:?} {name}");
        }
    }
}

/// Expressions of each deep kind, `depth` levels.
fn deep(kind: usize, depth: usize) -> String {
    match kind {
        0 => format!("{}1", "1 + ".repeat(depth - 1)),
        1 => format!("{}1{}", "[".repeat(depth - 1), "]".repeat(depth - 1)),
        2 => format!("{}1", "-".repeat(depth - 1)),
        3 => format!("{}1{}", "sin(".repeat(depth - 1), ")".repeat(depth - 1)),
        _ => format!(
            "{}1{}",
            "local a = 1 in ".repeat(depth - 1),
            " end".repeat(depth - 1)
        ),
    }
}

/// At the limit every pass takes the program (on a test thread's small stack); one past it the
/// parser refuses it with E0203 and nothing overflows, however deep.
#[test]
fn nesting_is_limited_by_design() {
    use lsdc::syntax::nesting::MAX_NESTING;
    for kind in 0..5 {
        let at_limit = format!(
            "import joints ;\nlet s = {} ;\nlet b = body mass = 1, iframe = 1, inertia = [1, 1, 1] end ;\njoin earth and b with revolute([1, 0, 0]) as j ;\ninitial j.q = 0 * s ;\n",
            deep(kind, MAX_NESTING).replace("1 end", "0 end")
        );
        let program = Program::from_text("deep.lsd", &at_limit, None, &Default::default());
        assert!(!codes(&program).contains(&"E0203"), "kind {kind}");
        if !program.has_errors() {
            let changes = SettingsChanges {
                duration: Some(0.01),
                ..Default::default()
            };
            let prepared = program.prepare(&[], &changes).expect("prepares");
            run(&prepared, &mut |_| {});
        }
        for depth in [MAX_NESTING + 1, 30_000] {
            let text = format!("let x = {} ;\ninitial x = 1 ;\n", deep(kind, depth));
            let program = Program::from_text("deep.lsd", &text, None, &Default::default());
            assert!(
                codes(&program).contains(&"E0203"),
                "kind {kind} depth {depth}"
            );
        }
    }
    let primes = format!(
        "import joints ;\nlet b = body mass = 1, iframe = 1, inertia = [1, 1, 1] end ;\njoin earth and b with link(q) dof = q{} * [1, 0, 0] end ;\n",
        "'".repeat(30_000)
    );
    let program = Program::from_text("deep.lsd", &primes, None, &Default::default());
    assert!(codes(&program).contains(&"E0203"));
}

/// Values given with `--set` are checked as written ones are: `nan`, `inf` and a missing name
/// are usage errors, a negative mass is E0816 at the body.
#[test]
fn values_given_on_the_command_line_are_checked() {
    for text in ["k=nan", "k=inf", "k=-inf", "k=1e309", "=3", " =3"] {
        assert!(text.parse::<Override>().is_err(), "{text}");
    }
    let text = "import joints ;\nlet m = ?s ;\nlet b = body mass = m, iframe = 1, inertia = [1, 1, 1] end ;\njoin earth and b with revolute([1, 0, 0]) as j ;\n";
    let program = Program::from_text("set.lsd", text, None, &Default::default());
    let set = |value: f64| Override {
        name: "m".to_string(),
        value,
    };
    match program.prepare(&[set(-2.0)], &Default::default()) {
        Err(Error::Program(diagnostics)) => {
            assert_eq!(diagnostics[0].code, "E0816");
            assert!(diagnostics[0]
                .to_string()
                .contains("a mass of -2 is impossible"));
        }
        Err(other) => panic!("{other}"),
        Ok(_) => panic!("a negative mass was accepted"),
    }
    assert!(program.prepare(&[set(2.0)], &Default::default()).is_ok());
}

/// A coordinate whose motion becomes zero only through the values of unknowns is refused
/// before the run (E0829, at the link and the join, naming them), as a rotation axis made zero
/// so is (E0704): a translation `q * [a, 0, 0]` and an angle `k * q`, with `--set`, while
/// other values run.
#[test]
fn a_motion_zeroed_by_given_values_is_refused() {
    let head = "import joints ;\nlet a = ?s ;\nlet b = body mass = 1, iframe = 0, inertia = [1, 1, 1] end ;\n";
    for link in [
        "prismatic([a, 0, 0])",
        "link(q) dof = [0, 0, 1] * q * a end",
        "link(q) dof = (a * q) || [0, 0, 1] end",
        "link(x, y) dof1 = x * [1, 0, 0], dof2 = y * [0, a, 0] end",
    ] {
        let text = format!("{head}join earth and b with {link} as slide ;\n");
        let program = Program::from_text("set.lsd", &text, None, &Default::default());
        assert_eq!(codes(&program), Vec::<&str>::new(), "{link}");
        let set = |value: f64| Override {
            name: "a".to_string(),
            value,
        };
        match program.prepare(&[set(0.0)], &Default::default()) {
            Err(Error::Program(diagnostics)) => {
                assert_eq!(diagnostics[0].code, "E0829", "{link}");
                let d = &diagnostics[0];
                assert!(d.message.contains("of join `slide` moves nothing"), "{d}");
                assert_eq!(d.labels.len(), 2, "{link}: the link and the join");
                assert!(d.notes[0].ends_with("the values given to `a`"), "{d}");
            }
            Err(other) => panic!("{link}: {other}"),
            Ok(_) => panic!("{link}: a motionless coordinate was accepted"),
        }
        let moving = program.prepare(&[set(0.5)], &Default::default());
        assert!(moving.is_ok(), "{link}");
    }
}

fn examples() -> Vec<(PathBuf, String)> {
    crate::common::example_paths()
        .into_iter()
        .map(|p| {
            let text = std::fs::read_to_string(&p).expect("readable");
            (p, text)
        })
        .collect()
}

/// How many mutants the test runs, and the most time it may take (it takes a few seconds).
const MUTANTS: u64 = 300;
const TIME_LIMIT: Duration = Duration::from_secs(60);

/// Mutants of every example (numbers made degenerate, joints and integrators swapped, axes made
/// zero, declarations dropped or duplicated, one to three at a time) through the whole back end:
/// no panic, and all of them within the time limit.
#[test]
fn mutants_neither_panic_nor_hang() {
    let examples = examples();
    assert!(examples.len() >= 20, "the examples went missing");
    let (done, finished) = mpsc::channel();
    let current = Arc::new(AtomicU64::new(0));
    let running = current.clone();
    std::thread::spawn(move || {
        let start = Instant::now();
        let mut reached = [0; 4];
        for seed in 0..MUTANTS {
            running.store(seed, Ordering::Relaxed);
            let mut choices = Choices::new(seed);
            let (path, text) = &examples[seed as usize % examples.len()];
            let mut mutant = text.clone();
            for _ in 0..1 + choices.below(3) {
                mutant = mutate(&mutant, &mut choices);
            }
            let outcome = std::panic::catch_unwind(|| exercise(&mutant, path.parent()));
            if let Ok(stage) = outcome {
                reached[stage] += 1;
            } else {
                let _ = done.send(Err(format!(
                    "mutant {seed} of {} panicked:\n{mutant}",
                    path.display()
                )));
                return;
            }
        }
        let _ = done.send(Ok((start.elapsed(), reached)));
    });
    match finished.recv_timeout(TIME_LIMIT) {
        Ok(Ok((elapsed, reached))) => {
            eprintln!("{MUTANTS} mutants in {elapsed:.1?}: refused, no tree, not prepared, simulated: {reached:?}");
            // The mutants reach the back end: a good share of them simulated, others refused.
            assert!(reached[3] >= MUTANTS as usize / 6, "{reached:?}");
            assert!(reached[0] >= MUTANTS as usize / 20, "{reached:?}");
        }
        Ok(Err(failure)) => panic!("{failure}"),
        Err(_) => panic!(
            "the mutants took more than {TIME_LIMIT:?}: mutant {} hangs",
            current.load(Ordering::Relaxed)
        ),
    }
}

/// The shared mutator changes programs (a test of the test).
#[test]
fn mutants_differ_from_their_example() {
    let (_, text) = &examples()[0];
    let changed = (0..20)
        .filter(|&seed| mutate(text, &mut Choices::new(seed)) != *text)
        .count();
    assert!(
        changed >= 18,
        "only {changed} of 20 mutants changed the program"
    );
}

/// A zero rotation axis and a guess of 1e308 made the closure Jacobian of the delta robot NaN,
/// and the SVD of the assembly iterated on it for ever: now the configuration is refused, and
/// the tree says why its mobility is unknown. The zero axis itself is now refused where it is
/// written (E0609); the guess alone still overflows the poses.
#[test]
fn an_overflowing_configuration_is_refused() {
    let delta = std::fs::read_to_string("examples/delta_isir88.lsd").expect("readable");
    let dir = std::path::Path::new("examples");
    let overflowing = delta.replace("P3p.a = 0 guess", "P3p.a = 1e308 guess");
    let program = Program::from_text("delta.lsd", &overflowing, Some(dir), &Default::default());
    let mechanism = program.mechanism().expect("the program is valid");
    let tree = lsdc::studies::analysis::tree(mechanism).expect("a tree");
    assert!(tree.mobility.is_none());
    let why = tree.mobility_unavailable.expect("a reason");
    assert!(why.contains("not a finite number"), "{why}");
    let zero_axis = overflowing.replace("(phi || [0, 0, 1])", "(phi || [0, 0, 0])");
    let program = Program::from_text("delta.lsd", &zero_axis, Some(dir), &Default::default());
    let codes: Vec<_> = program.diagnostics().iter().map(|d| d.code).collect();
    assert_eq!(codes, ["E0609"]);
}

/// nalgebra's SVD never ends on a NaN: the project's decomposes only finite matrices.
#[test]
fn decompositions_refuse_non_finite_matrices() {
    use nalgebra::DMatrix;
    let mut m = DMatrix::<f64>::identity(3, 3);
    assert!(lsdc::linalg::svd(m.clone(), true, true).is_some());
    m[(1, 2)] = f64::NAN;
    assert!(lsdc::linalg::svd(m.clone(), true, true).is_none());
    m[(1, 2)] = f64::INFINITY;
    assert!(lsdc::linalg::pseudo_inverse(m, 1e-12).is_none());
}

/// With a damping torque beside gravity, the samples still carry the potential energy of the
/// weight (m g z of the centre of mass), the one the report's final energies count; the energy
/// is not said to drift, since it is not conserved.
#[test]
fn potential_energy_is_written_beside_non_conservative_efforts() {
    let text = "import joints ;\nlet rod = body mass = 1.2, iframe = [0, 0, -0.5] ++ 1, inertia = [0.1, 0.1, 0.001] end ;\njoin earth and rod with revolute([1, 0, 0]) as swing ;\napply force value = [0, 0, -9.81 * rod.mass], body = earth end on rod.iframe ;\napply torque value = [-0.3 * swing.q', 0, 0] end on rod ;\ninitial swing.q = pi / 3 ;\nsimulate duration = 1, output = 0.1, integrator = dopri5, tolerance = 1e-10 end ;\n";
    let program = Program::from_text("damped.lsd", text, None, &Default::default());
    let prepared = program.prepare(&[], &Default::default()).expect("prepares");
    let simulation = run(&prepared, &mut |_| {});
    assert!(simulation.report.failure.is_none());
    assert_eq!(simulation.samples.len(), 11);
    for sample in &simulation.samples {
        let height = -0.5 * sample.coordinates[0].cos();
        let expected = 1.2 * 9.81 * height;
        let potential = sample.potential_energy.expect("the weight's potential");
        assert!(
            (potential - expected).abs() < 1e-9,
            "{potential} vs {expected}"
        );
    }
    let last = simulation.samples.last().expect("a sample");
    let [_, potential, _] = simulation
        .report
        .final_energies
        .expect("the work is tracked");
    assert!((potential - last.potential_energy.unwrap_or(f64::NAN)).abs() < 1e-9);
    assert!(simulation.report.energy_drift.is_none());
}

/// `-` reads the program from standard input.
#[test]
fn a_program_is_read_from_standard_input() {
    use std::io::Write;
    use std::process::{Command, Stdio};
    let mut child = Command::new(env!("CARGO_BIN_EXE_lsdc"))
        .args(["check", "-"])
        .env_remove("LSD_PATH")
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("lsdc runs");
    let text = std::fs::read("examples/pendulum.lsd").expect("readable");
    child
        .stdin
        .take()
        .expect("stdin")
        .write_all(&text)
        .expect("written");
    let output = child.wait_with_output().expect("lsdc ends");
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert_eq!(output.status.code(), Some(0), "{stdout}");
    assert!(stdout.contains("bodies    1 (rod)"), "{stdout}");
}

/// Usage errors where JSON is asked for: `check` reports the readable files and the unreadable
/// one, exit code 2; a `--set` without a name is a usage error as JSON.
#[test]
fn usage_errors_are_json_where_json_is_asked_for() {
    let (code, stdout, _) = crate::common::lsdc(&[
        "check",
        "--format",
        "json",
        "examples/pendulum.lsd",
        "examples/no_such_file.lsd",
    ]);
    assert_eq!(code, 2);
    let value: serde_json::Value = serde_json::from_str(&stdout).expect("one JSON document");
    let files = value["files"].as_array().expect("a list of files");
    assert_eq!(files.len(), 2);
    assert_eq!(files[0]["ok"], true);
    assert_eq!(files[1]["file"], "examples/no_such_file.lsd");
    assert!(files[1]["usage_error"]
        .as_str()
        .is_some_and(|m| m.contains("cannot read")));
    let (code, stdout, _) = crate::common::lsdc(&[
        "statics",
        "--format",
        "json",
        "--actuate",
        "swing.q",
        "--set",
        "=3",
        "examples/pendulum.lsd",
    ]);
    assert_eq!(code, 2);
    let value: serde_json::Value = serde_json::from_str(&stdout).expect("one JSON document");
    assert!(value["usage_error"]
        .as_str()
        .is_some_and(|m| m.contains("no name before `=`")));
    clap_rejections_are_json_too();
}

/// Arguments clap rejects, with JSON asked for: one JSON document on standard output, clap's
/// text with its usage on standard error. Help is still help.
fn clap_rejections_are_json_too() {
    let rejected = [
        (
            vec!["tree", "--format", "json", "--no-such-option", "x.lsd"],
            "--no-such-option",
        ),
        (vec!["simulate", "--report=json"], "required"),
        (vec!["eval", "--format=json", "x.lsd"], "'--format'"),
    ];
    for (arguments, expected) in rejected {
        let (code, stdout, stderr) = crate::common::lsdc(&arguments);
        assert_eq!(code, 2, "{arguments:?}: {stderr}");
        let value: serde_json::Value = serde_json::from_str(&stdout)
            .unwrap_or_else(|e| panic!("{arguments:?}: {e}: {stdout}"));
        assert_eq!(value["ok"], false);
        let message = value["usage_error"].as_str().expect("a message");
        assert!(message.contains(expected), "{arguments:?}: {message}");
        assert!(stderr.contains("Usage:"), "{arguments:?}: {stderr}");
    }
    let (code, stdout, _) = crate::common::lsdc(&["check", "--format", "json", "--help"]);
    assert_eq!(code, 0);
    assert!(stdout.contains("Usage:"), "{stdout}");
}

/// A states file of the wrong form says what is wrong in it, not how serde tried to read it.
#[test]
fn states_files_are_explained() {
    let cases = [
        (r#"{"states": [{"v": [0]}]}"#, "missing field `q`"),
        (
            r#"{"x": 1}"#,
            "neither an object with one `states` list nor a list",
        ),
    ];
    for (text, expected) in cases {
        let error = lsdc::studies::batch::parse_states(text)
            .expect_err("refused")
            .to_string();
        assert!(error.contains(expected), "{error}");
        assert!(!error.contains("untagged"), "{error}");
    }
}

proptest::proptest! {
    /// A states file is read exactly: any finite number written with 17 significant digits, as
    /// a peer's reference values are, comes back to the same bits (serde_json's default parser
    /// could miss such a number by one unit in the last place).
    #[test]
    fn states_are_read_back_to_the_bit(bits in proptest::prelude::any::<u64>()) {
        let x = f64::from_bits(bits);
        proptest::prop_assume!(x.is_finite());
        let text = format!("[{{\"q\": [{x:.16e}, {x:?}]}}]");
        let states = lsdc::studies::batch::parse_states(&text).expect("a states file");
        proptest::prop_assert_eq!(states[0].q[0].to_bits(), x.to_bits());
        proptest::prop_assert_eq!(states[0].q[1].to_bits(), x.to_bits());
    }
}

/// A URDF's warnings are printed once each, and not at all under `--quiet`.
#[test]
fn warnings_are_printed_once_and_silenced_by_quiet() {
    let panda = "tests/fixtures/urdf/panda.urdf";
    let (code, _, stderr) = crate::common::lsdc(&["import-urdf", panda]);
    assert_eq!(code, 0);
    let warnings: Vec<&str> = stderr
        .lines()
        .filter(|l| l.starts_with("warning"))
        .collect();
    let distinct: std::collections::BTreeSet<&str> = warnings.iter().copied().collect();
    // The joints' `<dynamics>` are imported as friction: 17 warnings are left.
    assert!(warnings.len() >= 15, "{stderr}");
    assert_eq!(warnings.len(), distinct.len(), "{stderr}");
    let run = ["simulate", "--duration", "0.001", "-o", "/dev/null", panda];
    let (code, _, stderr) = crate::common::lsdc(&run);
    assert_eq!(code, 0);
    assert!(stderr.contains("warning["), "{stderr}");
    let (code, _, stderr) = crate::common::lsdc(&[&["--quiet"], &run[..]].concat());
    assert_eq!(code, 0);
    assert!(!stderr.contains("warning"), "{stderr}");
    assert!(stderr.contains("function evaluations"), "{stderr}");
}

/// `export-urdf` says which efforts the URDF leaves out.
#[test]
fn exported_urdf_names_the_efforts_left_out() {
    let (code, stdout, stderr) = crate::common::lsdc(&["export-urdf", "examples/governor.lsd"]);
    assert_eq!(code, 0);
    assert!(stdout.contains("<robot"));
    assert!(
        stderr.contains("leaves out the mechanism's efforts (gravity, 8 applied efforts)"),
        "{stderr}"
    );
}

/// Large numbers are written with an exponent in the notation table, not as 301 digits.
#[test]
fn large_numbers_are_written_with_an_exponent() {
    let text = std::fs::read_to_string("examples/pendulum.lsd")
        .expect("readable")
        .replace("mass = 1.2", "mass = 1e300");
    std::fs::write(std::env::temp_dir().join("lsdc_large_mass.lsd"), text).expect("writable");
    let path = std::env::temp_dir().join("lsdc_large_mass.lsd");
    let path = path.to_str().expect("a UTF-8 path");
    let (code, stdout, _) = crate::common::lsdc(&["compile", "--emit", "notation", path]);
    assert_eq!(code, 0);
    assert!(stdout.contains("mu_1 := 1e300"), "{stdout}");
    assert!(stdout.lines().all(|l| l.len() < 200), "{stdout}");
}

/// Many unknown names: each is reported, the first 100 with a suggestion (each suggestion
/// compares the name with every visible one, so they are bounded to keep checking linear).
#[test]
fn suggestions_for_unknown_names_are_bounded() {
    let text: String = (0..300)
        .map(|i| format!("let a{i} = 1 ;\nlet b{i} = a{i}x ;\n"))
        .collect();
    let program = Program::from_text("names.lsd", &text, None, &Default::default());
    let unknown: Vec<_> = (program.diagnostics().iter())
        .filter(|d| d.code == "E0301")
        .collect();
    assert_eq!(unknown.len(), 300);
    let suggested = unknown.iter().filter(|d| d.help.is_some()).count();
    assert_eq!(suggested, 100);
}

/// A pendulum whose weight is `weight`: a run of it from rest.
fn pendulum_weighing(weight: &str) -> lsdc::api::Simulation {
    let text = format!(
        "import joints ;\n\
         let rod = body mass = 1.2, iframe = [0, 0, -0.5] ++ 1, inertia = [0.1, 0.1, 0.001] end ;\n\
         join earth and rod with revolute([1, 0, 0]) as swing ;\n\
         apply force value = [0, 0, {weight}], body = earth end on rod.iframe ;\n\
         initial swing.q = pi / 3 ;\n\
         simulate duration = 0.1, output = 0.05 end ;\n"
    );
    let program = Program::from_text("weighed.lsd", &text, None, &Default::default());
    assert!(
        codes(&program).is_empty(),
        "{weight}: {:?}",
        codes(&program)
    );
    let prepared = program.prepare(&[], &Default::default()).expect("prepares");
    run(&prepared, &mut |_| {})
}

/// Expressions that are NaN somewhere are not folded into numbers: `(time - time) / (time -
/// time)` is 0/0 at every instant and `time / time` at t = 0, so the runs fail at t = 0 saying
/// why, where they ran as if the weight were -9.81 before.
#[test]
fn an_effort_that_is_nan_is_not_folded_into_a_number() {
    for weight in [
        "-9.81 + 5 * (time - time) / (time - time)",
        "-9.81 * time / time",
        "-9.81 + 0 * sqrt(-1 - time)",
    ] {
        let simulation = pendulum_weighing(weight);
        let failure = simulation.report.failure.as_ref();
        assert!(
            failure.is_some_and(|f| f.time == 0.0 && f.message.contains("not finite")),
            "{weight}: {failure:?}"
        );
    }
    // Where the factor is finite everywhere, 0 · x still vanishes and the run is the plain one.
    let plain = pendulum_weighing("-9.81");
    let folded = pendulum_weighing("-9.81 + 0 * sin(time) * swing.q");
    assert!(folded.report.failure.is_none());
    let last = |s: &lsdc::api::Simulation| s.samples.last().expect("samples").coordinates.clone();
    assert_eq!(last(&plain), last(&folded));
}

/// A symplectic step too long for a stiff element fails saying so: its implicit equations did
/// not converge, with the step to shorten. The governor's stiff spring at 0.01 s was reported as
/// a state that is not finite (and a loop's iterate as a singular configuration), which sent the
/// user after a fault of the mechanism.
#[test]
fn a_symplectic_step_too_long_for_the_motion_says_so() {
    let text = std::fs::read_to_string("examples/governor.lsd").expect("the example");
    let program = Program::from_text("governor.lsd", &text, None, &Default::default());
    let changes = SettingsChanges {
        integrator: Some(Integrator::Symplectic),
        step: Some(0.01),
        duration: Some(0.1),
        ..Default::default()
    };
    let prepared = program.prepare(&[], &changes).expect("prepares");
    let simulation = run(&prepared, &mut |_| {});
    let failure = simulation.report.failure.expect("fails");
    assert!(
        failure.message.contains("did not converge")
            && failure.message.contains("use a smaller `step` than 0.01")
            && !failure.message.contains("not finite"),
        "{}",
        failure.message
    );
}
