//! The studies beside `simulate` and `inverse` on mechanisms with motions imposed in time
//! (`drive`, `time` in a dof chain): `linearize` keeps the driven coordinates on their laws,
//! out of the state, and its A about a run's state at time T is the time-varying model's A(T),
//! against closed forms (Kapitza's pendulum, a bead on a rod turned by a drive). `statics`,
//! `eval`, `kinematics`, and `linearize` with loops or at an equilibrium refuse them with E0491
//! (golden files `tests/golden/commands/*_imposed_motion.*` and
//! `tests/golden/linearize/imposed_motion_*`, run by those folders' tests).

use nalgebra::DMatrix;

use crate::common::programs::{prepared, prepared_text};
use lsdc::studies::linearize::{linearize, Linearization, OperatingPoint, Request};
use lsdc::studies::statics::{holding_efforts, StaticsError};

fn at(point: OperatingPoint, inputs: &[&str]) -> Request {
    Request {
        point,
        inputs: inputs.iter().map(|s| s.to_string()).collect(),
        coordinates: Vec::new(),
    }
}

/// A = [[0, 1], [a21, 0]] to `tolerance`, the entry's own error estimate below it.
fn assert_oscillator(l: &Linearization, a21: f64, tolerance: f64) {
    let expected = DMatrix::from_row_slice(2, 2, &[0.0, 1.0, a21, 0.0]);
    let error = (&l.a - &expected).amax();
    assert!(
        error < tolerance * a21.abs().max(1.0),
        "A = {} against a21 = {a21}: {error:e}",
        l.a
    );
}

/// Kapitza's pendulum (examples/kapitza_pendulum.lsd): a bob at distance l from a pivot
/// shaken vertically, z(t) = a sin(w t), obeys θ'' = −(g + z''(t)) / l sin θ, so about a state
/// (θ, θ') at time T the linear model in (θ, θ') alone is A(T) = [[0, 1], [−(g + z''(T)) / l
/// cos θ, 0]]. The pivot's height `swing.motion1` is imposed by the time: no state of it.
#[test]
fn kapitza_pendulum_is_linearised_in_its_angle_with_the_pivot_on_its_law() {
    let (a, w, l, g) = (0.01, 300.0, 0.1, 9.81);
    let pivot_acceleration = |t: f64| -a * w * w * f64::sin(w * t);
    let a21 = |theta: f64, t: f64| -(g + pivot_acceleration(t)) / l * theta.cos();

    let initial = linearize(
        &prepared("kapitza_pendulum", &[]),
        &at(OperatingPoint::Initial, &[]),
    )
    .unwrap();
    assert_eq!(initial.states, ["swing.q", "swing.q'"]);
    assert_eq!(initial.driven, ["swing.motion1"]);
    assert_eq!(initial.state, [2.9, 0.0]);
    assert_oscillator(&initial, a21(2.9, 0.0), 1e-9);

    // At T = 0.0123 the pivot accelerates upwards at z'' = 469 m/s² (48 g): A(T)
    // is about 49 times what gravity alone gives, with the run's θ(T).
    let time = 0.0123;
    let run = prepared(
        "kapitza_pendulum",
        &[("duration = 2", &format!("duration = {time}"))],
    );
    let later = linearize(&run, &at(OperatingPoint::EndOfRun, &[])).unwrap();
    assert_eq!(later.time, time);
    assert_eq!(later.states, ["swing.q", "swing.q'"]);
    let theta = later.state[0];
    assert_oscillator(&later, a21(theta, time), 1e-9);
    // The acceleration at the operating point is the equation's too.
    let expected = -(g + pivot_acceleration(time)) / l * theta.sin();
    assert!(
        (later.accelerations[0] - expected).abs() < 1e-9 * expected.abs(),
        "{} against {expected}",
        later.accelerations[0]
    );
}

/// A bead on a rod that a drive turns about a vertical axis at ω(t) = 3 + t: along the rod
/// r'' = ω² r whatever the rod's angular acceleration (its tangential equation is the rod's
/// push), so A(T) = [[0, 1], [ω(T)², 0]] in (r, r'), the rod's angle not a state.
#[test]
fn bead_on_a_driven_rod_is_linearised_along_the_rod() {
    let text = |duration: f64| {
        format!(
            "import joints ;\n\
             let rod = body mass = 1, iframe = [0.5, 0, 0] ++ 1, inertia = [0.01, 0.1, 0.1] end ;\n\
             let bead = body mass = 0.2, iframe = 1, inertia = [0, 0, 0] end ;\n\
             join earth and rod with revolute([0, 0, 1]) as spin ;\n\
             join rod and bead with prismatic([1, 0, 0]) as slide ;\n\
             drive spin.q = 3 * time + 0.5 * time ^ 2 ;\n\
             initial slide.q = 0.5 ;\n\
             simulate duration = {duration}, output = 0.01, tolerance = 1e-12 end ;\n"
        )
    };
    let initial = linearize(
        &prepared_text(&text(1.0)),
        &at(OperatingPoint::Initial, &["slide.q"]),
    )
    .unwrap();
    assert_eq!(initial.states, ["slide.q", "slide.q'"]);
    assert_eq!(initial.driven, ["spin.q"]);
    assert_oscillator(&initial, 9.0, 1e-9);
    // An input along the rod: B = [0, 1/m].
    assert!(
        (initial.b[(1, 0)] - 1.0 / 0.2).abs() < 1e-9,
        "{}",
        initial.b
    );

    let later = linearize(
        &prepared_text(&text(0.4)),
        &at(OperatingPoint::EndOfRun, &[]),
    )
    .unwrap();
    assert_eq!(later.time, 0.4);
    assert_oscillator(&later, 3.4 * 3.4, 1e-9);
}

/// An input along a driven coordinate moves nothing: refused, not a column of zeros.
#[test]
fn an_input_along_a_driven_coordinate_is_refused() {
    let refused = linearize(
        &prepared("kapitza_pendulum", &[]),
        &at(OperatingPoint::Initial, &["swing.motion1"]),
    )
    .unwrap_err();
    assert!(
        refused
            .to_string()
            .contains("`swing.motion1` is imposed by a law of time"),
        "{refused}"
    );
}

/// The statics of a driven mechanism is refused in the library too (not only by the command),
/// naming the driven coordinate.
#[test]
fn statics_refuses_a_driven_mechanism() {
    let refused = holding_efforts(&prepared("four_bar_driven", &[]), &["rocker.q".to_string()]);
    assert!(
        matches!(&refused, Err(StaticsError::ImposedMotion { name }) if name == "crank.q"),
        "{refused:?}"
    );
}
