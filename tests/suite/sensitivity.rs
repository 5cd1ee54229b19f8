//! `lsdc sensitivity`: the forward sensitivities against central differences of whole runs
//! (each run at p ± h, as `lsdc sweep` would run it, at a tight tolerance) on the pendulum (its
//! length, mass and initial angle), the double pendulum (a length, initial values), a linear
//! spring-damper, the geared arm (rotors) and the PI-controlled flywheel (efforts and a state from the tape); against
//! closed forms (the small-angle pendulum's d(q)/d(q₀) and d(q)/d(q₀'), the spring-damper's
//! solution differentiated by complex steps); and the command's output and diagnostics
//! (golden files under `tests/golden/sensitivity/`: `NAME.args`, the arguments after `lsdc
//! sensitivity`, and `NAME.stderr`; `UPDATE_GOLDEN=1` rewrites them).

use nalgebra::Complex;

use crate::common::programs::example_text;
use crate::common::{check_command_goldens, lsdc};
use lsdc::driver::compile_text;
use lsdc::elab::Mechanism;
use lsdc::kinematics::unknowns::Override;
use lsdc::prepare::settings::SettingsChanges;
use lsdc::prepare::{prepare, Prepared, Settings};
use lsdc::simulate::run::{run_from, Sample, Start};
use lsdc::studies::sensitivity::{sensitivities, Sensitivities, DIFFERENCED, EXACT};

/// The tolerance of every run here: the differences of whole runs need runs far more accurate
/// than the agreement asked of them (a run's error, over the step of the difference).
const TOLERANCE: f64 = 1e-12;

fn mechanism_of(name: &str, text: &str) -> Mechanism {
    let folder = std::path::Path::new("examples")
        .join(std::path::Path::new(name).parent().unwrap_or("".as_ref()));
    let compilation = compile_text(
        &format!("{name}.lsd"),
        text,
        Some(&folder),
        &Default::default(),
    );
    assert!(!compilation.has_errors(), "{:?}", compilation.diagnostics);
    compilation.mechanism.expect("elaborates")
}

fn changes(duration: f64, output: f64) -> SettingsChanges {
    SettingsChanges {
        duration: Some(duration),
        output: Some(output),
        tolerance: Some(TOLERANCE),
        ..Default::default()
    }
}

fn names(names: &[&str]) -> Vec<String> {
    names.iter().map(|s| s.to_string()).collect()
}

/// A sample's quantities in the order of the study's: coordinates, rates, states and outputs.
fn quantities(sample: &Sample) -> Vec<f64> {
    (sample.coordinates.iter().chain(&sample.rates))
        .chain(&sample.outputs)
        .copied()
        .collect()
}

/// The samples' quantities of a whole run of `mechanism` with `overrides`, and the declared
/// start moved by `moved(coordinates, rates)`.
fn whole_run(
    mechanism: &Mechanism,
    overrides: &[Override],
    changes: &SettingsChanges,
    moved: impl Fn(&Prepared, &mut Vec<f64>, &mut Vec<f64>),
) -> Vec<Vec<f64>> {
    let mut prepared = prepare(mechanism, overrides, &Settings::default()).expect("prepares");
    prepared.settings.apply(changes).unwrap();
    let (mut coordinates, mut rates) = (prepared.coordinates.clone(), prepared.rates.clone());
    moved(&prepared, &mut coordinates, &mut rates);
    let start = Start {
        coordinates: &coordinates,
        rates: &rates,
    };
    let simulation = run_from(&prepared, &start, &mut |_| {});
    assert!(
        simulation.report.failure.is_none(),
        "{:?}",
        simulation.report.failure
    );
    simulation.samples.iter().map(quantities).collect()
}

