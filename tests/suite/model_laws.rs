//! Laws that read the model (`actuate`, `mass_matrix`, `bias`, `gravity_effort`,
//! `inverse_dynamics`): computed torques track their references with the closed form of their
//! linear error dynamics, on a tree and on the Delta in its actuated coordinates; the mass
//! matrix against the two-link arm's closed form, the gravity efforts against `lsdc statics`.

use crate::common::programs::{prepared, simulated};
use lsdc::simulate::run::Simulation;
use lsdc::studies::statics::holding_efforts;

/// The values of output `name` at every sample, with the samples' times.
fn output(simulation: &Simulation, name: &str) -> Vec<(f64, f64)> {
    let k = (simulation.output_names.iter().position(|n| n == name))
        .unwrap_or_else(|| panic!("no output {name}"));
    let samples = simulation.samples.iter();
    samples.map(|s| (s.time, s.outputs[k])).collect()
}

/// The largest difference of an error's output from the critically damped closed form
/// e0 (1 + w t) exp(−w t) of e'' + 2 w e' + w² e = 0 from rest.
fn worst_tracking(simulation: &Simulation, name: &str, e0: f64, w: f64) -> f64 {
    output(simulation, name)
        .iter()
        .map(|&(t, e)| (e - e0 * (1.0 + w * t) * (-w * t).exp()).abs())
        .fold(0.0, f64::max)
}

#[test]
fn a_computed_torque_on_a_two_link_arm_leaves_the_linear_error_dynamics() {
    let simulation = simulated(&prepared("control/computed_torque_arm", &[]));
    let shoulder = worst_tracking(&simulation, "shoulder_error", -0.1, 10.0);
    let elbow = worst_tracking(&simulation, "elbow_error", 0.05, 10.0);
    println!(
        "worst tracking error against the closed form: shoulder {shoulder:e}, elbow {elbow:e}"
    );
    assert!(shoulder < 1e-9 && elbow < 1e-9, "{shoulder:e} {elbow:e}");
}

#[test]
fn a_computed_torque_on_the_delta_in_its_actuated_coordinates_leaves_the_linear_error_dynamics() {
    let simulation = simulated(&prepared("control/computed_torque_delta", &[]));
    for name in ["error1", "error2", "error3"] {
        let worst = worst_tracking(&simulation, name, -0.02, 20.0);
        println!("{name}: worst difference from the closed form {worst:e}");
        assert!(worst < 1e-9, "{name}: {worst:e}");
    }
}

/// Without the model (the reduced mass replaced by a constant, the bias left out), the same
/// PD does not give the closed form: the tracking test can fail.
#[test]
fn without_the_model_the_arm_does_not_follow_the_closed_form() {
    let replaced = [(
        "actuate shoulder.q = inverse_dynamics(shoulder.q, shoulder.q, wanted(shoulder, r1), elbow.q, wanted(elbow, r2)) ;",
        "actuate shoulder.q = 0.6 * wanted(shoulder, r1) ;",
    )];
    let simulation = simulated(&prepared("control/computed_torque_arm", &replaced));
    let shoulder = worst_tracking(&simulation, "shoulder_error", -0.1, 10.0);
    assert!(shoulder > 1e-3, "{shoulder:e}");
}

/// The two-link arm's mass matrix in closed form (both joints about y, centres of mass on the
/// links' axes): m22 = I2 + m2 c2², m12 = m22 + m2 l1 c2 cos q2,
/// m11 = I1 + m1 c1² + I2 + m2 (l1² + c2² + 2 l1 c2 cos q2).
#[test]
fn the_mass_matrix_is_the_two_link_arms_closed_form() {
    let simulation = simulated(&prepared("control/computed_torque_arm", &[]));
    let (m1, c1, i1, m2, c2, i2, l1) = (2.0, 0.25, 0.045, 1.0, 0.2, 0.015, 0.5);
    let elbow = simulation
        .coordinate_names
        .iter()
        .position(|n| n == "elbow.q")
        .unwrap();
    let mut worst: f64 = 0.0;
    for (k, sample) in simulation.samples.iter().enumerate() {
        let cos = sample.coordinates[elbow].cos();
        let m22 = i2 + m2 * c2 * c2;
        let m12 = m22 + m2 * l1 * c2 * cos;
        let m11 = i1 + m1 * c1 * c1 + i2 + m2 * (l1 * l1 + c2 * c2 + 2.0 * l1 * c2 * cos);
        for (name, closed) in [("m11", m11), ("m12", m12), ("m22", m22)] {
            worst = worst.max((output(&simulation, name)[k].1 - closed).abs());
        }
    }
    println!("mass matrix against the closed form: {worst:e}");
    assert!(worst < 1e-14, "{worst:e}");
}

