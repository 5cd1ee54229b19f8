//! Rheonomic joints (`time` in a dof chain): Kapitza's pendulum, whose pivot is shaken, against
//! a direct integration of θ'' = -(g + a''(t)) / l sin θ and its shaking force against
//! m (g + z''); a bead on a rod turning at a constant rate against r0 cosh(w t) and its torque
//! against 2 m w r r'; with every integrator of the registry (or its refusal), the hidden
//! coordinates on their laws and the energy balance with their work; the refusals.

use crate::common::programs::output;
use crate::common::programs::{column, example_text, refusal_codes, run_text};
use lsdc::integrators::{Feature, INTEGRATORS};
use lsdc::prepare::{Integrator, Settings};
use lsdc::simulate::run::Simulation;

fn settings(integrator: Integrator, duration: f64) -> Settings {
    Settings {
        integrator,
        duration,
        output: 0.01,
        rtol: 1e-13,
        atol: 1e-13,
        step: Some(2e-5),
        ..Settings::default()
    }
}

/// Runs `example` with every integrator of the registry, checking the refusal of those that
/// do not handle drives; `check` receives the others' runs.
fn with_every_integrator(example: &str, duration: f64, check: impl Fn(&str, &Simulation)) {
    let text = example_text(example, &[]);
    run_with_every_integrator(&text, |integrator| settings(integrator, duration), check);
}

/// Runs the program `text` with every integrator of the registry (its settings from
/// `settings`), checking the refusal of those that do not handle drives and the energy balance
/// of the others' runs (to 1e-9), which `check` receives.
pub fn run_with_every_integrator(
    text: &str,
    settings: impl Fn(Integrator) -> Settings,
    check: impl Fn(&str, &Simulation),
) {
    for entry in INTEGRATORS {
        let simulation = run_text(text, settings(entry.integrator.clone()));
        if entry.unsupported.contains(&Feature::Drives) {
            let failure = simulation.report.failure.expect("refused");
            assert!(failure.message.contains("drives"), "{}", failure.message);
            continue;
        }
        assert!(
            simulation.report.failure.is_none(),
            "{}: {:?}",
            entry.name,
            simulation.report.failure
        );
        check(entry.name, &simulation);
        let balance = simulation.report.energy_balance.expect("work tracked");
        assert!(balance < 1e-9, "{}: energy balance {balance:e}", entry.name);
    }
}

/// Kapitza's pendulum of `examples/kapitza_pendulum.lsd`: its parameters.
const KAPITZA: (f64, f64, f64, f64, f64) = (0.01, 300.0, 0.1, 0.3, 9.81);

/// θ and θ' of θ'' = -(g + a''(t)) / l sin θ from θ(0) = 2.9, θ'(0) = 0 at the times `at`
/// (multiples of `h`), by the classical Runge–Kutta method with `h` = 1e-5: its error,
/// O((h w)⁴) over the run, is about 3e-11 (against h = 2e-6).
fn kapitza_reference(at: &[f64]) -> Vec<(f64, f64)> {
    let (a, w, l, _, g) = KAPITZA;
    let field = |t: f64, y: [f64; 2]| {
        let shaking = -a * w * w * (w * t).sin();
        [y[1], -(g + shaking) / l * y[0].sin()]
    };
    runge_kutta(field, [2.9, 0.0], 1e-5, at)
}

