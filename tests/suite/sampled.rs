//! Sampled states (`let u = sample(h, u0); update u = f;`): the discrete PD pendulum of
//! `examples/control/discrete_pd_pendulum.lsd` against the same difference equation computed
//! by hand from the run's own states at the instants (to round-off) and against the pendulum
//! integrated between the instants by a Runge–Kutta written here, with the held torque (to the
//! integrators' tolerance), with every integrator of the registry; every instant landed on
//! exactly and listed in the report (text and JSON); the held value before the first instant
//! from `given` and `--set`; the discrete PI with saturation; a sampled computed torque that
//! reads the model (`inverse_dynamics`, `mass_matrix`, `bias`) against the pendulum's closed
//! form.

use crate::common::lsdc;
use crate::common::programs::{example_text, output, refusal_codes, run_text};
use lsdc::integrators::{Integrator, INTEGRATORS};
use lsdc::prepare::Settings;
use lsdc::simulate::run::Simulation;

/// The example's own settings, which the tests' replace.
const PD_SETTINGS: &str =
    "simulate duration = 3, output = 0.01, integrator = dopri5, tolerance = 1e-10 end ;";

/// The example's pendulum: J q'' = −m g l sin q + u with J = I_x + m l², its controller
/// u = k_p (q_ref − q) − k_d q' sampled every H.
const M: f64 = 1.2;
const L: f64 = 0.5;
const G: f64 = 9.81;
const J: f64 = 0.1 + M * L * L;
const H: f64 = 0.01;
const Q_REF: f64 = 0.5;
const K_P: f64 = 20.0;
const K_D: f64 = 2.0;
const DURATION: f64 = 3.0;

/// The controller's difference equation, written by hand.
fn pd(q: f64, rate: f64) -> f64 {
    K_P * (Q_REF - q) - K_D * rate
}

/// The pendulum from (q, q') over `span` seconds with the torque `u` held: classic RK4 in
/// `substeps` steps (independent of the crate's integrators).
fn hold(mut state: [f64; 2], u: f64, span: f64, substeps: usize) -> [f64; 2] {
    let f = |[q, w]: [f64; 2]| [w, (-M * G * L * q.sin() + u) / J];
    let dt = span / substeps as f64;
    for _ in 0..substeps {
        let k1 = f(state);
        let k2 = f([state[0] + dt / 2.0 * k1[0], state[1] + dt / 2.0 * k1[1]]);
        let k3 = f([state[0] + dt / 2.0 * k2[0], state[1] + dt / 2.0 * k2[1]]);
        let k4 = f([state[0] + dt * k3[0], state[1] + dt * k3[1]]);
        for i in 0..2 {
            state[i] += dt / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
        }
    }
    state
}

fn settings(integrator: &Integrator) -> Settings {
    Settings {
        integrator: integrator.clone(),
        duration: DURATION,
        output: H,
        rtol: 1e-11,
        atol: 1e-11,
        step: Some(1e-4),
        ..Settings::default()
    }
}

fn pd_text() -> String {
    example_text("control/discrete_pd_pendulum", &[(PD_SETTINGS, "")])
}

/// The largest differences of one run from the hand-written controller and pendulum: the
/// controller's u[k] against the difference equation on the run's own states at t_k, the
/// states at the instants against the pendulum integrated here with the torques it computes
/// itself, and the run's u[k] against those torques.
struct Agreement {
    controller: f64,
    motion: f64,
    torque: f64,
}

fn agreement(simulation: &Simulation) -> Agreement {
    let sampling = (simulation.report.sampling.as_ref()).expect("the sampling in the report");
    assert_eq!(sampling.states, ["u"]);
    assert_eq!(sampling.periods, [H]);
    let instants = &sampling.instants;
    let count = (1..).take_while(|&k| k as f64 * H <= DURATION).count();
    assert_eq!(instants.len(), count, "instants");
    let column = output(simulation, "u");
    let (mut controller, mut motion, mut torque) = (0.0f64, 0.0f64, 0.0f64);
    let (mut by_hand, mut u_by_hand) = ([std::f64::consts::PI / 3.0, 0.0], 0.0);
    for (k, instant) in instants.iter().enumerate() {
        // Landed on exactly: the instant is k h, the output there the run's state at it.
        let t = (k + 1) as f64 * H;
        assert_eq!(instant.time, t, "instant {k}");
        let sample = (simulation.samples.iter())
            .find(|s| s.time == t)
            .unwrap_or_else(|| panic!("no output at the instant {t}"));
        let held = if k == 0 {
            0.0
        } else {
            instants[k - 1].values[0]
        };
        assert_eq!(
            sample.outputs[column], held,
            "the output at {t} shows the held value"
        );
        let u = instant.values[0];
        controller = controller.max((u - pd(sample.coordinates[0], sample.rates[0])).abs());
        by_hand = hold(by_hand, u_by_hand, H, 200);
        motion = motion
            .max((sample.coordinates[0] - by_hand[0]).abs())
            .max((sample.rates[0] - by_hand[1]).abs());
        u_by_hand = pd(by_hand[0], by_hand[1]);
        torque = torque.max((u - u_by_hand).abs());
    }
    Agreement {
        controller,
        motion,
        torque,
    }
}

