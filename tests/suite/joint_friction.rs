//! Friction in joints (links' `friction`, `damping`): a block on an inclined prismatic joint
//! against the closed forms of its motion for both signs of its velocity, sliding back or
//! sticking where it stops (the switch located in time), a pendulum whose energy lost is the
//! dry friction times the angle it swept, viscous decay, and the refusals.

use crate::common::programs::{column, example_text, refusal_codes, run_text};
use lsdc::dynamics::friction::Phase;
use lsdc::prepare::{Integrator, Settings};
use lsdc::simulate::run::Simulation;

const G: f64 = 9.81;
const MASS: f64 = 2.0;
const SLOPE: f64 = 0.5;

fn settings(integrator: Integrator, duration: f64) -> Settings {
    Settings {
        integrator,
        duration,
        output: 0.05,
        rtol: 1e-12,
        atol: 1e-12,
        step: Some(1e-3),
        ..Settings::default()
    }
}

/// `friction_incline` with friction `dry` and starting rate `rate`.
fn incline(integrator: Integrator, dry: f64, rate: f64) -> Simulation {
    let text = example_text(
        "friction_incline",
        &[
            ("sin(slope)], 3, 0)", &format!("sin(slope)], {dry}, 0)")),
            (
                "initial slide.q' = 2",
                &format!("initial slide.q' = {rate}"),
            ),
        ],
    );
    let simulation = run_text(&text, settings(integrator, 1.5));
    assert!(
        simulation.report.failure.is_none(),
        "{:?}",
        simulation.report.failure
    );
    simulation
}

/// The closed form of the block's motion from rate v0 with friction F: uniformly accelerated
/// at −g sin α − s F / m while moving in direction s; where the rate reaches zero at t1, it
/// sticks when F ≥ m g sin α, and slides down from there otherwise. (x, ẋ) at t, and t1.
fn block_motion(dry: f64, v0: f64, t: f64) -> (f64, f64, Option<f64>) {
    let weight = G * SLOPE.sin();
    let a1 = -weight - v0.signum() * dry / MASS;
    let t1 = -v0 / a1;
    if t1 < 0.0 || t <= t1 {
        let stop = (t1 >= 0.0).then_some(t1);
        return (v0 * t + 0.5 * a1 * t * t, v0 + a1 * t, stop);
    }
    let x1 = v0 * t1 + 0.5 * a1 * t1 * t1;
    if dry >= MASS * weight {
        return (x1, 0.0, Some(t1));
    }
    let a2 = -weight + dry / MASS;
    let s = t - t1;
    (x1 + 0.5 * a2 * s * s, a2 * s, Some(t1))
}

#[test]
fn a_block_on_an_incline_follows_the_closed_forms_for_both_signs_of_its_rate() {
    // (friction, starting rate): up then back down; down throughout; up then stuck; down then
    // stuck.
    let cases = [(3.0, 2.0), (3.0, -2.0), (12.0, 2.0), (12.0, -1.5)];
    for integrator in [
        Integrator::DormandPrince,
        Integrator::Dop853,
        Integrator::Rk4,
    ] {
        for (dry, rate) in cases {
            let simulation = incline(integrator.clone(), dry, rate);
            let slide = column(&simulation, "slide.q");
            for sample in &simulation.samples {
                let (x, v, _) = block_motion(dry, rate, sample.time);
                let error = (sample.coordinates[slide] - x)
                    .abs()
                    .max((sample.rates[slide] - v).abs());
                assert!(
                    error < 1e-9,
                    "{integrator:?} F = {dry}, v0 = {rate}, t = {}: off by {error:e}",
                    sample.time
                );
            }
            let switches = &simulation.report.friction_switches;
            match block_motion(dry, rate, 0.0).2 {
                Some(t1) => {
                    assert_eq!(switches.len(), 1, "{switches:?}");
                    assert!(
                        (switches[0].time - t1).abs() < 1e-9,
                        "{integrator:?}: stop at {} for {t1}",
                        switches[0].time
                    );
                    let expected = if dry >= MASS * G * SLOPE.sin() {
                        Phase::Sticking
                    } else {
                        Phase::Slipping(-1.0)
                    };
                    assert_eq!(switches[0].phase, expected);
                }
                None => assert!(switches.is_empty(), "{switches:?}"),
            }
        }
    }
}

