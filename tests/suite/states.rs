//! States (`let s = state(x0); rate s = f;`): a PI speed loop on a flywheel against the closed
//! form of its second-order error equation, and a DC motor's step response (its current a
//! stiff state) against its closed form, with every integrator of the registry (or its
//! refusal); on a closed loop, a state integrating the crank's rate follows the crank's angle to
//! the integrator's tolerance while the integral action holds the crank; the refusals.

use crate::common::programs::{example_text, output, refusal_codes, run_text};
use lsdc::integrators::{Feature, INTEGRATORS};
use lsdc::prepare::{Integrator, Settings};
use lsdc::simulate::run::Simulation;

/// The examples' own settings, which the tests' replace.
const PI_SETTINGS: &str =
    "simulate duration = 5, output = 0.05, integrator = dopri5, tolerance = 1e-10 end ;";
const MOTOR_SETTINGS: &str =
    "simulate duration = 10, output = 0.01, integrator = implicit, tolerance = 1e-10 end ;";
const FOUR_BAR_SETTINGS: &str = "simulate duration = 4, output = 0.02, tolerance = 1e-10 end ;";

fn settings(integrator: &Integrator, duration: f64, tolerance: f64) -> Settings {
    Settings {
        integrator: integrator.clone(),
        duration,
        output: 0.01,
        rtol: tolerance,
        atol: tolerance,
        step: Some(1e-3),
        ..Settings::default()
    }
}

/// Whether the integrator refused the run for its states (saying so); otherwise the run must
/// have succeeded.
pub(crate) fn refused(simulation: &Simulation, integrator: &Integrator) -> bool {
    let entry = integrator.entry();
    if entry.unsupported.contains(&Feature::States) {
        let failure = simulation.report.failure.as_ref().expect("refused");
        assert!(failure.message.contains("states"), "{}", failure.message);
        return true;
    }
    assert!(
        simulation.report.failure.is_none(),
        "{}: {:?}",
        entry.name,
        simulation.report.failure
    );
    false
}

/// The flywheel of `pi_flywheel.lsd`: J ω̇ = k_p e + k_i I with e = ω_ref − ω and İ = e, so
/// J ë + k_p ė + k_i e = 0 from e(0) = ω_ref, ė(0) = −k_p ω_ref / J: e = e^(−σt)(A cos ω_d t +
/// B sin ω_d t), σ = k_p / 2J, ω_d = √(k_i/J − σ²), A = ω_ref, B = −σ ω_ref / ω_d; the
/// integral from J ω̇ = k_p e + k_i I with ω̇ = −ė: I = −(J ė + k_p e) / k_i.
fn pi_flywheel(t: f64) -> (f64, f64) {
    let (j, w_ref, kp, ki): (f64, f64, f64, f64) = (0.5, 10.0, 1.0, 5.0);
    let sigma = kp / (2.0 * j);
    let wd = (ki / j - sigma * sigma).sqrt();
    let (a, b) = (w_ref, -sigma * w_ref / wd);
    let decay = (-sigma * t).exp();
    let (c, s) = ((wd * t).cos(), (wd * t).sin());
    let e = decay * (a * c + b * s);
    let de = decay * ((b * wd - sigma * a) * c - (a * wd + sigma * b) * s);
    let integral = (-j * de - kp * e) / ki;
    (w_ref - e, integral)
}

/// The PI speed loop equals its closed form to 1e-9 (speed in rad/s, integral in rad) at
/// every output of a 5 s run, with every integrator but `symplectic`, which refuses states.
#[test]
fn a_pi_speed_loop_is_its_closed_form_with_every_integrator() {
    let text = example_text("control/pi_flywheel", &[(PI_SETTINGS, "")]);
    for entry in INTEGRATORS {
        let simulation = run_text(&text, settings(&entry.integrator, 5.0, 1e-12));
        if refused(&simulation, &entry.integrator) {
            continue;
        }
        let integral = output(&simulation, "integral");
        let (mut speed_error, mut integral_error) = (0.0f64, 0.0f64);
        for sample in &simulation.samples {
            let (speed, expected_integral) = pi_flywheel(sample.time);
            speed_error = speed_error.max((sample.rates[0] - speed).abs());
            integral_error =
                integral_error.max((sample.outputs[integral] - expected_integral).abs());
        }
        assert_eq!(simulation.samples.len(), 501);
        assert!(
            speed_error < 1e-9 && integral_error < 1e-9,
            "{}: speed {speed_error:e}, integral {integral_error:e}",
            entry.name
        );
    }
}

