//! Examples as test cases: an example's text with some of it replaced (the test's variation of
//! its scenario), prepared for a run with its own `simulate` settings, and what a run reports.
//! A name may lie in a folder of `examples/` (`hard/bennett`).

use lsdc::driver::compile_text;
use lsdc::load::LoadOptions;
use lsdc::prepare::{prepare, Prepared, Settings};
use lsdc::simulate::constraints::ConstraintReport;
use lsdc::simulate::run::{run, Simulation};

/// An example's text with some of it replaced.
pub fn example_text(name: &str, replacements: &[(&str, &str)]) -> String {
    let mut text = std::fs::read_to_string(format!("examples/{name}.lsd")).expect("example");
    for (from, to) in replacements {
        assert!(text.contains(from), "{name}: `{from}` not found");
        text = text.replace(from, to);
    }
    text
}

/// An example's mechanism, its text with some of it replaced.
pub fn mechanism(name: &str, replacements: &[(&str, &str)]) -> lsdc::elab::Mechanism {
    let options = no_library_path();
    let text = example_text(name, replacements);
    // Imports are found from the example's own folder, as the command line finds them.
    let folder = std::path::Path::new("examples")
        .join(std::path::Path::new(name).parent().unwrap_or("".as_ref()));
    let compilation = compile_text(&format!("{name}.lsd"), &text, Some(&folder), &options);
    assert!(
        !compilation.has_errors(),
        "{name}: {:?}",
        compilation.diagnostics
    );
    compilation.mechanism.expect("elaborates")
}

pub fn prepared(name: &str, replacements: &[(&str, &str)]) -> Prepared {
    let mechanism = mechanism(name, replacements);
    prepare(&mechanism, &[], &Settings::default()).unwrap_or_else(|d| {
        panic!(
            "{name}: {:?}",
            d.iter().map(|d| &d.message).collect::<Vec<_>>()
        )
    })
}

/// A program or URDF file prepared with its own settings, as `lsdc` reads it.
pub fn prepared_file(path: &str) -> Prepared {
    let compilation =
        lsdc::driver::compile_files(&[std::path::PathBuf::from(path)], &no_library_path())
            .expect("loads");
    let mechanism = compilation.mechanism.expect("elaborates");
    prepare(&mechanism, &[], &Settings::default()).unwrap_or_else(|d| panic!("{path}: {d:?}"))
}

/// A run of the example `name` with `replacements` and `settings`, its own `simulate`
/// declaration `declaration` removed so that `settings` rule.
pub fn run_example(
    name: &str,
    declaration: &str,
    replacements: &[(&str, &str)],
    settings: &Settings,
) -> Simulation {
    let mut replaced = vec![(declaration, "")];
    replaced.extend_from_slice(replacements);
    let prepared = prepare(&mechanism(name, &replaced), &[], settings)
        .unwrap_or_else(|d| panic!("{:?}", d.iter().map(|d| &d.message).collect::<Vec<_>>()));
    run(&prepared, &mut |_| {})
}

pub fn simulated(prepared: &Prepared) -> Simulation {
    let simulation = run(prepared, &mut |_| {});
    assert!(
        simulation.report.failure.is_none(),
        "{:?}",
        simulation.report.failure
    );
    simulation
}

pub fn constraints(simulation: &Simulation) -> &ConstraintReport {
    simulation
        .report
        .constraints
        .as_ref()
        .expect("a mechanism with loops")
}

pub fn column(simulation: &Simulation, name: &str) -> usize {
    simulation
        .coordinate_names
        .iter()
        .position(|n| n == name)
        .unwrap_or_else(|| panic!("no coordinate {name}"))
}

/// The column of the output `name` (a drive's effort, a state, a program's output).
pub fn output(simulation: &Simulation, name: &str) -> usize {
    (simulation.output_names.iter())
        .position(|n| n == name)
        .unwrap_or_else(|| panic!("no output {name} in {:?}", simulation.output_names))
}

