//! `lsdc linearize` with the program's states (a motor's current, a controller's integral) as
//! rows and columns of A, constant states as inputs (a voltage), and outputs that read the
//! model, each against a closed form.

use nalgebra::DMatrix;

use crate::common::programs::{prepared, prepared_text};
use lsdc::studies::linearize::{linearize, OperatingPoint, Request};

fn request(point: OperatingPoint, inputs: &[&str]) -> Request {
    Request {
        point,
        inputs: inputs.iter().map(|s| s.to_string()).collect(),
        coordinates: Vec::new(),
    }
}

/// A DC motor (the Delta seed's constants, §2) turning an arm of inertia J through a reducer
/// of ratio N, its voltage set by a PI loop on the arm's speed, U = kp (w_ref − θ') + ki ξ,
/// ξ' = w_ref − θ', plus a voltage `disturbance` held as an input: with
/// x = (θ, θ', I, ξ) and u = (a torque on the arm, the disturbance),
///   J θ'' = N K_i I + τ,   İ = b2 N θ' + b1 I + b3 (U + δU),
/// b1 = −R/L, b2 = −K_e/L, b3 = 1/L (seed §4.4).
const PI_MOTOR: &str = "import joints ;
let J = 0.5 ;
let arm = body mass = 1, iframe = 1, inertia = [0.3, 0.3, J] end ;
join earth and arm with revolute([0, 0, 1]) as shoulder ;
let R = 1.35 ;
let L = 1.2e-3 ;
let K_e = 0.1194 ;
let K_i = 0.119 ;
let N = 12 ;
let w_ref = 2 ;
let kp = 0.4 ;
let ki = 3 ;
let error = w_ref - shoulder.q' ;
let integral = state(0.25) ;
rate integral = error ;
let disturbance = state(0.5) ;
rate disturbance = 0 ;
let current = state(1.5) ;
rate current = -K_e / L * N * shoulder.q' - R / L * current + (kp * error + ki * integral + disturbance) / L ;
apply torque value = [0, 0, N * K_i * current], body = earth end on arm ;
initial shoulder.q = 0.3, shoulder.q' = 1.1 ;
";

#[test]
fn pi_speed_loop_on_a_motor_matches_its_closed_form() {
    let prepared = prepared_text(PI_MOTOR);
    let l = linearize(
        &prepared,
        &request(OperatingPoint::Initial, &["shoulder.q", "disturbance"]),
    )
    .unwrap();
    let (j, r, inductance, ke, ki_motor, n) = (0.5, 1.35, 1.2e-3, 0.1194, 0.119, 12.0);
    let (kp, ki) = (0.4, 3.0);
    let (b1, b2, b3) = (-r / inductance, -ke / inductance, 1.0 / inductance);
    assert_eq!(
        l.states,
        ["shoulder.q", "shoulder.q'", "integral", "current"]
    );
    assert_eq!(l.program_states, ["integral", "current"]);
    #[rustfmt::skip]
    let a = DMatrix::from_row_slice(4, 4, &[
        0.0, 1.0, 0.0, 0.0,
        0.0, 0.0, 0.0, n * ki_motor / j,
        0.0, -1.0, 0.0, 0.0,
        0.0, b2 * n - b3 * kp, b3 * ki, b1,
    ]);
    #[rustfmt::skip]
    let b = DMatrix::from_row_slice(4, 2, &[
        0.0, 0.0,
        1.0 / j, 0.0,
        0.0, 0.0,
        0.0, b3,
    ]);
    // Relative to the entries' scale (b3 kp ≈ 333, b1 ≈ −1125).
    let scale = a.amax();
    assert!((&l.a - &a).amax() < 1e-9 * scale, "{}\n{}", l.a, a);
    assert!((&l.b - &b).amax() < 1e-9 * b.amax(), "{}\n{}", l.b, b);
    // The operating point: the states' starting values, the held state's value as the input.
    assert_eq!(l.state, [0.3, 1.1, 0.25, 1.5]);
    assert_eq!(l.input, [0.0, 0.5]);
    let current_rate = b2 * n * 1.1 + b1 * 1.5 + b3 * (kp * (2.0 - 1.1) + ki * 0.25 + 0.5);
    assert!((l.state_rates[1] - current_rate).abs() < 1e-9 * current_rate.abs());
    assert!((l.state_rates[0] - 0.9).abs() < 1e-12);
    // The estimates bound the errors.
    assert!((&l.a - &a)
        .abs()
        .iter()
        .zip(l.a_error.iter())
        .all(|(e, bound)| e <= bound));
    // No outputs declared: C = I over the four states, D = 0.
    assert_eq!(l.c, DMatrix::identity(4, 4));
    assert_eq!(l.d, DMatrix::zeros(4, 2));
}

/// An output that reads the model is differenced like any other: the two-link arm's mass
/// matrix, M11 = 0.475 + 0.2 cos q2 and M12 = 0.055 + 0.1 cos q2 (its header's bodies: the
/// upper link's 0.045 + 2·0.25² and the lower's 0.015 + 1·0.2² about their joints,
/// m2 l1² = 0.25, m2 l1 c2 = 0.1), whose rows of C are −0.2 sin q2 and −0.1 sin q2 along the
/// elbow's angle.
#[test]
fn outputs_that_read_the_model_are_differentiated() {
    let prepared = prepared("control/computed_torque_arm", &[]);
    let l = linearize(&prepared, &request(OperatingPoint::Initial, &[])).unwrap();
    let row = |name: &str| l.outputs.iter().position(|o| o == name).unwrap();
    let q2: f64 = -0.05;
    assert!(l.c.iter().all(|c| c.is_finite()), "{}", l.c);
    #[rustfmt::skip]
    let expected = [
        ("m11", [0.0, -0.2 * q2.sin(), 0.0, 0.0]),
        ("m12", [0.0, -0.1 * q2.sin(), 0.0, 0.0]),
        ("m22", [0.0, 0.0, 0.0, 0.0]),
    ];
    for (name, derivative) in expected {
        for (k, d) in derivative.iter().enumerate() {
            let found = l.c[(row(name), k)];
            assert!(
                (found - d).abs() < 1e-9,
                "{name}, column {k}: {found} against {d}"
            );
        }
    }
}

/// A state named as an input must be constant: holding it would change the program's model.
#[test]
fn a_state_with_a_rate_is_no_input() {
    let prepared = prepared_text(PI_MOTOR);
    let error = linearize(&prepared, &request(OperatingPoint::Initial, &["current"]))
        .unwrap_err()
        .to_string();
    assert!(error.contains("`current` has a rate"), "{error}");
}
