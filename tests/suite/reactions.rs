//! The wrenches the joins transmit (`simulate --reactions`) where more than the bodies' own
//! dynamics acts in them: a geared rotor's torque on the body that carries it, against the same
//! arm with each rotor an explicit body on its own joint that mimics the geared one, and against
//! the rotor's torque by hand; a stop's contact force holding a four-bar at rest, against the
//! balance of moments of the weights along the four-bar's one motion, and holding a pendulum on
//! a rolling cylinder, against Newton–Euler by hand; a mimic coupling's force on a four-bar,
//! against the plate welded to the crank.

use super::common::programs::{example_text, initial_state, prepared_text};
use super::rows::rolling_pendulum;
use lsdc::dynamics::loops::Stabilisation;
use lsdc::dynamics::stops::{Side, Stop};
use lsdc::prepare::Prepared;
use lsdc::simulate::run::reaction_names_of;
use lsdc::simulate::system::MechanicalSystem;
use nalgebra::{Matrix2, Rotation3, Vector2, Vector3};

fn system(prepared: &Prepared) -> MechanicalSystem<'_> {
    let reference = prepared.coordinates.clone();
    MechanicalSystem::new(&prepared.model, reference, Stabilisation::Projection)
}

/// The reactions and accelerations of a prepared program at its initial state.
fn reactions_at_start(prepared: &Prepared) -> (Vec<f64>, Vec<f64>) {
    reactions_resting(prepared, None)
}