/// A program's run with `settings` (its own `simulate` declaration overridden).
pub fn run_text(text: &str, settings: Settings) -> Simulation {
    let compilation = compile_text("test.lsd", text, None, &no_library_path());
    assert!(!compilation.has_errors(), "{:?}", compilation.diagnostics);
    let mechanism = compilation.mechanism.expect("elaborates");
    let prepared = prepare(&mechanism, &[], &settings).unwrap_or_else(|d| panic!("{d:?}"));
    run(&prepared, &mut |_| {})
}

/// A program prepared for a run with the default settings.
pub fn prepared_text(text: &str) -> Prepared {
    let compilation = compile_text("test.lsd", text, None, &no_library_path());
    assert!(!compilation.has_errors(), "{:?}", compilation.diagnostics);
    let mechanism = compilation.mechanism.expect("elaborates");
    prepare(&mechanism, &[], &Settings::default()).unwrap_or_else(|d| panic!("{d:?}"))
}

/// The initial state of a prepared program: positions, then velocities.
pub fn initial_state(prepared: &Prepared) -> Vec<f64> {
    let (mut y, v) = (prepared.model)
        .state_from_declared(&prepared.coordinates, &prepared.rates)
        .expect("state");
    y.extend_from_slice(&v);
    y
}

/// The codes of the diagnostics of a program that elaborates, from its preparation for a run.
pub fn refusal_codes(text: &str) -> Vec<String> {
    let compilation = compile_text("test.lsd", text, None, &no_library_path());
    let Some(mechanism) = compilation.mechanism else {
        return compilation
            .diagnostics
            .iter()
            .map(|d| d.code.to_string())
            .collect();
    };
    match prepare(&mechanism, &[], &Settings::default()) {
        Ok(_) => Vec::new(),
        Err(errors) => errors.iter().map(|d| d.code.to_string()).collect(),
    }
}

pub fn no_library_path() -> LoadOptions {
    LoadOptions {
        library_dirs: Vec::new(),
        use_environment: false,
        scene: None,
    }
}

/// The accelerations of the velocities `velocities` (named as `Model::velocity_name`) and the
/// rates of the program's states, at the prepared program's initial state as its own assembly
/// closes it, at t = 0: an evaluation of the closed-loop model independent of a
/// linearisation's chart.
pub fn assembled_rates(prepared: &Prepared, velocities: &[&str]) -> (Vec<f64>, Vec<f64>) {
    use lsdc::dynamics::loops::Stabilisation;
    use lsdc::simulate::system::MechanicalSystem;
    let model = &prepared.model;
    let mut y = initial_state(prepared);
    let reference = prepared.coordinates.clone();
    let mut system = MechanicalSystem::new(model, reference, Stabilisation::Projection);
    system.start_loops(&mut y).unwrap();
    let mut dydt = vec![0.0; y.len()];
    system.derivative(0.0, &y, &mut dydt).unwrap();
    let mut states = vec![0.0; model.states.len()];
    system.state_rates(&mut states).unwrap();
    let names: Vec<String> = (0..model.velocities())
        .map(|i| model.velocity_name(i))
        .collect();
    let accelerations = velocities
        .iter()
        .map(|a| dydt[model.positions() + names.iter().position(|n| n == a).unwrap()])
        .collect();
    (accelerations, states)
}

/// `examples/four_bar.lsd` made a parallelogram (bars 3, 1, 3, 1), its crank at 1 rad turning at
/// 3 rad/s through its flat configurations, dopri5 at 1e-12 over 5 s, outputs every 1 ms.
pub fn parallelogram() -> Prepared {
    prepared(
        "four_bar",
        &[
            ("let l0 = 4.0 ;", "let l0 = 3.0 ;"),
            ("let l2 = 3.5 ;", "let l2 = 3.0 ;"),
            ("let l3 = 3.0 ;", "let l3 = 1.0 ;"),
            ("duration = 10, output = 0.05", "duration = 5, output = 0.001"),
            ("initial crank.q = 1.0, coupler.q = -0.36 guess, rocker.q = 1.79 guess, c.q = 1.15 guess ;", "initial crank.q = 1.0 fixed, coupler.q = -1.0, rocker.q = 1.0, c.q = 1.0, crank.q' = 3 ;"),
        ],
    )
}