/// The discrete PD matches its difference equation to round-off (u ≈ 10 N m; measured equal to
/// the bit, bound 4e-15) and the pendulum integrated between the instants to the tolerance
/// (1e-11: measured 7.9e-13 for dopri5 and implicit, 2.4e-14 for rk4 at 0.1 ms, 1.2e-14 for
/// dop853; bound 1e-10 on angles and rates of order 1, torques 20 times that through k_p),
/// with every integrator that takes sampled states; `symplectic` refuses them at the `sample`
/// call (E0498).
#[test]
fn a_discrete_pd_on_the_pendulum_is_its_difference_equation_with_every_integrator() {
    let text = pd_text();
    for entry in INTEGRATORS {
        let settings = settings(&entry.integrator);
        if entry.integrator == Integrator::Symplectic {
            let symplectic = "simulate duration = 3, integrator = symplectic, step = 1e-4 end ;";
            assert_eq!(refusal_codes(&format!("{text}{symplectic}")), ["E0498"]);
            continue;
        }
        let simulation = run_text(&text, settings);
        assert!(simulation.report.failure.is_none(), "{}", entry.name);
        let found = agreement(&simulation);
        eprintln!(
            "{}: controller {:e}, motion {:e}, torque {:e}",
            entry.name, found.controller, found.motion, found.torque
        );
        assert!(found.controller <= 4e-15, "{}", entry.name);
        assert!(found.motion < 1e-10, "{}", entry.name);
        assert!(found.torque < 2e-9, "{}", entry.name);
    }
}

/// RK4 with a step that does not divide the period (3 ms against 10 ms) still lands on every
/// instant, its steps cut there; the motion then agrees with the hand-written one to the
/// method's accuracy at that step.
#[test]
fn a_fixed_step_lands_on_instants_off_its_grid() {
    let settings = Settings {
        step: Some(3e-3),
        ..settings(&Integrator::Rk4)
    };
    let simulation = run_text(&pd_text(), settings);
    assert!(simulation.report.failure.is_none());
    let found = agreement(&simulation);
    assert!(found.controller <= 4e-15, "{:e}", found.controller);
    assert!(found.motion < 1e-6, "{:e}", found.motion);
}

/// The run's report lists the sampling: its count, states and span in text, every instant with
/// the values it set in JSON; `--set u0=1.5` holds 1.5 before the first instant.
#[test]
fn the_sampling_instants_are_in_the_report() {
    let example = "examples/control/discrete_pd_pendulum.lsd";
    let (code, _, report) = lsdc(&["simulate", example, "-o", "/dev/null"]);
    assert_eq!(code, 0, "{report}");
    assert!(
        report.contains("sampling: 300 instants (`u` every 0.01 s), from t = 0.01 to t = 3\n"),
        "{report}"
    );
    let args = ["simulate", example, "--report", "json", "--set", "u0=1.5"];
    let (code, samples, report) = lsdc(&args);
    assert_eq!(code, 0, "{report}");
    let report: serde_json::Value = serde_json::from_str(&report).expect("a JSON report");
    let instants = report["sampling"]["instants"].as_array().expect("instants");
    assert_eq!(instants.len(), 300);
    assert_eq!(instants[0]["time"], 0.01);
    assert_eq!(report["sampling"]["states"][0], "u");
    // The first rows: the held value before the first instant is --set's, the output at the
    // first instant still shows it (the values held up to an instant).
    let column = |row: &str| {
        row.rsplit(',')
            .next()
            .expect("u")
            .parse::<f64>()
            .expect("u")
    };
    let rows: Vec<&str> = samples.lines().collect();
    assert!(rows[0].ends_with(",u"), "{}", rows[0]);
    assert_eq!(column(rows[1]), 1.5);
    assert_eq!(column(rows[2]), 1.5);
    assert_eq!(
        column(rows[3]),
        instants[0]["values"][0].as_f64().expect("u")
    );
}

/// The discrete PI with saturation: its command never leaves ±2 N m, saturates while the
/// wheel speeds up, then settles the speed within 1e-2 of 10 rad/s in 8 s; the integral is the
/// rectangle rule of the errors at the instants clamped to ±0.4 (the anti-windup), recomputed
/// here from the run's states there to round-off.
#[test]
fn a_discrete_pi_with_saturation_settles_within_its_limits() {
    let settings_line =
        "simulate duration = 8, output = 0.02, integrator = dopri5, tolerance = 1e-10 end ;";
    let text = example_text("control/discrete_pi_saturation", &[(settings_line, "")]);
    let settings = Settings {
        duration: 8.0,
        output: 0.02,
        rtol: 1e-10,
        atol: 1e-10,
        ..Settings::default()
    };
    let simulation = run_text(&text, settings);
    assert!(simulation.report.failure.is_none());
    let sampling = simulation.report.sampling.as_ref().expect("sampling");
    assert_eq!(sampling.states, ["integral", "command"]);
    let (mut integral, mut largest, mut saturated) = (0.0, 0.0f64, 0);
    for instant in &sampling.instants {
        let sample = (simulation.samples.iter())
            .find(|s| s.time == instant.time)
            .expect("an output at each instant");
        let error = 10.0 - sample.rates[0];
        integral = f64::clamp(integral + 0.02 * error, -0.4, 0.4);
        largest = largest.max((instant.values[0] - integral).abs());
        let command = instant.values[1];
        assert!(command.abs() <= 2.0, "{command}");
        saturated += usize::from(command.abs() == 2.0);
    }
    assert!(largest < 1e-12, "{largest:e}");
    assert!(saturated > 50, "{saturated} instants saturated");
    let last = simulation.samples.last().expect("samples");
    assert!((last.rates[0] - 10.0).abs() < 1e-2, "{}", last.rates[0]);
}