/// The motor of `dc_motor.lsd`: x = (ω, I), ω̇ = N K_i I / J, İ = b2 N ω + b1 I + b3 U from
/// rest, whose eigenvalues λ solve λ² − b1 λ − b2 N² K_i / J = 0; ω = ω∞ (1 + (λ₂ e^(λ₁t) −
/// λ₁ e^(λ₂t)) / (λ₁ − λ₂)) with ω∞ = U / (N K_e), and I = J ω̇ / (N K_i).
fn dc_motor(t: f64) -> (f64, f64) {
    let (j, r, l, ke, ki, n, u): (f64, f64, f64, f64, f64, f64, f64) =
        (0.5, 1.35, 1.2e-3, 0.1194, 0.119, 12.0, 12.0);
    let (b1, b2) = (-r / l, -ke / l);
    let (sum, product) = (b1, -b2 * n * n * ki / j);
    let root = (sum * sum - 4.0 * product).sqrt();
    let (l1, l2) = ((sum + root) / 2.0, (sum - root) / 2.0);
    let final_speed = u / (n * ke);
    let (e1, e2) = ((l1 * t).exp(), (l2 * t).exp());
    let speed = final_speed * (1.0 + (l2 * e1 - l1 * e2) / (l1 - l2));
    let acceleration = final_speed * l1 * l2 * (e1 - e2) / (l1 - l2);
    (speed, j * acceleration / (n * ki))
}

/// A DC motor's step response, its current a state 1000 times faster than the arm: speed and
/// current against the closed form to 1e-8 of their largest values, with every integrator but
/// `symplectic`; `implicit` takes Radau IIA steps for most of the run (its Jacobian differences
/// the states' rates with the motion).
#[test]
fn a_dc_motor_step_response_is_its_closed_form_with_every_integrator() {
    let text = example_text("control/dc_motor", &[(MOTOR_SETTINGS, "")]);
    let (final_speed, peak_current) = (12.0 / (12.0 * 0.1194), 10.0);
    for entry in INTEGRATORS {
        let step = match entry.integrator {
            Integrator::Rk4 => 1e-4,
            _ => 1e-3,
        };
        let run_settings = Settings {
            step: Some(step),
            ..settings(&entry.integrator, 10.0, 1e-11)
        };
        let simulation = run_text(&text, run_settings);
        if refused(&simulation, &entry.integrator) {
            continue;
        }
        if entry.integrator == Integrator::Implicit {
            let stiff = simulation
                .report
                .stiff_steps
                .expect("the implicit method reports");
            assert!(stiff > 0, "no stiff step");
        }
        let current = output(&simulation, "current");
        let (mut speed_error, mut current_error) = (0.0f64, 0.0f64);
        for sample in &simulation.samples {
            let (speed, expected_current) = dc_motor(sample.time);
            speed_error = speed_error.max((sample.rates[0] - speed).abs() / final_speed);
            current_error = current_error
                .max((sample.outputs[current] - expected_current).abs() / peak_current);
        }
        assert!(
            speed_error < 1e-8 && current_error < 1e-8,
            "{}: speed {speed_error:e}, current {current_error:e}",
            entry.name
        );
    }
}

/// The four-bar of `four_bar_integral.lsd`, a closed loop, its crank held by a PID torque whose
/// integral is a state: `travel`, whose rate is the crank's, equals the crank's angle to the
/// integrator's tolerance at every output (the motion is projected onto the loop after each
/// step, the states are not), and after 4 s the integral action holds the crank on θ_ref.
#[test]
fn a_state_read_by_an_effort_of_a_closed_loop_integrates_with_every_integrator() {
    let text = example_text("control/four_bar_integral", &[(FOUR_BAR_SETTINGS, "")]);
    for entry in INTEGRATORS {
        let tolerance = 1e-10;
        let simulation = run_text(&text, settings(&entry.integrator, 4.0, tolerance));
        if refused(&simulation, &entry.integrator) {
            continue;
        }
        let travel = output(&simulation, "travel");
        let crank = (simulation.coordinate_names.iter())
            .position(|n| n == "crank.q")
            .expect("crank");
        let drift = (simulation.samples.iter())
            .map(|s| (s.outputs[travel] - s.coordinates[crank]).abs())
            .fold(0.0, f64::max);
        let last = simulation.samples.last().expect("samples");
        let settled = (last.coordinates[crank] - 1.2).abs();
        assert!(drift < 100.0 * tolerance, "{}: drift {drift:e}", entry.name);
        assert!(settled < 1e-3, "{}: {settled:e} from θ_ref", entry.name);
    }
}

/// A state without `rate` (E0488), a `rate` of what is not a state (E0486) or given twice
/// (E0487), and a starting value that needs a value nobody gave (E0806).
#[test]
fn states_without_their_equation_are_refused() {
    let flywheel = "import joints;
let wheel = body mass = 2, iframe = 1, inertia = [0.3, 0.3, 0.5] end;
join earth and wheel with revolute([0, 0, 1]) as spin;
";
    let codes = |states: &str| refusal_codes(&format!("{flywheel}{states}"));
    let applied = "apply torque value = [0, 0, s], body = earth end on wheel;";
    assert_eq!(codes(&format!("let s = state(0); {applied}")), ["E0488"]);
    assert_eq!(codes("let s = 2; rate s = 1;"), ["E0486"]);
    assert_eq!(codes("rate spin.q = 1;"), ["E0486"]);
    assert_eq!(
        codes(&format!(
            "let s = state(0); rate s = 1; rate s = 2; {applied}"
        )),
        ["E0487"]
    );
    assert_eq!(
        codes(&format!(
            "let x0 = ?s; let s = state(x0); rate s = 1; {applied}"
        )),
        ["E0806"]
    );
    assert!(codes(&format!("let s = state(0); rate s = -s; {applied}")).is_empty());
}