/// d(quantities)/d(parameter j) at each sample by the central difference of whole runs at
/// p ± h, h = `relative` max(1, |p|).
fn differences_of_runs(
    mechanism: &Mechanism,
    changes: &SettingsChanges,
    study: &Sensitivities,
    j: usize,
    relative: f64,
) -> Vec<Vec<f64>> {
    let parameter = &study.parameters[j];
    let h = relative * parameter.value.abs().max(1.0);
    let run_at = |value: f64| match parameter.kind {
        "initial value" => whole_run(mechanism, &[], changes, |prepared, coordinates, rates| {
            let (name, declared) = match parameter.name.strip_suffix('\'') {
                Some(name) => (name, &mut *rates),
                None => (parameter.name.as_str(), &mut *coordinates),
            };
            let index = (prepared.coordinate_names.iter()).position(|n| n == name);
            declared[index.expect("a declared coordinate")] = value;
        }),
        _ => {
            let moved = Override {
                name: parameter.name.clone(),
                value,
            };
            whole_run(mechanism, &[moved], changes, |_, _, _| {})
        }
    };
    let (plus, minus) = (run_at(parameter.value + h), run_at(parameter.value - h));
    let width = (parameter.value + h) - (parameter.value - h);
    (plus.iter().zip(&minus))
        .map(|(p, m)| p.iter().zip(m).map(|(a, b)| (a - b) / width).collect())
        .collect()
}

/// The differences of whole runs at steps h and h/2 extrapolated (Richardson: (4 D(h/2) −
/// D(h)) / 3), so that their truncation error, h² times the third derivative, falls to h⁴: on
/// the double pendulum the plain difference at h = 2e-4 is off by 1.5e-6 relative, falling as
/// h² (3.7e-7 at h/2), while the sensitivities agree with the extrapolation to 3e-8.
fn extrapolated_differences(
    mechanism: &Mechanism,
    changes: &SettingsChanges,
    study: &Sensitivities,
    j: usize,
    relative: f64,
) -> Vec<Vec<f64>> {
    let coarse = differences_of_runs(mechanism, changes, study, j, relative);
    let fine = differences_of_runs(mechanism, changes, study, j, relative / 2.0);
    (coarse.iter().zip(&fine))
        .map(|(c, f)| c.iter().zip(f).map(|(c, f)| (4.0 * f - c) / 3.0).collect())
        .collect()
}

/// For each column of parameter j, the largest difference between the study and the runs'
/// differences over the samples, relative to the column's largest magnitude (columns that
/// stay within 1e-9 of zero measured against 1).
fn worst_relative(study: &Sensitivities, j: usize, runs: &[Vec<f64>]) -> (f64, String) {
    let count = study.parameters.len();
    assert_eq!(runs.len(), study.samples.len());
    let mut worst = (0.0, String::new());
    for (k, quantity) in study.quantities.iter().enumerate() {
        let column =
            |samples: &mut dyn Iterator<Item = f64>| samples.fold(0.0f64, |m, x| m.max(x.abs()));
        let scale = column(&mut runs.iter().map(|r| r[k]));
        let scale = if scale < 1e-9 { 1.0 } else { scale };
        let error = column(
            &mut (study.samples.iter().zip(runs)).map(|(s, r)| s.derivatives[k * count + j] - r[k]),
        );
        if error / scale > worst.0 {
            worst = (
                error / scale,
                format!("d({quantity})/d({})", study.parameters[j].name),
            );
        }
    }
    worst
}

/// Every parameter's columns agree with the (extrapolated) differences of whole runs within
/// 1e-6 relative, ∂f/∂x S computed by `route` (`EXACT` where gravity alone acts, `DIFFERENCED`
/// where the tape's efforts do).
fn check_against_runs(
    mechanism: &Mechanism,
    parameters: &[&str],
    changes: &SettingsChanges,
    route: &str,
) {
    let study = sensitivities(mechanism, &[], changes, &names(parameters)).expect("computes");
    assert!(study.report.failure.is_none(), "{:?}", study.report.failure);
    assert_eq!(study.report.state_derivatives, route);
    for j in 0..parameters.len() {
        let runs = extrapolated_differences(mechanism, changes, &study, j, 1e-4);
        let (error, column) = worst_relative(&study, j, &runs);
        eprintln!("{column}: {error:.2e} relative");
        assert!(error <= 1e-6, "{column}: {error:e} relative");
    }
}

