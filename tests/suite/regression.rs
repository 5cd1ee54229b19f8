//! Regression over the example mechanisms: every example that can be simulated is simulated with
//! its own `simulate` settings, and its outputs are compared with `tests/expected/NAME.csv`
//! (written by the same simulation when the results were checked; set `UPDATE_EXPECTED=1` to
//! rewrite them after an intended change, and review the difference).
//!
//! Tolerance: 1e-8 relative to the largest magnitude of each column, which leaves room for
//! floating-point differences between machines and catches any change of the dynamics. A column
//! that is zero up to round-off (an angle that symmetry keeps at 0, at 1e-16) is compared at
//! 1e-14 of the largest column of its kind (coordinates, or rates) instead: round-off does not
//! reproduce to its own last digits.

use std::path::PathBuf;

use lsdc::driver::compile_files;
use lsdc::load::LoadOptions;
use lsdc::simulate::prepare::{prepare, Settings};
use lsdc::simulate::run::run;

/// Examples that are not simulated, and why.
const NOT_SIMULATED: &[(&str, &str)] = &[
    (
        "satellite",
        "unknowns without values and unknown torque laws (the thesis's program)",
    ),
    ("satellite_library", "the same program through a library"),
    ("link_forms", "bodies without inertia"),
    (
        "delta_isir88_ik",
        "inverse kinematics of the Delta: bodies without inertia",
    ),
    (
        "planar_triangle",
        "a kinematic loop: bodies without inertia",
    ),
];

fn parse_csv(text: &str) -> Vec<Vec<f64>> {
    text.lines()
        .skip(1)
        .filter(|l| !l.starts_with('#'))
        .map(|l| {
            l.split(',')
                .map(|x| x.parse().unwrap_or(f64::NAN))
                .collect()
        })
        .collect()
}

#[test]
fn examples_reproduce_their_expected_results() {
    let update = std::env::var_os("UPDATE_EXPECTED").is_some();
    let options = LoadOptions {
        library_dirs: Vec::new(),
        use_environment: false,
    };
    let mut examples: Vec<PathBuf> = std::fs::read_dir("examples")
        .expect("examples")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "lsd"))
        .collect();
    examples.sort();
    let mut simulated = 0;
    for path in examples {
        let name = path
            .file_stem()
            .and_then(|s| s.to_str())
            .expect("name")
            .to_string();
        let compilation = compile_files(std::slice::from_ref(&path), &options).expect("readable");
        let mechanism = compilation.mechanism.expect("examples check clean");
        let prepared = match prepare(&mechanism, &[], &Settings::default()) {
            Ok(p) => p,
            Err(d) => {
                assert!(
                    NOT_SIMULATED.iter().any(|(n, _)| *n == name),
                    "{name} cannot be simulated: {:?}",
                    d.first().map(|d| &d.message)
                );
                continue;
            }
        };
        assert!(
            !NOT_SIMULATED.iter().any(|(n, _)| *n == name),
            "{name} is simulated now: update NOT_SIMULATED"
        );
        let csv = lsdc::output::csv::to_csv(&run(&prepared, &mut |_| {}));
        let expected_path = PathBuf::from(format!("tests/expected/{name}.csv"));
        simulated += 1;
        if update {
            std::fs::write(&expected_path, &csv).expect("writable");
            continue;
        }
        let expected = std::fs::read_to_string(&expected_path)
            .unwrap_or_else(|_| panic!("{} missing", expected_path.display()));
        assert_eq!(
            csv.lines().next(),
            expected.lines().next(),
            "{name}: columns changed"
        );
        assert_eq!(
            csv.lines().last().filter(|l| l.starts_with('#')).is_some(),
            expected
                .lines()
                .last()
                .filter(|l| l.starts_with('#'))
                .is_some(),
            "{name}: the run's success changed"
        );
        let (actual, expected) = (parse_csv(&csv), parse_csv(&expected));
        assert_eq!(actual.len(), expected.len(), "{name}: number of outputs");
        let columns = expected.first().map_or(0, Vec::len);
        let largest = |c: usize| {
            expected
                .iter()
                .map(|r| r[c].abs())
                .filter(|x| x.is_finite())
                .fold(1e-300, f64::max)
        };
        // Columns: time, n coordinates, n rates, kinetic and potential energy.
        let n = (columns - 3) / 2;
        let kind = |c: usize| {
            if (1..=n).contains(&c) {
                1..=n
            } else if (n + 1..=2 * n).contains(&c) {
                n + 1..=2 * n
            } else {
                c..=c
            }
        };
        for c in 0..columns {
            let kind_scale = kind(c).map(largest).fold(0.0, f64::max);
            let scale = largest(c).max(1e-6 * kind_scale);
            for (row, (a, e)) in actual.iter().zip(&expected).enumerate() {
                let (a, e) = (a[c], e[c]);
                let same = (a.is_nan() && e.is_nan()) || (a - e).abs() <= 1e-8 * scale;
                assert!(same, "{name}: row {row}, column {c}: {a} vs {e}");
            }
        }
    }
    assert!(simulated >= 3, "only {simulated} examples simulated");
}
