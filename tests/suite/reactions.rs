//! The wrenches the joins transmit (`simulate --reactions`) where more than the bodies' own
//! dynamics acts in them: a geared rotor's torque on the body that carries it, against the same
//! arm with each rotor an explicit body on its own joint that mimics the geared one, and against
//! the rotor's torque by hand; a stop's contact force holding a four-bar at rest, against the
//! balance of moments of the weights along the four-bar's one motion.

use std::cell::RefCell;
use std::rc::Rc;

use super::common::programs::{example_text, initial_state, prepared_text};
use lsdc::dynamics::loops::Stabilisation;
use lsdc::simulate::prepare::Prepared;
use lsdc::simulate::run::reaction_names_of;
use lsdc::simulate::system::MechanicalSystem;
use nalgebra::{Rotation3, Vector3};

fn system(prepared: &Prepared) -> MechanicalSystem<'_> {
    let reference = Rc::new(RefCell::new(prepared.coordinates.clone()));
    MechanicalSystem::new(&prepared.model, reference, Stabilisation::Projection)
}

/// The reactions and accelerations of a prepared program at its initial state.
fn reactions_at_start(prepared: &Prepared) -> (Vec<f64>, Vec<f64>) {
    let mut system = system(prepared);
    let y = initial_state(prepared);
    let mut dydt = vec![0.0; y.len()];
    system.derivative(0.0, &y, &mut dydt).expect("f");
    let (q, v) = prepared.model.split_state(&y);
    let reactions = system.reactions(0.0, &q, v).expect("reactions");
    let accelerations = dydt[prepared.model.positions()..].to_vec();
    (reactions, accelerations)
}

/// The six reaction numbers of join `name`.
fn reaction<'r>(prepared: &Prepared, reactions: &'r [f64], name: &str) -> &'r [f64] {
    let names = reaction_names_of(prepared);
    let k = names.iter().position(|n| n == name).expect("join");
    &reactions[6 * k..6 * k + 6]
}

fn largest_difference(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

/// `examples/geared_arm.lsd` moving: both joints turning, so that the elbow's rotor, carried by
/// the upper arm, feels the upper arm's rotation (its gyroscopic torque).
fn geared_arm(replacements: &[(&str, &str)]) -> Prepared {
    let moving = (
        "initial shoulder.q = 0.3, shoulder.q' = 0.5, elbow.q = -0.4 ;",
        "initial shoulder.q = 0.3, shoulder.q' = 0.5, elbow.q = -0.4, elbow.q' = 0.8 ;",
    );
    let mut all = vec![moving];
    all.extend_from_slice(replacements);
    let mut prepared = prepared_text(&example_text("geared_arm", &all));
    prepared.settings.reactions = true;
    prepared
}

/// The geared arm with each rotor an explicit body on a revolute joint of its own, placed as the
/// geared joint's first frame and mimicking it with the gear's ratio: a disc without mass, of
/// moment J about its axis and J / 2 about the others, its transverse moments taken from the
/// upper arm that carries it (a geared rotor's transverse inertia is its carrier's). The
/// rotor's spin then has the kinetic energy ½ J (ε·ω_B + n q̇)² of a geared rotor.
fn explicit_rotors() -> Prepared {
    let rotors = "let shoulder_rotor = body mass = 0, iframe = [0, 0, 0] ++ 1, inertia = [1.5e-5, 1.5e-5, 3e-5] end ;\n\
        let elbow_rotor = body mass = 0, iframe = [0, 0, 0] ++ 1, inertia = [0.001, 0.002, 0.001] end ;\n\
        join [0, 0, 0.3] ++ 1 @ earth and shoulder_rotor with mimic_revolute([0, 0, 1], shoulder, 100, 0) as shoulder_motor ;\n\
        join [0.4, 0.05, 0] ++ 1 @ upper and elbow_rotor with mimic_revolute([0, 1, 0], elbow, 50, 0) as elbow_motor ;";
    geared_arm(&[
        (
            "geared_revolute([0, 0, 1], 100, 3e-5)",
            "revolute([0, 0, 1])",
        ),
        ("geared_revolute([0, 1, 0], 50, 0.002)", "revolute([0, 1, 0])"),
        ("as elbow ;", &format!("as elbow ;\n{rotors}")),
        ("inertia = [0.01, 0.05, 0.05]", "inertia = [0.009, 0.05, 0.049]"),
        (
            "elbow.q' = 0.8 ;",
            "elbow.q' = 0.8, shoulder_motor.q = 30, shoulder_motor.q' = 50, elbow_motor.q = -20, elbow_motor.q' = 40 ;",
        ),
    ])
}

#[test]
fn a_geared_rotor_s_torque_is_in_the_reaction_of_the_joins_that_carry_it() {
    let geared = geared_arm(&[]);
    let explicit = explicit_rotors();
    let (with_gears, a_geared) = reactions_at_start(&geared);
    let (with_bodies, a_explicit) = reactions_at_start(&explicit);
    // Each explicit rotor's velocity follows its geared joint's.
    let accelerations = largest_difference(&a_geared, &[a_explicit[0], a_explicit[2]]);
    assert!(
        accelerations < 1e-12,
        "accelerations {a_geared:?} vs {a_explicit:?}"
    );
    for join in ["shoulder", "elbow"] {
        let (g, e) = (
            reaction(&geared, &with_gears, join),
            reaction(&explicit, &with_bodies, join),
        );
        let scale = e.iter().fold(1.0_f64, |m, x| m.max(x.abs()));
        let difference = largest_difference(g, e);
        assert!(
            difference < 1e-12 * scale,
            "{join}: geared {g:?}\nexplicit {e:?}\n(off by {difference:e})"
        );
    }
    // The elbow's rotor by hand: its axis ε (the upper arm's y) is square to the upper arm's
    // rotation ω_B = ṡ z, so its spin rate is n ė and its torque
    // τ_r = J (n ë ε + n ė ω_B × ε); its joint also turns its transverse moment J / 2 with
    // the upper arm, (J / 2) s̈ z (ω_B × (J / 2) ω_B = 0).
    let (n, inertia) = (50.0, 0.002);
    let (shoulder, shoulder_rate, elbow_rate) = (0.3, 0.5, 0.8);
    let axis = Rotation3::from_axis_angle(&Vector3::z_axis(), shoulder) * Vector3::y();
    let spin = Vector3::new(0.0, 0.0, shoulder_rate);
    let torque = inertia * n * (a_geared[1] * axis + elbow_rate * spin.cross(&axis));
    let by_hand = torque + 0.5 * inertia * a_geared[0] * Vector3::z();
    let motor = reaction(&explicit, &with_bodies, "elbow_motor");
    let rotor_difference = largest_difference(&motor[..3], by_hand.as_slice());
    assert!(
        rotor_difference < 1e-12 * by_hand.amax() && motor[3..].iter().all(|f| f.abs() < 1e-12),
        "rotor {motor:?} vs {by_hand:?}"
    );
    // The rotor's torque matters: it is far above round-off in the shoulder's reaction.
    assert!(torque.amax() > 1e-2, "{torque:?}");
}
