//! `simulate --compiled` on closed loops: the accelerations solved on the run's kept rows in the
//! generated code (`symbolic::kept_rows_solve`), the projection after each step the simulator's
//! own (also where the mass matrix is singular on the tree, as for the reduced Delta's point
//! nacelle), with ball joints in the simulator's quaternion state and the rods' spins held at
//! rest as the full Delta's. The runs must give the interpreted motion and keep the loops as closed; a native code
//! that is not the mechanism's is refused by the check at the start.

use crate::common::{c_compiler, lsdc_with};
use std::path::{Path, PathBuf};

use lsdc::driver::compile_text;
use lsdc::load::LoadOptions;
use lsdc::prepare::native::Unavailable;
use lsdc::prepare::{prepare, Settings};
use lsdc::simulate::compiled;

fn fresh_cache(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("lsdc-native-loops-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

/// `lsdc simulate FILE ARGS --format json --report json` with the cache and the compiler:
/// samples (JSON), report (JSON, at the end of standard error) and standard error.
fn simulate(
    file: &str,
    args: &[&str],
    cache: &Path,
    compiler: &str,
) -> (serde_json::Value, serde_json::Value, String) {
    let arguments: Vec<&str> = ["simulate", file, "--format", "json", "--report", "json"]
        .into_iter()
        .chain(args.iter().copied())
        .collect();
    let environment = [
        ("LSDC_CACHE_DIR", cache.as_os_str()),
        ("CC", std::ffi::OsStr::new(compiler)),
    ];
    let (code, stdout, stderr) = lsdc_with(&arguments, &environment);
    assert_eq!(code, 0, "{file}: {stderr}");
    let samples = serde_json::from_str(&stdout).expect("JSON samples");
    // The report is the last object of standard error, after any warning.
    let start = match stderr.starts_with('{') {
        true => 0,
        false => stderr.rfind("\n{").expect("a report") + 1,
    };
    let report = serde_json::from_str(&stderr[start..]).expect("JSON report");
    (samples, report, stderr)
}

/// Every number of the samples, in order, but the work of non-conservative efforts, which a
/// native run does not track (W0905: the shorted motors of the Delta).
fn numbers(samples: &serde_json::Value) -> Vec<f64> {
    fn walk(value: &serde_json::Value, out: &mut Vec<f64>) {
        match value {
            serde_json::Value::Number(n) => out.extend(n.as_f64()),
            serde_json::Value::Array(items) => items.iter().for_each(|v| walk(v, out)),
            serde_json::Value::Object(map) => (map.iter())
                .filter(|(key, _)| *key != "work")
                .for_each(|(_, v)| walk(v, out)),
            _ => {}
        }
    }
    let mut out = Vec::new();
    walk(&samples["samples"], &mut out);
    out
}

/// The largest difference of two runs' samples, relative to 1 + |value|.
fn difference(a: &serde_json::Value, b: &serde_json::Value) -> f64 {
    let (a, b) = (numbers(a), numbers(b));
    assert_eq!(a.len(), b.len(), "as many values");
    assert!(a.len() > 100, "{} values", a.len());
    (a.iter().zip(&b))
        .map(|(x, y)| (x - y).abs() / (1.0 + y.abs()))
        .fold(0.0, f64::max)
}

/// What a native run of a loop is judged against, beside the interpreted run of the same file.
enum Oracle {
    /// The interpreted run, to this bound.
    Interpreted(f64),
    /// The interpreted run to this bound, and the interpreted run at a tolerance of 1e-13: the
    /// native run no further from it than twice the interpreted run at the program's is.
    InterpretedAndTight(f64),
    /// The exact motion (samples in the shape of the runs'): the interpreted and the native run
    /// each within `bound` of it, and so within twice `bound` of each other.
    Exact {
        samples: serde_json::Value,
        bound: f64,
    },
}

/// Runs `file` for 1 s interpreted and with `--compiled` (at the program's tolerance): the
/// native code must serve, the loops stay as closed, and the samples agree as `oracle` says.
/// Runs through singular configurations, where the simulator's step control reads the loops'
/// conditioning from its own evaluations, take other steps interpreted and native.
fn agrees_with_the_runs(file: &str, name: &str, oracle: Oracle) {
    let Some(compiler) = c_compiler() else {
        crate::common::skip("no C compiler found (CC, cc, gcc, clang), --compiled is not checked");
        return;
    };
    let cache = fresh_cache(name);
    let args = ["--duration", "1", "--every", "0.02"];
    let (interpreted, interpreted_report, _) = simulate(file, &args, &cache, &compiler);
    let compiled_args = [&args[..], &["--compiled"]].concat();
    let (compiled, report, stderr) = simulate(file, &compiled_args, &cache, &compiler);
    assert!(
        !stderr.contains("W0904"),
        "the native code serves: {stderr}"
    );
    let apart = difference(&compiled, &interpreted);
    let bound = match oracle {
        Oracle::Interpreted(bound) => bound,
        Oracle::InterpretedAndTight(bound) => {
            let tight = [&args[..], &["--tolerance", "1e-13"]].concat();
            let (reference, _, _) = simulate(file, &tight, &cache, &compiler);
            let own = difference(&interpreted, &reference);
            let native = difference(&compiled, &reference);
            assert!(
                native <= 2.0 * own,
                "{file}: the native run is {native:e} from the reference, the interpreted {own:e}"
            );
            bound
        }
        Oracle::Exact { samples, bound } => {
            for (run, name) in [(&interpreted, "interpreted"), (&compiled, "native")] {
                let error = difference(run, &samples);
                assert!(
                    error <= bound,
                    "{file}: the {name} run is {error:e} from the exact motion (bound {bound:e})"
                );
            }
            2.0 * bound
        }
    };
    assert!(
        apart <= bound,
        "{file}: compiled and interpreted samples differ by {apart:e} (bound {bound:e})"
    );
    // The projection still closes every state the run goes on from, as interpreted.
    for key in ["position_residual", "velocity_residual"] {
        let native = report["constraints"][key].as_f64().expect(key);
        let own = interpreted_report["constraints"][key].as_f64().expect(key);
        assert!(
            native <= 1e-12_f64.max(10.0 * own),
            "{file}: {key} {native:e} compiled, {own:e} interpreted"
        );
    }
    let _ = std::fs::remove_dir_all(&cache);
}

#[test]
fn a_four_bar_runs_natively_as_interpreted() {
    // No singular configuration on the way: the same equations, to round-off.
    agrees_with_the_runs(
        "examples/four_bar.lsd",
        "four-bar",
        Oracle::Interpreted(1e-10),
    );
}

#[test]
fn a_row_of_two_four_bars_runs_natively_as_interpreted() {
    // Judged by the row's exact motion (phi'' = -K cos(phi) / J at 30 digits, the fixture's
    // provenance), not by a run of the same code: a run at 1e-13 was once further from the
    // motion than the run at 1e-10 it judged (BENCHMARKS.md, "the row of two four-bars").
    //
    // The bound, from the run's tolerance tol = 1e-10 (the program's; dopri5, rtol = atol,
    // each step's local error held to tol (1 + |y|), the scale of the measure here) as the sum
    // of two parts, each measured where the other is negligible (interpreted and native runs
    // against the fixture):
    // - the integration's global error, proportional to the tolerance (Hairer, Nørsett &
    //   Wanner, "Solving Ordinary Differential Equations I", §II.4, tolerance
    //   proportionality): 5.3 tol at 1e-8, 6.2 and 6.6 tol at 1e-9; counted as 10 tol;
    // - the passage through the flat configuration, where the rows set aside are released for
    //   a stretch of some tens of µs and the restore leaves a phase error that the tolerance
    //   does not reduce: 1.2e-10 to 3.4e-10 at tolerances 1e-11 to 1e-13; counted as 5e-10.
    // So 10 tol + 5e-10 = 1.5e-9 (measured at 1e-10: 7.9e-10 interpreted, 7.7e-10 native).
    // Tried: the run at 100 times the tolerance is 5.3e-8 from the motion; in the generated
    // code, one crank's weight with a wrong sign or dropped puts the native run 3.6 or 1.7
    // away, and that weight 1e-8 too large (relative) puts it 1.5e-8 away.
    let exact: serde_json::Value =
        serde_json::from_str(include_str!("../fixtures/hard/four_bar_row_2_exact.json"))
            .expect("the exact motion");
    let tolerance = 1e-10;
    let oracle = Oracle::Exact {
        samples: exact,
        bound: 10.0 * tolerance + 5e-10,
    };
    agrees_with_the_runs("examples/hard/four_bar_row_2.lsd", "row-2", oracle);
}

#[test]
fn the_reduced_delta_runs_natively_as_interpreted() {
    // Its nacelle is a point mass at the universal joint P1 of the tree, so P1's rows of M are
    // zero while the constrained system is regular: P1's coordinates pivot on kept rows as the
    // closing joints' do (`kept_rows_solve`), a solve of other sums than the simulator's
    // sparse factorisation, checked at the start against it to 1e-9. The arms sink under
    // gravity against the shorted motors, far from any singular configuration; the implicit
    // integrator's steps follow the round-off apart, and the runs
    // agree to the program's tolerance, 1e-10 (measured: 5.4e-11, and the interpreted run is
    // 4.6e-11 from itself at 1e-13).
    agrees_with_the_runs(
        "examples/delta_isir88_reduced.lsd",
        "delta-reduced",
        Oracle::Interpreted(1e-10),
    );
}

#[test]
fn the_full_delta_runs_natively_as_interpreted() {
    // Ten bodies, 15 ball joints: the simulator integrates the tree's seven as quaternions with
    // their body-axis angular velocities, which the native code takes as they are
    // (`symbolic::quaternion_joints`); the five closing ones keep their declared angles, left
    // at rest (no kept row touches them). The six rods' spins about their own axes move no
    // mass: the run holds at rest those it chose to (`Massive`), and the native code takes
    // the same rates out with their equations (`kept_rows_solve`). The start check holds them
    // to 1e-9; over 1 s the runs agree to the program's tolerance, 1e-10 (measured: 9.2e-11),
    // and the native run is nearer the interpreted run at 1e-13 than the interpreted run at
    // the program's tolerance is (measured: 5.9e-11 against 7.0e-11).
    agrees_with_the_runs(
        "examples/delta_isir88.lsd",
        "delta",
        Oracle::InterpretedAndTight(1e-10),
    );
}

#[test]
fn a_nacelle_without_inertia_about_an_oblique_axis_runs_natively_as_interpreted() {
    // The reduced Delta whose nacelle has inertia about every axis but one, in the plane of
    // its universal joint P1's axes at the start (the bisector of the first axis and the
    // second, turned by P1.a = 1.19631 rad): M is singular on the tree there though no row of
    // it is zero, so the plain order finds a pivot of round-off and the accelerations are
    // eliminated with the augmented M + ρ GᵀG (`kept_rows_solve`). The nacelle only
    // translates (the loops hold it parallel to the base), so the motion is the reduced
    // Delta's, and so is the agreement (measured: 5.4e-11).
    let text = std::fs::read_to_string("examples/delta_isir88_reduced.lsd").expect("example");
    let nacelle = "let nacelle = body mass = M3, \
        iframe = (1.3091671797075548 || [0, 0.6581016617114844, 0.7071067811865475]) \
        * ([0, 0, 0] ++ 1), inertia = [0, 1e-5, 1e-5] end ;";
    let text = text.replacen("let nacelle = nacelle_body() ;", nacelle, 1);
    assert!(text.contains("inertia = [0, 1e-5"), "the nacelle replaced");
    let directory = fresh_cache("oblique-program");
    std::fs::create_dir_all(directory.join("lib")).expect("a directory");
    let masses = std::fs::read_to_string("examples/lib/delta_masses.lsd").expect("library");
    std::fs::write(directory.join("lib/delta_masses.lsd"), masses).expect("written");
    let file = directory.join("delta_oblique.lsd");
    std::fs::write(&file, text).expect("written");
    agrees_with_the_runs(
        file.to_str().expect("a path"),
        "oblique",
        Oracle::Interpreted(1e-10),
    );
    let _ = std::fs::remove_dir_all(&directory);
}

/// The four-bar's program, with the weight of its coupler `factor` times its own.
fn four_bar(factor: &str) -> lsdc::elab::mechanism::Mechanism {
    let text = std::fs::read_to_string("examples/four_bar.lsd").expect("example");
    let weight = format!("apply weight_in(bar2, [0, -9.81 * {factor}, 0])");
    let text = text.replacen("apply weight_in(bar2, down)", &weight, 1);
    let options = LoadOptions {
        library_dirs: Vec::new(),
        use_environment: false,
        scene: None,
    };
    let directory = Some(Path::new("examples"));
    let compilation = compile_text("four_bar.lsd", &text, directory, &options);
    compilation.mechanism.expect("compiles")
}

#[test]
fn native_loops_that_are_not_the_mechanisms_are_refused() {
    let Some(compiler) = c_compiler() else {
        crate::common::skip("no C compiler found (CC, cc, gcc, clang), --compiled is not checked");
        return;
    };
    // The library's cache and compiler are the process's (`native::build` reads them from the
    // environment), and setting the environment beside other tests' threads is a race: the
    // work runs in a process of its own, started with them set.
    let cache = std::env::temp_dir().join(format!("lsdc-native-refused-{}", std::process::id()));
    let name = "native_loops::native_loops_that_are_not_the_mechanisms_are_refused";
    let environment = [
        ("LSDC_CACHE_DIR", cache.as_os_str()),
        ("CC", std::ffi::OsStr::new(&compiler)),
    ];
    if !crate::common::alone(name, &environment) {
        let _ = std::fs::remove_dir_all(&cache);
        return;
    }
    let (own, other) = (four_bar("1"), four_bar("1.5"));
    let mut prepared = prepare(&own, &[], &Settings::default()).expect("prepares");
    compiled::attach(&mut prepared, &own).expect("its own native code serves");
    // The native code of a four-bar whose coupler is heavier: the check at the start sees it.
    let mut prepared = prepare(&own, &[], &Settings::default()).expect("prepares");
    match compiled::attach(&mut prepared, &other) {
        Err(Unavailable::Disagrees { largest }) => assert!(largest > 1e-6, "{largest:e}"),
        other => panic!("refused for its disagreement, not {other:?}"),
    }
    assert!(prepared.native.is_none());
}
