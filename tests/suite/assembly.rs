//! Assembly respects what the program gives: `fixed` values are held, given values are kept
//! whenever a closed configuration holds them, and otherwise the smallest change is made and
//! reported (W0801); `guess` values are starting points only. Oracle: a parallelogram
//! four-bar, whose closed configurations are known in closed form (both cranks at the same
//! angle φ, the coupler's joints at −φ and φ).

use lsdc::analysis::{assembled_model, AssemblyReport};
use lsdc::diag::Diagnostic;
use lsdc::driver::compile_text;
use lsdc::load::LoadOptions;

use crate::common::programs::example_text;

/// The parallelogram (row of one four-bar) with its `initial` positions replaced.
fn parallelogram(initial: &str) -> String {
    example_text(
        "hard/four_bar_row_1",
        &[(
            "initial c0.q = -pi / 2 fixed,\n  c1.q = -pi / 2,\n  p1.q = pi / 2,\n  e1.q = -pi / 2 ;",
            initial,
        )],
    )
}

fn assembled(text: &str) -> (AssemblyReport, Vec<Diagnostic>) {
    let options = LoadOptions {
        library_dirs: Vec::new(),
        use_environment: false,
    };
    let compilation = compile_text("parallelogram.lsd", text, None, &options);
    assert!(!compilation.has_errors(), "{:?}", compilation.diagnostics);
    let mechanism = compilation.mechanism.expect("elaborates");
    let topology = lsdc::topology::build(&mechanism).expect("topology");
    let (_, report, warnings) =
        assembled_model(&mechanism, topology, &Default::default()).expect("assembles");
    (report, warnings)
}

fn value(report: &AssemblyReport, name: &str) -> f64 {
    report
        .coordinates
        .iter()
        .find(|c| c.name == name)
        .unwrap_or_else(|| panic!("no coordinate {name}"))
        .value
}

/// Checks the closed form of the parallelogram branch at crank angle `phi`.
fn on_parallelogram_branch(report: &AssemblyReport, phi: f64) {
    for (name, expected) in [("c0.q", phi), ("c1.q", phi), ("p1.q", -phi), ("e1.q", phi)] {
        let got = value(report, name);
        assert!(
            (got - expected).abs() < 1e-12,
            "{name}: {got} vs {expected}"
        );
    }
}

#[test]
fn a_given_crank_is_kept_when_the_loop_closes_without_moving_it() {
    // The loop's own coordinates are not given: they close the loop, the crank stays at 1.
    let (report, warnings) = assembled(&parallelogram("initial c0.q = 1.0 ;"));
    assert_eq!(value(&report, "c0.q"), 1.0);
    on_parallelogram_branch(&report, 1.0);
    assert!(
        warnings.is_empty() && report.moved.is_empty(),
        "{warnings:?}"
    );
}

#[test]
fn inconsistent_given_values_move_the_least_and_are_reported() {
    // Both cranks turn together: given 1.0 and 0.9, the nearest closed configuration puts both
    // at 0.95, each moved by 0.05.
    let (report, warnings) = assembled(&parallelogram("initial c0.q = 1.0, c1.q = 0.9 ;"));
    on_parallelogram_branch(&report, 0.95);
    assert_eq!(warnings.len(), 1, "{warnings:?}");
    let warning = &warnings[0];
    assert_eq!(warning.code, "W0801");
    assert_eq!(warning.message, "assembly moved 2 given values");
    assert!(warning
        .notes
        .iter()
        .any(|n| n.starts_with("`c0.q` from 1 to 0.95")));
    assert!(warning
        .notes
        .iter()
        .any(|n| n.starts_with("`c1.q` from 0.9 to 0.9")));
    let moved: Vec<(&str, f64)> = report
        .moved
        .iter()
        .map(|m| (m.name.as_str(), m.given))
        .collect();
    assert_eq!(moved, [("c0.q", 1.0), ("c1.q", 0.9)]);
}

#[test]
fn a_fixed_value_wins_over_a_given_one() {
    let (report, warnings) = assembled(&parallelogram("initial c0.q = 1.0 fixed, c1.q = 0.9 ;"));
    on_parallelogram_branch(&report, 1.0);
    assert_eq!(warnings.len(), 1, "{warnings:?}");
    assert!(
        warnings[0]
            .message
            .starts_with("assembly moved `c1.q` from 0.9 to "),
        "{}",
        warnings[0].message
    );
    assert_eq!(report.moved.len(), 1);
}

#[test]
fn guesses_are_moved_silently_and_choose_the_branch() {
    // Guesses near the crossed (anti-parallelogram) branch lead there; near the parallelogram,
    // to it. Neither is a warning.
    let (parallel, warnings) = assembled(&parallelogram(
        "initial c0.q = 1.0 fixed, c1.q = 0.9 guess, p1.q = -0.9 guess, e1.q = 1.1 guess ;",
    ));
    on_parallelogram_branch(&parallel, 1.0);
    assert!(warnings.is_empty(), "{warnings:?}");
    let (crossed, warnings) = assembled(&parallelogram(
        "initial c0.q = 1.0 fixed, c1.q = 4.2 guess, p1.q = 4.2 guess, e1.q = 5.3 guess ;",
    ));
    assert!(warnings.is_empty(), "{warnings:?}");
    assert!(
        (value(&crossed, "c1.q") - 1.0).abs() > 1.0,
        "{:?}",
        crossed.coordinates
    );
}

#[test]
fn a_starting_velocity_cannot_be_a_guess() {
    let text = parallelogram("initial c0.q = 1.0, c0.q' = 2 guess ;");
    let options = LoadOptions {
        library_dirs: Vec::new(),
        use_environment: false,
    };
    let compilation = compile_text("parallelogram.lsd", &text, None, &options);
    let error = compilation
        .diagnostics
        .iter()
        .find(|d| d.code == "E0416")
        .expect("E0416");
    assert_eq!(error.message, "a starting velocity cannot be `guess`");
}
