//! `lsdc linearize` with the program's states (a motor's current, a controller's integral) as
//! rows and columns of A, constant states as inputs (a voltage), and outputs that read the
//! model, each against a closed form.

use nalgebra::DMatrix;

use crate::common::programs::{assembled_rates, prepared, prepared_text};
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

/// The seed's motor constants (table III.2) and reduction.
const SEED_MOTOR: (f64, f64, f64, f64, f64) = (1.35, 1.2e-3, 0.1194, 0.119, 12.0);

fn delta_request(inputs: &[&str]) -> Request {
    Request {
        point: OperatingPoint::Initial,
        inputs: inputs.iter().map(|s| s.to_string()).collect(),
        coordinates: (1..=3).map(|i| format!("leg[{i}]:A.q")).collect(),
    }
}

/// `by` in leg k's instance and 0 in the others: Lagrange's basis polynomial on the indices
/// 1, 2, 3, written with the package's index `i`.
fn in_leg(k: usize, by: f64) -> String {
    let others: Vec<usize> = (1..=3).filter(|&j| j != k).collect();
    let denominator: f64 = others.iter().map(|&j| k as f64 - j as f64).product();
    format!(
        "({by:e} / {denominator:e}) * (i - {}) * (i - {})",
        others[0], others[1]
    )
}

