//! The built-in functions `floor` and `mod` against closed forms: on numbers (folded where they
//! are written) and on quantities known only during a run (time, a coordinate), where the
//! floored modulo is checked by its defining properties rather than by its formula.

use crate::common::programs::{example_text, simulated};

use lsdc::driver::compile_text;
use lsdc::load::LoadOptions;
use lsdc::prepare::{prepare, Settings};
use lsdc::simulate::run::Simulation;

/// The pendulum of `examples/pendulum.lsd` run with extra lines (outputs).
fn pendulum_with(lines: &str) -> Simulation {
    let text = example_text("pendulum", &[]) + lines;
    let options = LoadOptions {
        library_dirs: Vec::new(),
        use_environment: false,
    };
    let compilation = compile_text(
        "program.lsd",
        &text,
        Some(std::path::Path::new("examples")),
        &options,
    );
    assert!(!compilation.has_errors(), "{:?}", compilation.diagnostics);
    let mechanism = compilation.mechanism.expect("elaborates");
    let prepared = prepare(&mechanism, &[], &Settings::default()).expect("prepares");
    simulated(&prepared)
}

fn column(simulation: &Simulation, name: &str) -> Vec<f64> {
    let k = (simulation.output_names.iter())
        .position(|n| n == name)
        .unwrap_or_else(|| panic!("no output {name} in {:?}", simulation.output_names));
    simulation.samples.iter().map(|s| s.outputs[k]).collect()
}

#[test]
fn floor_and_mod_of_numbers_are_their_closed_forms() {
    let simulation = pendulum_with(
        "output f = floor(-2.5) ; output g = floor(3) ; output wrap = mod(-1, 3) ;
         output negative = mod(7.5, -2) ; output exact = mod(6, 3) ;",
    );
    let first = |name| column(&simulation, name)[0];
    assert_eq!(first("f"), -3.0);
    assert_eq!(first("g"), 3.0);
    // The sign of a floored modulo is the divisor's: −1 wraps to the last of 3 indices.
    assert_eq!(first("wrap"), 2.0);
    assert_eq!(first("negative"), -0.5);
    assert_eq!(first("exact"), 0.0);
}

#[test]
fn floor_and_mod_of_run_quantities_keep_their_defining_properties() {
    let simulation = pendulum_with(
        "output steps = floor(10 * time - 0.5) ; output phase = mod(time, 0.3) ;
         output turned = mod(swing.q, -0.25) ;",
    );
    let (steps, phase, turned) = (
        column(&simulation, "steps"),
        column(&simulation, "phase"),
        column(&simulation, "turned"),
    );
    for (k, sample) in simulation.samples.iter().enumerate() {
        let (t, q) = (sample.time, sample.coordinates[0]);
        // floor: an integer n with n ≤ x < n + 1.
        let x = 10.0 * t - 0.5;
        assert_eq!(steps[k].fract(), 0.0, "t = {t}");
        assert!(steps[k] <= x && x < steps[k] + 1.0, "t = {t}: {}", steps[k]);
        // mod(a, b): in [0, b) for b > 0, in (b, 0] for b < 0, and a − mod(a, b) a multiple of b.
        let multiple = |a: f64, b: f64, r: f64| {
            let n = (a - r) / b;
            (n - n.round()).abs() < 1e-9
        };
        assert!((0.0..0.3).contains(&phase[k]), "t = {t}: {}", phase[k]);
        assert!(multiple(t, 0.3, phase[k]), "t = {t}: {}", phase[k]);
        assert!(
            turned[k] <= 0.0 && turned[k] > -0.25,
            "q = {q}: {}",
            turned[k]
        );
        assert!(multiple(q, -0.25, turned[k]), "q = {q}: {}", turned[k]);
    }
    // The run crosses several periods, so the wrap is exercised.
    assert!(phase.iter().any(|&p| p > 0.2) && phase.iter().any(|&p| p < 0.1));
}
