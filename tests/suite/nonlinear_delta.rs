//! The Delta seed's nonlinear control in closed loop (its backstepping IV.8; notes on the Delta
//! seed, §4.4 and §6) on the Delta ISIR88 with its motors' currents as states,
//! `examples/control/backstepping_delta.lsd`: the arms track their quintic references with
//! every integrator that integrates states; the seed's robustness signals (R21) measured against
//! what the seed reports (R22, R23). And the language feature the law needs: a state's rate that
//! reads the model, against closed forms.

use crate::common::programs::{output, run_example, run_text};
use crate::states::refused;
use lsdc::integrators::{Feature, INTEGRATORS};
use lsdc::prepare::{Integrator, Settings};
use lsdc::simulate::run::Simulation;

const EXAMPLE: &str = "control/backstepping_delta";
/// The example's own settings and test signals, which the tests replace.
const SETTINGS: &str =
    "simulate duration = 2, output = 0.005, integrator = implicit, tolerance = 1e-8 end ;";
const SIGNALS: &str = "given A_in = 0, B_noise = 0 ;";
const BIAS_GAIN: &str = "given bias_gain = 1200 ;";

/// A run of the example with `replacements`, its `simulate` declaration replaced by `settings`.
fn backstepping(replacements: &[(&str, &str)], settings: Settings) -> Simulation {
    run_example(EXAMPLE, SETTINGS, replacements, &settings)
}

/// The Delta's closed-loop runs' settings (shared with `cascade_delta.rs`).
pub(crate) fn settings(integrator: &Integrator, duration: f64) -> Settings {
    Settings {
        integrator: integrator.clone(),
        duration,
        output: 0.005,
        rtol: 1e-8,
        atol: 1e-8,
        // RK4's fixed step, within the stability of the currents' loop (its fastest mode
        // about 5e3 /s); the adaptive methods' first step.
        step: Some(2e-4),
        ..Settings::default()
    }
}

/// The largest tracking error of the three arms (rad of the arm) at the outputs in [from, to).
pub(crate) fn largest_error(simulation: &Simulation, from: f64, to: f64) -> f64 {
    let errors = ["error1", "error2", "error3"].map(|name| output(simulation, name));
    let samples = simulation.samples.iter();
    samples
        .filter(|s| s.time >= from && s.time < to)
        .flat_map(|s| errors.iter().map(|&k| s.outputs[k].abs()))
        .fold(0.0, f64::max)
}

/// The arms follow their quintic laws out (0.2 to 0.7 s) and back (from 1.0 s) within 1e-4
/// rad of the arm (measured with `implicit`: 3.1e-5 while the currents build up from zero in
/// the first milliseconds, 1e-5 after 0.1 s), with every integrator that integrates states;
/// the seed reports errors of order 1e-3. Before the reduced model's solve was refined,
/// `dopri5` stopped at t = 1.06 s: its SVD left a residual of 8.8e-8 on consistent rows.
#[test]
fn backstepping_tracks_the_delta_references_with_every_integrator() {
    for entry in INTEGRATORS {
        let simulation = backstepping(&[], settings(&entry.integrator, 1.2));
        if refused(&simulation, &entry.integrator) {
            continue;
        }
        let whole = largest_error(&simulation, 0.0, 1.3);
        let settled = largest_error(&simulation, 0.1, 1.3);
        assert!(
            whole < 1e-4 && settled < 2e-5,
            "{}: {whole:e}, after 0.1 s {settled:e}",
            entry.name
        );
    }
}