/// The Delta with the seed's motors (examples/control/delta_motors.lsd) in its arms' angles:
/// A has the seed's blocks [[0, I, 0], [Q, R, L], [0, N b2 I, b1 I]] and B = [0; 0; b3 I]
/// (§6; N b2 since the states are the arms' angles, θ = N α); L is N K_i times the response to
/// a torque on each arm (B's exact columns for generalised forces); and every row of A matches
/// plain central differences (step 1e-5) of the closed-loop model, each state made by the
/// program's own assembly (an arm's angle or rate, or a motor's starting current, moved in one
/// instance of the legs).
#[test]
fn delta_with_its_motors_has_the_seeds_state_model() {
    let (r, inductance, ke, ki, n) = SEED_MOTOR;
    let (b1, b2, b3) = (-r / inductance, -ke / inductance, 1.0 / inductance);
    let voltages = ["leg[1]:voltage", "leg[2]:voltage", "leg[3]:voltage"];
    let torques = ["leg[1]:A.q", "leg[2]:A.q", "leg[3]:A.q"];
    let inputs: Vec<&str> = voltages.iter().chain(&torques).copied().collect();
    let l = linearize(
        &prepared("control/delta_motors", &[]),
        &delta_request(&inputs),
    )
    .unwrap();
    let currents = ["leg[1]:current", "leg[2]:current", "leg[3]:current"];
    assert_eq!(&l.states[6..], currents);
    let block = |m: &DMatrix<f64>, row: usize, column: usize| {
        m.view((3 * row, 3 * column), (3, 3)).into_owned()
    };
    let identity = DMatrix::<f64>::identity(3, 3);
    let zero = DMatrix::<f64>::zeros(3, 3);
    let close = |found: DMatrix<f64>, expected: DMatrix<f64>, tolerance: f64, what: &str| {
        let gap = (&found - &expected).amax();
        assert!(gap <= tolerance, "{what}: {gap:e}\n{found}\n{expected}");
    };
    close(block(&l.a, 0, 0), zero.clone(), 0.0, "[0 I 0]");
    close(block(&l.a, 0, 1), identity.clone(), 0.0, "[0 I 0]");
    close(block(&l.a, 0, 2), zero.clone(), 0.0, "[0 I 0]");
    close(
        block(&l.a, 2, 0),
        zero.clone(),
        1e-9,
        "the currents along the angles",
    );
    close(
        block(&l.a, 2, 1),
        &identity * (n * b2),
        1e-9 * (n * b2).abs(),
        "N b2 I",
    );
    close(block(&l.a, 2, 2), &identity * b1, 1e-9 * b1.abs(), "b1 I");
    let b_voltages = l.b.columns(0, 3).into_owned();
    let b_torques = l.b.columns(3, 3).into_owned();
    close(
        b_voltages.rows(0, 6).into_owned(),
        DMatrix::zeros(6, 3),
        0.0,
        "B's zeros",
    );
    close(
        b_voltages.rows(6, 3).into_owned(),
        &identity * b3,
        1e-9 * b3,
        "b3 I",
    );
    // L = Mₐ⁻¹ N K_i: the currents' columns against the torques' exact ones.
    let response = b_torques.rows(3, 3).into_owned();
    let l_block = block(&l.a, 1, 2);
    close(
        l_block.clone(),
        &response * (n * ki),
        1e-9 * l_block.amax(),
        "L = Mₐ⁻¹ N K_i",
    );
    // At rest the velocity products vanish: R = 0 (to the differences' rounding).
    close(block(&l.a, 1, 1), zero, 1e-9, "R at rest");

    // Every row of A against plain central differences through the program's assembly.
    let rates_at = |moved: usize, by: f64| -> Vec<f64> {
        let leg = moved % 3 + 1;
        let (from, to) = match moved / 3 {
            0 => (
                "initial A.q = 40 * pi / 180 fixed,".to_string(),
                format!("initial A.q = 40 * pi / 180 + {} fixed,", in_leg(leg, by)),
            ),
            1 => (
                "initial A.q = 40 * pi / 180 fixed,".to_string(),
                format!(
                    "initial A.q = 40 * pi / 180 fixed, A.q' = {},",
                    in_leg(leg, by)
                ),
            ),
            _ => (
                "dc_current(0)".to_string(),
                format!("dc_current({})", in_leg(leg, by)),
            ),
        };
        let prepared = prepared("control/delta_motors", &[(&from, &to)]);
        let (accelerations, states) = assembled_rates(&prepared, &torques);
        let state_names: Vec<&str> = (prepared.model.states.iter())
            .map(|s| s.name.as_str())
            .collect();
        let current_rates =
            (currents.iter()).map(|c| states[state_names.iter().position(|s| s == c).unwrap()]);
        accelerations
            .into_iter()
            .chain(current_rates)
            .collect::<Vec<f64>>()
    };
    let step = 1e-5;
    let mut largest = 0.0_f64;
    for column in 0..9 {
        let ahead = rates_at(column, step);
        let behind = rates_at(column, -step);
        for row in 0..6 {
            let difference = (ahead[row] - behind[row]) / (2.0 * step);
            let gap = (difference - l.a[(3 + row, column)]).abs();
            largest = largest.max(gap / l.a[(3 + row, column)].abs().max(1.0));
        }
    }
    assert!(
        largest < 1e-6,
        "largest relative difference {largest:e}\n{}",
        l.a
    );
}

/// At the state a run reaches (`--at-time`), the program's states are the run's: the linear
/// model's operating state is the run's last sample, states included.
#[test]
fn at_a_run_s_state_the_states_are_the_run_s() {
    let text = format!(
        "{PI_MOTOR}simulate duration = 0.25, output = 0.05, integrator = dopri5, tolerance = 1e-10 end ;\n"
    );
    let prepared = prepared_text(&text);
    let l = linearize(
        &prepared,
        &request(OperatingPoint::EndOfRun, &["disturbance"]),
    )
    .unwrap();
    let simulation = lsdc::simulate::run::run(&prepared, &mut |_| {});
    let last = simulation.samples.last().unwrap();
    let column = |name: &str| crate::common::programs::output(&simulation, name);
    assert_eq!(l.time, last.time);
    assert_eq!(l.state[..2], [last.coordinates[0], last.rates[0]]);
    let states = [
        last.outputs[column("integral")],
        last.outputs[column("current")],
    ];
    assert_eq!(l.state[2..], states);
    // The states moved: the run is not at its start.
    assert!(states[0] != 0.25 && states[1] != 1.5, "{states:?}");
    assert_eq!(l.input, [0.5]);
}