/// The reactions and accelerations of a prepared program at its initial state, its loops closed
/// and its contacts kept, resting on the lower stop of coordinate `resting` if given.
fn reactions_resting(prepared: &Prepared, resting: Option<&str>) -> (Vec<f64>, Vec<f64>) {
    let mut system = system(prepared);
    let mut y = initial_state(prepared);
    system.start_loops(&mut y).expect("closes");
    if let Some(coordinate) = resting {
        let stops = &prepared.model.stops;
        let lower = |s: &Stop| s.coordinate == coordinate && s.side == Side::Lower;
        let k = stops.iter().position(lower).expect("stop");
        system.state.resting[k] = true;
    }
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

/// The four-bar of `examples/limited_four_bar.lsd` (bars of 1 kg/m) at rest with its crank at
/// 0.6 rad: the crank torque that holds the weights, by virtual work along the four-bar's one
/// motion (crank rate 1), τ = g Σ mᵢ vᵢ,y with vᵢ the bars' centres' velocities. The coupler's
/// far end C is at l2 from the crank's end P and at l3 from the rocker's pivot O, above the
/// ground line (the example's branch).
fn holding_torque() -> f64 {
    let (l0, l1, l2, l3, g) = (4.0f64, 1.0f64, 3.5f64, 3.0f64, 9.81);
    let angle = |v: Vector2<f64>| v.y.atan2(v.x);
    let along = |a: f64| Vector2::new(a.cos(), a.sin());
    let square = |a: f64| Vector2::new(-a.sin(), a.cos());
    let crank = 0.6;
    let (p, o) = (l1 * along(crank), Vector2::new(l0, 0.0));
    let d = (o - p).norm();
    let x = (d * d + l2 * l2 - l3 * l3) / (2.0 * d);
    let u = (o - p) / d;
    let c = p + x * u + (l2 * l2 - x * x).sqrt() * Vector2::new(-u.y, u.x);
    let (coupler, rocker) = (angle(c - p), angle(c - o));
    // Velocities at crank rate 1: l1 e⊥(θ1) + l2 θ2' e⊥(θ2) = l3 θ3' e⊥(θ3).
    let closure = Matrix2::from_columns(&[l2 * square(coupler), -l3 * square(rocker)]);
    let rates = closure.lu().solve(&(-l1 * square(crank))).expect("regular");
    let centres = [
        0.5 * l1 * square(crank),
        l1 * square(crank) + 0.5 * l2 * rates[0] * square(coupler),
        0.5 * l3 * rates[1] * square(rocker),
    ];
    let masses = [l1, l2, l3];
    g * (masses.iter().zip(&centres))
        .map(|(m, v)| m * v.y)
        .sum::<f64>()
}

/// A crank of `examples/limited_four_bar.lsd` resting on its lower stop (0.6 rad), at rest:
/// the stop's torque holds the weights ([`holding_torque`]); the crank's reaction has that
/// moment about its axis (its bearing transmits none), and with the rocker's it carries the
/// weights to the ground.
#[test]
fn a_resting_stop_s_torque_is_in_the_reaction_of_its_join_on_a_four_bar() {
    let mut prepared = prepared_text(&example_text(
        "limited_four_bar",
        &[("initial crank.q = 1.0", "initial crank.q = 0.6")],
    ));
    prepared.settings.reactions = true;
    let (reactions, accelerations) = reactions_resting(&prepared, Some("crank.q"));
    assert!(
        accelerations.iter().all(|a| a.abs() < 1e-12),
        "{accelerations:?}"
    );
    let (torque, g) = (holding_torque(), 9.81);
    assert!(
        torque > 1.0,
        "the weights push the crank onto its lower stop: {torque}"
    );
    let on_crank = reaction(&prepared, &reactions, "crank");
    assert!(
        (on_crank[2] - torque).abs() < 1e-9 * torque,
        "crank's moment {} vs the stop's torque {torque}",
        on_crank[2]
    );
    let on_rocker = reaction(&prepared, &reactions, "rocker");
    let weight = g * (1.0 + 3.5 + 3.0);
    let ground = [
        on_crank[3] + on_rocker[3],
        on_crank[4] + on_rocker[4] - weight,
    ];
    assert!(ground.iter().all(|f| f.abs() < 1e-9 * weight), "{ground:?}");
}

/// The pendulum of the rolling cylinder (`stop_loops`) resting on its stop at 0.2 rad while the
/// cylinder rolls: the rod moves with the carriage, without turning (the carriage translates;
/// the weights are vertical, so it rolls on at constant speed), so its join carries
/// F = m (ẍ, 0, g) at its centre (`gravity_field`: g = 9.80665), r = (−d sin θ, 0, −d cos θ) from the join, and the moment
/// r × F about the join (Newton–Euler by hand, ẍ from the run's equations). The stop's torque
/// is the moment's y component: without it the rod would swing.
/// With `loop_closed`, the carriage is also joined to the ground by a second planar link
/// (`rows::rolling_pendulum`): its rows repeat the first's, which leaves the rod's join alone.
#[test]
fn a_resting_stop_s_torque_is_in_the_reaction_of_its_join_with_contacts() {
    for loop_closed in [false, true] {
        resting_stop_with_contacts(loop_closed);
    }
}

fn resting_stop_with_contacts(loop_closed: bool) {
    let (m, d, theta, g) = (0.8f64, 0.3f64, 0.2f64, 9.80665);
    // Rolling from the start (x' = −r q'), so that keeping the contact gives the rod no rate.
    let text = rolling_pendulum("0.2, 1.0", 0.0, ", swing.q = 0.2", loop_closed);
    let mut prepared = prepared_text(&text.replace("spin.q' = 10", "spin.q' = -10"));
    prepared.settings.reactions = true;
    let (reactions, accelerations) = reactions_resting(&prepared, Some("swing.q"));
    let model = &prepared.model;
    let index = |name: &str| (0..model.velocities()).position(|k| model.velocity_name(k) == name);
    let swing = index("swing.q").expect("swing");
    assert!(accelerations[swing].abs() < 1e-12, "{accelerations:?}");
    let x = accelerations[index("motion.x").expect("x")];
    let force = m * Vector3::new(x, 0.0, g);
    let moment = Vector3::new(-d * theta.sin(), 0.0, -d * theta.cos()).cross(&force);
    let by_hand = [moment.as_slice(), force.as_slice()].concat();
    let on_rod = reaction(&prepared, &reactions, "swing");
    let difference = largest_difference(on_rod, &by_hand);
    assert!(difference < 1e-9 * m * g, "{on_rod:?} vs {by_hand:?}");
}

/// `examples/four_bar_mimic.lsd`: a plate hinged on the ground follows the crank at 0.3 rad, a
/// mimic coupling solved with the loop's rows. The coupling's force acts on the crank's and the
/// plate's coordinates as link efforts do, so the crank's and the plate's joins, both at the
/// crank's pivot, transmit together what the crank transmits when the plate is welded to it;
/// the rocker's reaction is the same in both.
#[test]
fn a_mimic_coupling_s_force_is_in_the_reactions_of_a_four_bar() {
    let mimic = "join earth and plate with mimic_revolute([0, 0, 1], crank, 1, 0.3) as turn ;";
    let weld = "join bar1 and plate with link dof = 0.3 || [0, 0, 1] end as weld ;";
    let start = (
        "initial crank.q = 1.0,",
        "initial crank.q = 1.0, turn.q = 1.3,",
    );
    let mut coupled = prepared_text(&example_text("four_bar_mimic", &[start]));
    let mut welded = prepared_text(&example_text("four_bar_mimic", &[(mimic, weld)]));
    coupled.settings.reactions = true;
    welded.settings.reactions = true;
    let (with_mimic, _) = reactions_at_start(&coupled);
    let (with_weld, _) = reactions_at_start(&welded);
    let crank = reaction(&coupled, &with_mimic, "crank");
    let turn = reaction(&coupled, &with_mimic, "turn");
    let together: Vec<f64> = crank.iter().zip(turn).map(|(a, b)| a + b).collect();
    let expected = reaction(&welded, &with_weld, "crank");
    let scale = expected.iter().fold(1.0_f64, |m, x| m.max(x.abs()));
    let difference = largest_difference(&together, expected);
    assert!(difference < 1e-9 * scale, "{together:?} vs {expected:?}");
    let rocker = largest_difference(
        reaction(&coupled, &with_mimic, "rocker"),
        reaction(&welded, &with_weld, "rocker"),
    );
    assert!(rocker < 1e-9 * scale, "rocker off by {rocker:e}");
}

/// The run's samples see the crank resting as the run does: `examples/limited_four_bar.lsd`
/// stopped dead on its lower stop (restitution 0) rests there, and every later sample's crank
/// reaction has the holding torque about its axis.
#[test]
fn the_samples_reactions_see_a_four_bar_resting_on_its_stop() {
    let text = example_text("limited_four_bar", &[("0.6, 2.5, 0.5)", "0.6, 2.5, 0)")]);
    let mut prepared = prepared_text(&text);
    prepared.settings.reactions = true;
    let simulation = super::common::programs::simulated(&prepared);
    let impacts = &simulation.report.impacts;
    assert!(impacts.len() == 1 && impacts[0].rests, "{impacts:?}");
    let torque = holding_torque();
    let resting = (simulation.samples.iter()).filter(|s| s.time > impacts[0].time);
    let mut checked = 0;
    for sample in resting {
        let on_crank = reaction(&prepared, &sample.reactions, "crank");
        assert!(
            (on_crank[2] - torque).abs() < 1e-9 * torque,
            "t = {}: {} vs {torque}",
            sample.time,
            on_crank[2]
        );
        checked += 1;
    }
    assert!(checked > 10, "{checked}");
}