/// The seed's R23 test (A = B = 5: a 5 V step on the voltage at 0.1 s, a 10 Hz sinusoid of
/// 5 V from 0.5 s, the noise 5 sin(500 t) on the motor's angle, speed and current from 1.2 s).
/// Measured: with the voltage-bias estimate the step leaves at most 4.0e-3 rad, the sinusoid
/// 6.4e-3; the noise, which the law reads through its sensors at 500 rad/s (5 rad of the motor
/// is 0.42 rad of the arm), 3.3e-2: rejected where the seed says so (the step and the
/// sinusoid, to a few 1e-3), not the noise, which it calls poor for sliding mode (R22). The
/// seed's IV.8 alone (`bias_gain = 0`) keeps the step's error, 0.14 rad.
#[test]
fn backstepping_rejects_the_seeds_input_disturbances_not_its_sensor_noise() {
    let signals = "given A_in = 5, B_noise = 5 ;";
    let implicit = |duration| settings(&Integrator::Implicit, duration);
    let with_estimate = backstepping(&[(SIGNALS, signals)], implicit(1.5));
    assert!(with_estimate.report.failure.is_none());
    let step = largest_error(&with_estimate, 0.1, 0.5);
    let sinusoid = largest_error(&with_estimate, 0.5, 1.2);
    let noise = largest_error(&with_estimate, 1.2, 1.6);
    assert!(
        step < 5e-3 && sinusoid < 8e-3 && noise > 2e-2 && noise < 5e-2,
        "step {step:e}, sinusoid {sinusoid:e}, noise {noise:e}"
    );
    let plain = backstepping(
        &[(SIGNALS, signals), (BIAS_GAIN, "given bias_gain = 0 ;")],
        implicit(0.5),
    );
    assert!(plain.report.failure.is_none());
    let plain_step = largest_error(&plain, 0.1, 0.5);
    assert!(
        plain_step > 0.1 && plain_step > 30.0 * step,
        "IV.8 alone {plain_step:e}, with the estimate {step:e}"
    );
}

/// A state's rate may read the model: on a pendulum held at rest by its actuator
/// (`gravity_effort`), the integrals of its inertia about the pivot and of its holding torque
/// are I t = (0.1 + 1.2 · 0.5²) t and m g l sin(q0) t, with every integrator that integrates
/// states.
#[test]
fn a_state_rate_reads_the_model_at_each_evaluation() {
    let text = "import joints ;
let rod = body mass = 1.2, iframe = [0, 0, -0.5] ++ 1, inertia = [0.1, 0.1, 0.001] end ;
join earth and rod with revolute([1, 0, 0]) as swing ;
apply force value = [0, 0, -9.81 * rod.mass], body = earth end on rod.iframe ;
actuate swing.q = gravity_effort(swing.q) ;
let inertia_integral = state(0) ;
rate inertia_integral = mass_matrix(swing.q, swing.q) ;
let holding_integral = state(0) ;
rate holding_integral = gravity_effort(swing.q) ;
initial swing.q = 0.3 ;
";
    let (inertia, holding) = (0.1 + 1.2 * 0.25, 1.2 * 9.81 * 0.5 * 0.3f64.sin());
    for entry in INTEGRATORS {
        if entry.unsupported.contains(&Feature::States) {
            continue;
        }
        let simulation = run_text(text, settings(&entry.integrator, 1.0));
        assert!(simulation.report.failure.is_none(), "{}", entry.name);
        let (i, h) = (
            output(&simulation, "inertia_integral"),
            output(&simulation, "holding_integral"),
        );
        for sample in &simulation.samples {
            let t = sample.time;
            assert!(
                (sample.outputs[i] - inertia * t).abs() < 1e-12
                    && (sample.outputs[h] - holding * t).abs() < 1e-12,
                "{} at t = {t}: {} against {}, {} against {}",
                entry.name,
                sample.outputs[i],
                inertia * t,
                sample.outputs[h],
                holding * t
            );
        }
    }
}

/// The seed's Ch. V test: 5 kg added on the nacelle (`payload`), the estimator, a state, finds
/// it from the motors' power and the energies of the robot and of the payload (an exact
/// balance: the loops' reactions do no work, the rods' spins move no mass). Measured: from 0
/// to 4.99995 at 0.35 s, the first move under way, and within 7e-7 kg of 5 kg from 0.4 s on
/// (1.4e-7 of it); the acceptance is 1 %. Without a payload it stays within 1e-6 kg of zero
/// after the first move.
#[test]
fn the_mass_estimator_finds_the_payload_added_on_the_nacelle() {
    for (payload, from, within) in [(5.0, 0.4, 1e-6), (0.0, 0.7, 1e-6)] {
        let given = format!("given payload = {payload} ;");
        let simulation = backstepping(
            &[("given payload = 0 ;", given.as_str())],
            settings(&Integrator::Implicit, 1.2),
        );
        assert!(simulation.report.failure.is_none());
        let estimate = output(&simulation, "mass_estimate");
        let largest = (simulation.samples.iter())
            .filter(|s| s.time >= from)
            .map(|s| (s.outputs[estimate] - payload).abs())
            .fold(0.0, f64::max);
        assert!(
            largest < within && largest < 0.01 * payload.max(1.0),
            "payload {payload}: {largest:e}"
        );
    }
}