/// A pendulum with dry friction in its hinge: each swing ends where its rate reaches zero,
/// and the energy lost from the start to the end is F_c times the angle swept, the sum of the
/// swings between the turning points (the switches' positions), until it sticks.
#[test]
fn a_pendulum_loses_the_dry_friction_times_the_angle_it_swept() {
    let dry = 0.6;
    let text = format!(
        "import joints;\n\
         let rod = body mass = 1.2, iframe = [0, 0, -0.5] ++ 1, inertia = [0.1, 0.1, 0.001] end;\n\
         join earth and rod with friction_revolute([1, 0, 0], {dry}, 0) as swing;\n\
         apply force value = [0, 0, -9.81 * rod.mass], body = earth end on rod.iframe;\n\
         initial swing.q = 1.2;\n"
    );
    for integrator in [
        Integrator::DormandPrince,
        Integrator::Dop853,
        Integrator::Rk4,
        Integrator::Implicit,
    ] {
        let simulation = run_text(&text, settings(integrator.clone(), 8.0));
        let report = &simulation.report;
        assert!(report.failure.is_none(), "{:?}", report.failure);
        let switches = &report.friction_switches;
        assert!(switches.len() >= 3, "{switches:?}");
        let last = switches.last().expect("switches");
        assert_eq!(last.phase, Phase::Sticking, "{integrator:?}: {switches:?}");
        // Released from rest it slips at once (the start is not a switch): the turning points
        // are the switches.
        let mut swept = 0.0;
        let mut from = 1.2;
        for switch in switches {
            swept += (switch.position - from).abs();
            from = switch.position;
        }
        let energy =
            |s: &lsdc::simulate::run::Sample| s.kinetic_energy + s.potential_energy.expect("known");
        let first = simulation.samples.first().expect("samples");
        let end = simulation.samples.last().expect("samples");
        let lost = energy(first) - energy(end);
        let bound = if integrator == Integrator::Implicit {
            1e-6
        } else {
            1e-9
        };
        assert!(
            (lost - dry * swept).abs() < bound,
            "{integrator:?}: lost {lost}, F swept {}",
            dry * swept
        );
        // Stuck: the weight's torque there is within the friction.
        let torque = 1.2 * 9.81 * 0.5 * last.position.sin();
        assert!(torque.abs() <= dry, "{torque}");
        assert!((end.coordinates[0] - last.position).abs() < 1e-12);
    }
}

/// Viscous friction alone: ẋ = v0 e^(−c t / m) on a level prismatic joint.
#[test]
fn viscous_friction_decays_the_rate_exponentially() {
    let text = "import joints;\n\
        let block = body mass = 2, iframe = 0, inertia = [0.1, 0.1, 0.1] end;\n\
        join earth and block with friction_prismatic([1, 0, 0], 0, 0.7) as slide;\n\
        initial slide.q' = 1.5;\n";
    let simulation = run_text(text, settings(Integrator::Dop853, 3.0));
    assert!(simulation.report.failure.is_none());
    for sample in &simulation.samples {
        let decay = (-0.7 * sample.time / 2.0f64).exp();
        let x = 1.5 * 2.0 / 0.7 * (1.0 - decay);
        assert!((sample.rates[0] - 1.5 * decay).abs() < 1e-10);
        assert!((sample.coordinates[0] - x).abs() < 1e-10);
        // The work of the friction is what the kinetic energy lost.
        let work = sample.work.expect("non-conservative");
        assert!((0.5 * 2.0 * 1.5f64.powi(2) + work - sample.kinetic_energy).abs() < 1e-9);
    }
}

#[test]
fn bad_friction_is_refused() {
    let program = |link: &str| {
        format!(
            "import joints;\n\
             let rod = body mass = 1, iframe = [0, 0, -0.5] ++ 1, inertia = [0.1, 0.1, 0.1] end;\n\
             join earth and rod with {link} as swing;\n"
        )
    };
    for link in [
        "friction_revolute([1, 0, 0], -1, 0)",
        "friction_revolute([1, 0, 0], 1, -0.5)",
        "link(a, b) dof1 = a || [1, 0, 0], dof2 = b || [0, 1, 0], friction = 1 end",
    ] {
        let codes = refusal_codes(&program(link));
        assert!(codes.iter().any(|c| c == "E0474"), "{link}: {codes:?}");
    }
}

/// The sampler mirrors the run's phases: once the block launched up the slope sticks (dry
/// friction 20 N above its weight along the slope, 9.41 N), its accelerations are zero and the
/// reaction of its joint balances its weight exactly, which the outputs' own evaluation gives
/// only if it holds the joint as the run does.
#[test]
fn the_reactions_see_a_sticking_joint_held() {
    let text = example_text(
        "friction_incline",
        &[("sin(slope)], 3, 0)", "sin(slope)], 20, 0)")],
    );
    let compilation = lsdc::driver::compile_text(
        "test.lsd",
        &text,
        None,
        &lsdc::load::LoadOptions {
            library_dirs: Vec::new(),
            use_environment: false,
            scene: None,
        },
    );
    let mechanism = compilation.mechanism.expect("elaborates");
    let settings = Settings {
        reactions: true,
        ..Settings::default()
    };
    let prepared = lsdc::prepare::prepare(&mechanism, &[], &settings).expect("prepares");
    let simulation = lsdc::simulate::run::run(&prepared, &mut |_| {});
    assert!(simulation.report.failure.is_none());
    let switches = &simulation.report.friction_switches;
    assert_eq!(switches.len(), 1, "{switches:?}");
    assert_eq!(switches[0].phase, Phase::Sticking);
    let weight = 9.81 * MASS;
    let mut checked = 0;
    for sample in simulation
        .samples
        .iter()
        .filter(|s| s.time > switches[0].time)
    {
        // The joint's wrench on the block, fixed axes: moment, then force.
        let force = &sample.reactions[3..6];
        assert!(
            force[0].abs() < 1e-9 && force[1].abs() < 1e-9 && (force[2] - weight).abs() < 1e-9,
            "t = {}: {force:?}",
            sample.time
        );
        checked += 1;
    }
    assert!(checked > 10);
}