/// An update that is not a number at an instant stops the run there, naming the state.
#[test]
fn an_update_that_is_not_a_number_stops_the_run_at_its_instant() {
    let law = "update u = k_p * (q_ref - swing.q) - k_d * swing.q' ;";
    let text = example_text(
        "control/discrete_pd_pendulum",
        &[(PD_SETTINGS, ""), (law, "update u = log(swing.q - 2) ;")],
    );
    let simulation = run_text(&text, settings(&Integrator::DormandPrince));
    let failure = simulation.report.failure.as_ref().expect("the run fails");
    assert_eq!(failure.time, H);
    assert!(
        failure
            .message
            .contains("the update of sampled state `u` is not finite"),
        "{}",
        failure.message
    );
    let last = simulation
        .samples
        .last()
        .expect("the outputs before the failure");
    assert_eq!(last.time, H);
}

/// A sampled law that reads the model: the computed torque u[k] = `inverse_dynamics` at the
/// acceleration a = k_p (q_ref − q) − k_d q' read at t_k, held until the next instant, and
/// w[k] = `mass_matrix` · a + `bias`, the same law from the other builtins. Against the law
/// written by hand from the pendulum's closed form, J a + m g l sin q at the run's states at the
/// instants (to round-off: measured 8.9e-16 N m with every integrator, w
/// equal to u to the bit; bound 1e-14), and the pendulum integrated here between the instants
/// with the torques it computes itself (to the tolerance, as the discrete PD's: measured
/// 4.5e-13 for dopri5 and implicit, 2.4e-14 for rk4), with every integrator that takes sampled
/// states and actuators.
#[test]
fn a_sampled_law_reads_the_model_at_its_instants() {
    let pd_law = "update u = k_p * (q_ref - swing.q) - k_d * swing.q' ;";
    let computed_torque = "let wanted = k_p * (q_ref - swing.q) - k_d * swing.q' ;
update u = inverse_dynamics(swing.q, swing.q, wanted) ;
let w = sample(h, u0) ;
update w = mass_matrix(swing.q, swing.q) * wanted + bias(swing.q) ;";
    let torque = "apply torque value = [u, 0, 0], body = earth end on rod ;";
    let text = example_text(
        "control/discrete_pd_pendulum",
        &[
            (PD_SETTINGS, ""),
            (pd_law, computed_torque),
            (torque, "actuate swing.q = u ;"),
        ],
    );
    let by_hand = |[q, rate]: [f64; 2]| J * pd(q, rate) + M * G * L * q.sin();
    let duration = 1.5;
    for entry in INTEGRATORS {
        if entry.integrator == Integrator::Symplectic {
            continue; // refuses sampled states (E0498) and actuators
        }
        let settings = Settings {
            duration,
            ..settings(&entry.integrator)
        };
        let simulation = run_text(&text, settings);
        assert!(simulation.report.failure.is_none(), "{}", entry.name);
        let sampling = (simulation.report.sampling.as_ref()).expect("the sampling");
        assert_eq!(sampling.states, ["u", "w"]);
        let count = (1..).take_while(|&k| k as f64 * H <= duration).count();
        assert_eq!(sampling.instants.len(), count, "{}", entry.name);
        let (mut law, mut builtins, mut motion) = (0.0f64, 0.0f64, 0.0f64);
        let (mut state, mut u_by_hand) = ([std::f64::consts::PI / 3.0, 0.0], 0.0);
        for instant in &sampling.instants {
            let sample = (simulation.samples.iter())
                .find(|s| s.time == instant.time)
                .expect("an output at each instant");
            let [u, w] = [instant.values[0], instant.values[1]];
            law = law.max((u - by_hand([sample.coordinates[0], sample.rates[0]])).abs());
            builtins = builtins.max((u - w).abs());
            state = hold(state, u_by_hand, H, 200);
            motion = motion
                .max((sample.coordinates[0] - state[0]).abs())
                .max((sample.rates[0] - state[1]).abs());
            u_by_hand = by_hand(state);
        }
        eprintln!(
            "{}: law {law:e}, mass_matrix and bias {builtins:e}, motion {motion:e}",
            entry.name
        );
        assert!(law < 1e-14 && builtins < 1e-14, "{}", entry.name);
        assert!(motion < 1e-10, "{}: {motion:e}", entry.name);
    }
}