/// The gravity efforts at the start are the efforts `lsdc statics` finds to hold the mechanism
/// (the program without its actuators, whose laws statics would count).
#[test]
fn the_gravity_efforts_are_what_statics_holds() {
    let arm = simulated(&prepared("control/computed_torque_arm", &[]));
    let statics_program = prepared(
        "control/computed_torque_arm",
        &[
            (
                "actuate shoulder.q = inverse_dynamics",
                "let a1 = inverse_dynamics",
            ),
            (
                "actuate elbow.q = inverse_dynamics",
                "let a2 = inverse_dynamics",
            ),
            ("output m11 = mass_matrix(shoulder.q, shoulder.q) ;", ""),
            ("output m12 = mass_matrix(shoulder.q, elbow.q) ;", ""),
            ("output m22 = mass_matrix(elbow.q, elbow.q) ;", ""),
            ("output g1 = gravity_effort(shoulder.q) ;", ""),
            ("output g2 = gravity_effort(elbow.q) ;", ""),
        ],
    );
    let names = ["shoulder.q".to_string(), "elbow.q".to_string()];
    let held = holding_efforts(&statics_program, &names).expect("statics");
    for (k, name) in ["g1", "g2"].iter().enumerate() {
        let gravity = output(&arm, name)[0].1;
        let statics = held.efforts[k].effort;
        println!("{name}: gravity effort {gravity:e}, statics {statics:e}");
        assert!((gravity - statics).abs() < 1e-12 * statics.abs().max(1.0));
    }
    let delta = simulated(&prepared("control/computed_torque_delta", &[]));
    let statics_program = prepared(
        "control/computed_torque_delta",
        &[
            ("actuate leg[1]:A.q = effort", "let e1 = effort"),
            ("actuate leg[2]:A.q = effort", "let e2 = effort"),
            ("actuate leg[3]:A.q = effort", "let e3 = effort"),
            ("output gravity1 = gravity_effort(leg[1]:A.q) ;", ""),
            (
                "output inertia11 = mass_matrix(leg[1]:A.q, leg[1]:A.q) ;",
                "",
            ),
        ],
    );
    let names = [
        "leg[1]:A.q".to_string(),
        "leg[2]:A.q".to_string(),
        "leg[3]:A.q".to_string(),
    ];
    let held = holding_efforts(&statics_program, &names).expect("statics");
    let gravity = output(&delta, "gravity1")[0].1;
    println!(
        "Delta: gravity effort {gravity:e}, statics {:e}",
        held.efforts[0].effort
    );
    assert!(
        (gravity - held.efforts[0].effort).abs() < 1e-10,
        "{gravity:e}"
    );
}

/// The four-bar reduced to its crank's angle: the reduced mass and the gravity effort against
/// the reduced Lagrangian written by hand (`linearize::four_bar_reference`), through its loop.
#[test]
fn the_four_bars_model_in_its_crank_angle_is_its_reduced_lagrangian() {
    let program = prepared(
        "four_bar",
        &[(
            "simulate duration = 10,",
            "actuate crank.q = 0 ;\noutput m = mass_matrix(crank.q, crank.q) ;\noutput g = gravity_effort(crank.q) ;\noutput b = bias(crank.q) ;\nsimulate duration = 0.5,",
        )],
    );
    let simulation = simulated(&program);
    let crank = simulation
        .coordinate_names
        .iter()
        .position(|n| n == "crank.q")
        .unwrap();
    let first = &simulation.samples[0];
    let reference = crate::linearize::four_bar_reference(first.coordinates[crank]);
    let (mass, gravity) = (output(&simulation, "m")[0].1, output(&simulation, "g")[0].1);
    let bias = output(&simulation, "b")[0].1;
    println!(
        "four-bar: M {mass:e} (by hand {:e}), G {gravity:e} (by hand {:e})",
        reference.mass, reference.holding
    );
    assert!(
        (mass - reference.mass).abs() < 1e-10 * reference.mass,
        "{mass:e}"
    );
    assert!(
        (gravity - reference.holding).abs() < 1e-10 * reference.holding.abs(),
        "{gravity:e}"
    );
    // At rest the bias is the gravity effort.
    assert!((bias - gravity).abs() < 1e-12 * gravity.abs(), "{bias:e}");
    // Along the run (the crank falling under gravity), the model in the crank's angle at each
    // sample.
    for (k, sample) in simulation.samples.iter().enumerate() {
        let reference = crate::linearize::four_bar_reference(sample.coordinates[crank]);
        let mass = output(&simulation, "m")[k].1;
        assert!(
            (mass - reference.mass).abs() < 1e-9 * reference.mass,
            "t = {}: {mass:e}",
            sample.time
        );
    }
}