const PENDULUM: &str = "import joints ;
let L = ?s ;
let rod = body iframe = [0, 0, -L] ++ 1, inertia = [0.1, 0.1, 0.001] end ;
join earth and rod with revolute([1, 0, 0]) as swing ;
apply force value = [0, 0, -9.81 * rod.mass], body = earth end on rod.iframe ;
given L = 0.5, rod.mass = 1.2 ;
initial swing.q = pi / 3 ;
output tip_y = 2 * L * sin(swing.q) ;
";

#[test]
fn pendulum_length_mass_and_angle_agree_with_differences_of_runs() {
    let mechanism = mechanism_of("pendulum", PENDULUM);
    let parameters = ["L", "mass(rod)", "swing.q", "swing.q'"];
    check_against_runs(&mechanism, &parameters, &changes(3.0, 0.1), EXACT);
}

#[test]
fn double_pendulum_agrees_with_differences_of_runs() {
    let text = example_text(
        "double_pendulum",
        &[("let l1 = 1 ;", "let l1 = ?s ; given l1 = 1 ;")],
    );
    let mechanism = mechanism_of("double_pendulum", &text);
    let parameters = ["l1", "shoulder.q", "elbow.q'"];
    check_against_runs(&mechanism, &parameters, &changes(2.0, 0.05), EXACT);
}

/// Geared rotors: reflected inertia and gyroscopic coupling in the equations differentiated.
#[test]
fn geared_arm_agrees_with_differences_of_runs() {
    let mechanism = mechanism_of("geared_arm", &example_text("geared_arm", &[]));
    check_against_runs(
        &mechanism,
        &["shoulder.q", "elbow.q'"],
        &changes(1.0, 0.05),
        EXACT,
    );
}