/// The solution of y' = `field`(t, y) from y(0) = `start` at the times `at` (multiples of
/// `h`), by the classical Runge–Kutta method with the step `h`.
fn runge_kutta(
    field: impl Fn(f64, [f64; 2]) -> [f64; 2],
    start: [f64; 2],
    h: f64,
    at: &[f64],
) -> Vec<(f64, f64)> {
    let (mut t, mut y) = (0.0, start);
    let mut states = Vec::new();
    for &target in at {
        while t < target - h / 2.0 {
            let k1 = field(t, y);
            let k2 = field(
                t + h / 2.0,
                [y[0] + h / 2.0 * k1[0], y[1] + h / 2.0 * k1[1]],
            );
            let k3 = field(
                t + h / 2.0,
                [y[0] + h / 2.0 * k2[0], y[1] + h / 2.0 * k2[1]],
            );
            let k4 = field(t + h, [y[0] + h * k3[0], y[1] + h * k3[1]]);
            for i in 0..2 {
                y[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
            }
            t += h;
        }
        states.push((y[0], y[1]));
    }
    states
}

/// A point mass hung at l = 1 m on a hinge carried by a turntable turning at w = 3 rad/s (the
/// motion in time and the coordinate along different axes, `dof1 = w * time || z, dof2 = q ||
/// x`): its relative angle follows q'' = sin q (w² cos q − g / l) (the bead on a turning hoop)
/// to 1e-9 with every integrator, against the classical Runge–Kutta method with h = 1e-4
/// (its error about 1e-13 over the run).
#[test]
fn a_pendulum_on_a_turntable_follows_its_relative_equation_with_every_integrator() {
    let text = "let bob = body mass = 1, iframe = [0, 0, -1] ++ 1, inertia = [0, 0, 0] end;
join earth and bob with link(q) dof1 = 3 * time || [0, 0, 1], dof2 = q || [1, 0, 0] end as hang;
apply force value = [0, 0, -9.81], body = earth end on bob.iframe;
initial hang.q = 0.5;
";
    let (w, g) = (3.0, 9.81);
    let settings = |integrator| settings(integrator, 2.0);
    run_with_every_integrator(text, settings, |name, simulation| {
        let angle = column(simulation, "hang.q");
        let times: Vec<f64> = simulation.samples.iter().map(|s| s.time).collect();
        let field = |_: f64, y: [f64; 2]| [y[1], y[0].sin() * (w * w * y[0].cos() - g)];
        let reference = runge_kutta(field, [0.5, 0.0], 1e-4, &times);
        for (sample, &(q, _)) in simulation.samples.iter().zip(&reference) {
            let error = (sample.coordinates[angle] - q).abs();
            assert!(error < 1e-9, "{name}: q at t = {}: {error:e}", sample.time);
        }
    });
}

/// The shaken pendulum's angle equals the direct integration of its equation to 1e-9, the pivot
/// stays on its law to 1e-12, and the shaking force equals m (g + z''), z = a(t) - l cos θ the
/// bob's height, to 1e-9 of its largest value, with every integrator.
#[test]
fn kapitza_pendulum_follows_its_equation_with_every_integrator() {
    let (a, w, l, m, g) = KAPITZA;
    with_every_integrator("kapitza_pendulum", 1.0, |name, simulation| {
        let (angle, pivot) = (
            column(simulation, "swing.q"),
            column(simulation, "swing.motion1"),
        );
        let force = output(simulation, "swing.motion1_effort");
        let times: Vec<f64> = simulation.samples.iter().map(|s| s.time).collect();
        let reference = kapitza_reference(&times);
        let expected_force = |t: f64, theta: f64, rate: f64| {
            let acceleration = -(g - a * w * w * (w * t).sin()) / l * theta.sin();
            let height = -a * w * w * (w * t).sin()
                + l * (acceleration * theta.sin() + rate * rate * theta.cos());
            m * (g + height)
        };
        let largest = (simulation.samples.iter().zip(&reference))
            .map(|(s, &(theta, rate))| expected_force(s.time, theta, rate).abs())
            .fold(0.0, f64::max);
        for (sample, &(theta, rate)) in simulation.samples.iter().zip(&reference) {
            let t = sample.time;
            let error = (sample.coordinates[angle] - theta).abs();
            assert!(error < 1e-9, "{name}: θ at t = {t}: {error:e}");
            let law = a * (w * t).sin();
            assert!((sample.coordinates[pivot] - law).abs() < 1e-12, "{name}");
            assert!(
                (sample.rates[pivot] - a * w * (w * t).cos()).abs() < 1e-12,
                "{name}"
            );
            let error = (sample.outputs[force] - expected_force(t, theta, rate)).abs();
            assert!(
                error < 1e-9 * largest,
                "{name}: force at t = {t}: {error:e}"
            );
        }
    });
}

/// The bead on the spinning rod flies out as r0 cosh(w t), and the torque that turns the rod is
/// 2 m w r r', to 1e-9 of its largest value, with every integrator.
#[test]
fn a_bead_on_a_spinning_rod_follows_the_closed_form_with_every_integrator() {
    let (w, m, r0) = (3.0, 0.5, 0.1);
    with_every_integrator("bead_on_spinning_rod", 1.0, |name, simulation| {
        let (length, turn) = (
            column(simulation, "rod.r"),
            column(simulation, "rod.motion1"),
        );
        let torque = output(simulation, "rod.motion1_effort");
        let closed = |t: f64| (r0 * (w * t).cosh(), r0 * w * (w * t).sinh());
        let largest = 2.0 * m * w * closed(1.0).0 * closed(1.0).1;
        for sample in &simulation.samples {
            let t = sample.time;
            let (r, rate) = closed(t);
            let error = (sample.coordinates[length] - r).abs() / r;
            assert!(error < 1e-9, "{name}: r at t = {t}: {error:e}");
            assert!((sample.coordinates[turn] - w * t).abs() < 1e-12, "{name}");
            let error = (sample.outputs[torque] - 2.0 * m * w * r * rate).abs();
            assert!(
                error < 1e-9 * largest,
                "{name}: torque at t = {t}: {error:e}"
            );
        }
    });
}

#[test]
fn rheonomic_chains_that_cannot_be_imposed_are_refused() {
    let body = "let b = body mass = 1, iframe = [0.3, 0, 0] ++ 1, inertia = [1, 1, 1] end;\n";
    let codes = |text: &str| refusal_codes(&format!("{body}{text}"));
    // The time and the coordinate turn about one axis, or slide along one direction.
    assert_eq!(
        codes("join earth and b with link(q) dof = q + 2 * time || [0, 0, 1] end as spin;"),
        ["E0490"]
    );
    assert_eq!(
        codes("join earth and b with link(q) dof = [q * cos(time), 0, 0] end as slide;"),
        ["E0490"]
    );
    assert_eq!(
        codes("join earth and b with link dof = [abs(time - 1), 0, 0] end as shaken;"),
        ["E0484"]
    );
    let loop_closing = "let c = body mass = 1, iframe = 0, inertia = [1, 1, 1] end;
join earth and b with link(q) dof = q || [0, 0, 1] end as first;
join earth and c with link(q) dof = q || [0, 0, 1] end as second;
join b and c with link dof = [sin(time), 0, 0] end as closing;";
    assert_eq!(codes(loop_closing), ["E0489"]);
    // Independent motions are imposed, a weld moved in time as well.
    assert!(codes("join earth and b with link dof = [0, 0, sin(time)] end as shaken;").is_empty());
    assert!(codes(
        "join earth and b with link(q) dof1 = 2 * time || [0, 0, 1], dof2 = q || [1, 0, 0] end as turntable;"
    )
    .is_empty());
}
