//! A sampled PD controller on the bundled pendulum, stepped from Rust through the library's
//! public API alone (`lsdc::api` and `lsdc::dynamics`): the crate as a user depending on it
//! sees it. `.ci/run` checks this file with the repository's `lsdc_internals` cfg removed, so it
//! cannot reach the library's own modules (src/lib.rs, "The library's boundary").
//!
//! Every 10 ms the controller reads the state and holds τ = −kp (q − target) − kd q̇ until the
//! next period (`set_inputs`, a zero-order hold). At rest the held torque balances gravity's,
//! −m g l sin q, so the pendulum settles where kp (target − q) = m g l sin q: the example checks
//! its final angle against that equation solved by Newton's method, then resets and repeats.
//!
//! Run with `cargo run --example sampled_pd` from the repository's root.

use lsdc::api::{Program, SettingsChanges, Simulator, Start};
use lsdc::dynamics::model::Model;

const KP: f64 = 20.0;
const KD: f64 = 3.0;
const TARGET: f64 = 0.5;
const PERIOD: f64 = 0.01;
const DURATION: f64 = 10.0;
/// The rod's mass (kg) times gravity (m/s²) times the distance of its centre of mass from the
/// axis (m), as examples/pendulum.lsd declares them.
const GRAVITY_MOMENT: f64 = 1.2 * 9.81 * 0.5;

/// The angle where the PD torque balances gravity: kp (target − q) = m g l sin q, by Newton's
/// method from the target.
fn balanced_angle() -> f64 {
    let mut q = TARGET;
    for _ in 0..50 {
        let residual = KP * (TARGET - q) - GRAVITY_MOMENT * q.sin();
        q += residual / (KP + GRAVITY_MOMENT * q.cos());
    }
    q
}

/// Runs the sampled loop to `DURATION`; the final angle and rate.
fn control(simulator: &mut Simulator<'_>) -> Result<(f64, f64), lsdc::api::Error> {
    let steps = (DURATION / PERIOD).round() as usize;
    for k in 1..=steps {
        let (q, v) = simulator.coordinates()?;
        let torque = -KP * (q[0] - TARGET) - KD * v[0];
        simulator.set_inputs(&[torque])?;
        simulator.advance_to(k as f64 * PERIOD)?;
    }
    let (q, v) = simulator.coordinates()?;
    Ok((q[0], v[0]))
}

fn main() -> Result<(), lsdc::api::Error> {
    let changes = SettingsChanges {
        duration: Some(DURATION),
        ..Default::default()
    };
    let program = Program::from_file("examples/pendulum.lsd", &Default::default())?;
    let prepared = program.prepare(&[], &changes)?;
    let model: &Model = &prepared.model;
    println!("the pendulum: {} velocity, input along swing.q", model.nv);

    let mut simulator = Simulator::new(&prepared, &["swing.q"])?;
    let (angle, rate) = control(&mut simulator)?;
    let expected = balanced_angle();
    println!("at t = {DURATION} s: q = {angle:.12}, q' = {rate:.3e}; balance: q = {expected:.12}");
    assert!(
        (angle - expected).abs() < 1e-9,
        "settled at {angle}, not {expected}"
    );
    assert!(rate.abs() < 1e-9);

    // Back to the start, the held torque kept: the same loop gives the same motion.
    let start = Start {
        coordinates: &prepared.coordinates,
        rates: &prepared.rates,
    };
    simulator.reset(&start)?;
    let (again, _) = control(&mut simulator)?;
    println!("after reset: q = {again:.12}");
    assert_eq!(again, angle);
    Ok(())
}