const SPRING_DAMPER: &str = "import joints ;
let k = ?s ;
let c = ?s ;
let block = body iframe = 1, inertia = [1, 1, 1] end ;
join earth and block with prismatic([1, 0, 0]) as slide ;
apply force value = [-k * slide.q - c * slide.q', 0, 0], body = earth end on block ;
given k = 4, c = 0.6, block.mass = 1.5 ;
initial slide.q = 0.1, slide.q' = -0.2 ;
";

#[test]
fn spring_damper_agrees_with_differences_of_runs() {
    let mechanism = mechanism_of("spring_damper", SPRING_DAMPER);
    let parameters = ["k", "c", "mass(block)", "slide.q", "slide.q'"];
    check_against_runs(&mechanism, &parameters, &changes(5.0, 0.1), DIFFERENCED);
}

/// Efforts from the tape with a state of the program: the PI loop's torque reads the speed
/// and the integral, whose rate reads the speed; its gain a value of the program.
#[test]
fn pi_flywheel_agrees_with_differences_of_runs() {
    let text = example_text(
        "control/pi_flywheel",
        &[("let k_p = 1 ;", "let k_p = ?s ; given k_p = 1 ;")],
    );
    let mechanism = mechanism_of("control/pi_flywheel", &text);
    check_against_runs(
        &mechanism,
        &["k_p", "spin.q'"],
        &changes(3.0, 0.05),
        DIFFERENCED,
    );
}

/// x(t) of m x'' + c x' + k x = 0 from (x₀, v₀), underdamped, for complex arguments.
fn spring_damper_position(t: f64, [m, c, k, x0, v0]: [Complex<f64>; 5]) -> Complex<f64> {
    let sigma = c / (m * 2.0);
    let damped = (k / m - sigma * sigma).sqrt();
    (-sigma * t).exp() * (x0 * (damped * t).cos() + (v0 + sigma * x0) / damped * (damped * t).sin())
}

/// The spring-damper's d(x)/d(p) against its closed form differentiated by a complex step
/// (Squire & Trapp 1998: Im f(p + i h)/h, exact to round-off for h = 1e-30).
#[test]
fn spring_damper_matches_its_closed_form() {
    let mechanism = mechanism_of("spring_damper", SPRING_DAMPER);
    let parameters = ["mass(block)", "c", "k", "slide.q", "slide.q'"];
    let study = sensitivities(&mechanism, &[], &changes(5.0, 0.1), &names(&parameters)).unwrap();
    let nominal = [1.5, 0.6, 4.0, 0.1, -0.2];
    let mut worst: f64 = 0.0;
    for sample in &study.samples {
        for j in 0..parameters.len() {
            let arguments: [Complex<f64>; 5] =
                std::array::from_fn(|i| Complex::new(nominal[i], if i == j { 1e-30 } else { 0.0 }));
            let exact = spring_damper_position(sample.time, arguments).im / 1e-30;
            // slide.q is the first quantity: its columns come first.
            worst = worst.max((sample.derivatives[j] - exact).abs());
        }
    }
    assert!(worst < 1e-9, "{worst:e}");
}

/// About the pendulum at rest hanging down, the variational equation is the small-angle
/// one: d(q)/d(q₀) = cos ωt and d(q)/d(q₀') = sin(ωt)/ω, ω² = m g a / I (examples/pendulum.lsd:
/// m = 1.2, a = 0.5, I = 0.1 + m a² = 0.4 about the axis).
#[test]
fn pendulum_at_rest_matches_the_small_angle_closed_form() {
    let text = example_text("pendulum", &[("initial swing.q = pi / 3 ;", "")]);
    let mechanism = mechanism_of("pendulum", &text);
    let parameters = names(&["swing.q", "swing.q'"]);
    let study = sensitivities(&mechanism, &[], &changes(5.0, 0.05), &parameters).unwrap();
    let omega = (1.2 * 9.81 * 0.5 / 0.4f64).sqrt();
    let mut worst: f64 = 0.0;
    for sample in &study.samples {
        let t = sample.time;
        worst = worst.max((sample.derivatives[0] - (omega * t).cos()).abs());
        worst = worst.max((sample.derivatives[1] - (omega * t).sin() / omega).abs());
    }
    assert!(study.samples.len() == 101);
    assert!(worst < 1e-9, "{worst:e}");
}

/// The CSV names a column per quantity and parameter; JSON adds the values and `final`.
#[test]
fn command_writes_csv_and_json() {
    let args = [
        "sensitivity",
        "examples/pendulum.lsd",
        "--parameters",
        "swing.q",
        "--duration",
        "1",
    ];
    let (code, stdout, stderr) = lsdc(&args);
    assert_eq!(code, 0, "{stderr}");
    let header = stdout.lines().next().unwrap();
    assert_eq!(header, "time,d(swing.q)/d(swing.q),d(swing.q')/d(swing.q)");
    assert_eq!(stdout.lines().count(), 1 + 21);
    assert!(
        stderr.contains("parameter swing.q = 1.0471975511965976 (initial value)"),
        "{stderr}"
    );
    let (code, stdout, _) = lsdc(&[&args[..], &["--format", "json"]].concat());
    assert_eq!(code, 0);
    let value: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    let last = value["final"]["d(swing.q)/d(swing.q)"].as_f64().unwrap();
    let samples = value["samples"].as_array().unwrap();
    assert_eq!(
        samples.last().unwrap()["derivatives"][0].as_f64().unwrap(),
        last
    );
    assert_eq!(value["parameters"][0]["kind"], "initial value");
}

/// `--plot` draws the derivatives.
#[test]
fn command_plots_the_derivatives() {
    let path = std::env::temp_dir().join(format!("lsdc-sensitivity-{}.svg", std::process::id()));
    let plot = path.to_str().unwrap();
    let args = [
        "sensitivity",
        "examples/pendulum.lsd",
        "--parameters",
        "swing.q",
        "--duration",
        "1",
        "--plot",
        plot,
    ];
    let (code, _, stderr) = lsdc(&args);
    assert_eq!(code, 0, "{stderr}");
    let svg = std::fs::read_to_string(&path).unwrap();
    std::fs::remove_file(&path).unwrap();
    assert!(svg.contains("Sensitivities to swing.q") && svg.contains("d(swing.q)/d(swing.q)"));
}

/// Each diagnostic of the command, as its golden file has it.
#[test]
fn diagnostics_match_their_golden_files() {
    check_command_goldens("sensitivity", "tests/golden/sensitivity", 5);
}
