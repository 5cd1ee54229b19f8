//! Mimic joints and joint friction on mechanisms with closed loops: their rows solved with the
//! loops' (`dynamics::rows`). A four-bar carrying a plate that mimics its crank
//! against the same four-bar with the plate welded to the crank; a four-bar with dry friction in
//! its crank's pivot against separate integrations of each swing under a constant torque, its
//! energy lost against the friction times the angle swept, and its sticking threshold against
//! the holding torque of statics.

use crate::common::programs::{column, constraints, example_text, prepared, run_text};
use lsdc::dynamics::friction::Phase;
use lsdc::prepare::{Integrator, Settings};
use lsdc::simulate::run::Simulation;
use lsdc::studies::statics::holding_efforts;

fn settings(duration: f64, output: f64, tolerance: f64) -> Settings {
    Settings {
        integrator: Integrator::DormandPrince,
        duration,
        output,
        rtol: tolerance,
        atol: tolerance,
        ..Settings::default()
    }
}

/// An example's text with some of it replaced and without its `simulate` declaration, whose
/// settings would take precedence over a test's.
fn variant(name: &str, replacements: &[(&str, &str)]) -> String {
    let text = example_text(name, replacements);
    let start = text
        .find("simulate duration")
        .expect("a simulate declaration");
    let end = start + text[start..].find(';').expect("its end");
    format!("{}{}", &text[..start], &text[end + 1..])
}

fn succeeded(simulation: Simulation) -> Simulation {
    assert!(
        simulation.report.failure.is_none(),
        "{:?}",
        simulation.report.failure
    );
    simulation
}

const MIMIC: &str = "join earth and plate with mimic_revolute([0, 0, 1], crank, 1, 0.3) as turn ;";

/// The plate mimicking the crank with multiplier 1 and offset 0.3 turns with it as if welded to
/// it at 0.3 rad: the four-bar moves as the one whose crank carries the plate, to the
/// integration's accuracy, with the coupling and the loop closed at round-off.
#[test]
fn a_mimic_on_a_four_bar_moves_as_the_welded_body() {
    let mimic = variant("four_bar_mimic", &[]);
    let welded = variant(
        "four_bar_mimic",
        &[(
            MIMIC,
            "join bar1 and plate with link dof = 0.3 || [0, 0, 1] end as weld ;",
        )],
    );
    let (mimic, welded) = (
        succeeded(run_text(&mimic, settings(3.0, 0.05, 1e-12))),
        succeeded(run_text(&welded, settings(3.0, 0.05, 1e-12))),
    );
    let (follower, leader) = (column(&mimic, "turn.q"), column(&mimic, "crank.q"));
    let mut largest = (0.0f64, 0.0f64);
    for (a, b) in mimic.samples.iter().zip(&welded.samples) {
        for name in ["crank.q", "coupler.q", "rocker.q", "c.q"] {
            let (i, j) = (column(&mimic, name), column(&welded, name));
            largest.0 = largest.0.max((a.coordinates[i] - b.coordinates[j]).abs());
            largest.0 = largest.0.max((a.rates[i] - b.rates[j]).abs());
        }
        let position = a.coordinates[follower] - a.coordinates[leader] - 0.3;
        let rate = a.rates[follower] - a.rates[leader];
        largest.1 = largest.1.max(position.abs()).max(rate.abs());
    }
    // Measured: 2.3e-11 between the two runs, 6.1e-13 on the coupling.
    assert!(largest.0 < 1e-9, "motion {:e}", largest.0);
    assert!(largest.1 < 2e-12, "coupling {:e}", largest.1);
    assert!(constraints(&mimic).position_residual < 1e-11);
    assert!(mimic.report.energy_drift.is_some_and(|d| d.abs() < 1e-10));
}

/// A multiplier other than one: the plate turns backwards at half the crank's rate. The
/// energy is conserved (the coupling does no work) and the coupling held at round-off.
#[test]
fn a_mimic_with_another_multiplier_conserves_the_energy() {
    let text = variant(
        "four_bar_mimic",
        &[(MIMIC, &MIMIC.replace("crank, 1, 0.3", "crank, -0.5, 0.2"))],
    );
    let simulation = succeeded(run_text(&text, settings(3.0, 0.05, 1e-12)));
    let (follower, leader) = (
        column(&simulation, "turn.q"),
        column(&simulation, "crank.q"),
    );
    for sample in &simulation.samples {
        let position = sample.coordinates[follower] + 0.5 * sample.coordinates[leader] - 0.2;
        let rate = sample.rates[follower] + 0.5 * sample.rates[leader];
        assert!(
            position.abs() < 2e-12 && rate.abs() < 2e-12,
            "{position:e} {rate:e}"
        );
    }
    assert!(simulation
        .report
        .energy_drift
        .is_some_and(|d| d.abs() < 1e-10));
}

/// The time where the crank's rate of the frictionless four-bar, driven by a constant torque
/// `torque` on the crank from rest at crank angle `crank` (the other angles guessed), first
/// crosses zero, by linear interpolation between outputs 1e-4 s apart; and the other angles
/// there.
fn swing_end(crank: f64, guesses: [f64; 3], torque: f64) -> (f64, [f64; 3]) {
    let text = variant(
        "four_bar_friction",
        &[
            (
                "friction_revolute([0, 0, 1], 4, 0)",
                &format!("link(q) dof = q || [0, 0, 1], torque = [0, 0, {torque}] end"),
            ),
            (
                "initial crank.q = 1.0, coupler.q = -0.36 guess, rocker.q = 1.79 guess, c.q = 1.15 guess",
                &format!(
                    "initial crank.q = {crank}, coupler.q = {} guess, rocker.q = {} guess, c.q = {} guess",
                    guesses[0], guesses[1], guesses[2]
                ),
            ),
        ],
    );
    let simulation = succeeded(run_text(&text, settings(2.5, 1e-4, 1e-12)));
    let rate = column(&simulation, "crank.q");
    let others = ["coupler.q", "rocker.q", "c.q"].map(|n| column(&simulation, n));
    let samples = &simulation.samples;
    let moving = samples[1].rates[rate].signum();
    let k = (2..samples.len())
        .find(|&k| samples[k].rates[rate] * moving <= 0.0)
        .expect("the swing ends");
    let (before, after) = (&samples[k - 1], &samples[k]);
    let share = before.rates[rate] / (before.rates[rate] - after.rates[rate]);
    let time = before.time + share * (after.time - before.time);
    (time, others.map(|i| after.coordinates[i]))
}

/// Each swing of the four-bar with dry friction F_c = 4 N m in the crank's pivot is the
/// frictionless four-bar's under the constant torque −s F_c while the crank turns in direction
/// s: the first two switches located by the run against separate integrations of those swings,
/// started where the run's switches leave the crank at rest. The energy lost by the end is F_c
/// times the angle the crank swept between its switches.
#[test]
fn dry_friction_on_a_four_bar_switches_as_separate_swings_and_dissipates_its_work() {
    let text = variant("four_bar_friction", &[]);
    let simulation = succeeded(run_text(&text, settings(10.0, 0.05, 1e-12)));
    let switches = &simulation.report.friction_switches;
    assert!(switches.len() >= 4, "{switches:?}");
    assert_eq!(switches.last().expect("switches").phase, Phase::Sticking);
    // Released from rest at crank = 1 rad, gravity turns the crank back: the torque is +F_c.
    let (first, guesses) = swing_end(1.0, [-0.36, 1.79, 1.15], 4.0);
    // Measured: 8.2e-15 s and 1.1e-13 s apart.
    assert!(
        (first - switches[0].time).abs() < 1e-9,
        "{first} {}",
        switches[0].time
    );
    let (second, _) = swing_end(switches[0].position, guesses, -4.0);
    let duration = switches[1].time - switches[0].time;
    assert!((second - duration).abs() < 1e-9, "{second} {duration}");
    // The energy lost against the work of friction over the angle swept.
    let mut swept = 0.0;
    let mut from = 1.0;
    for switch in switches {
        swept += (switch.position - from).abs();
        from = switch.position;
    }
    let energy = |k: usize| {
        let sample = &simulation.samples[k];
        sample.kinetic_energy + sample.potential_energy.expect("a potential")
    };
    let lost = energy(0) - energy(simulation.samples.len() - 1);
    // Measured: 71.5790221 J for 17.8947555 rad, 6.6e-14 relative apart.
    assert!(
        (lost - 4.0 * swept).abs() < 1e-10 * lost,
        "{lost} {}",
        4.0 * swept
    );
}

/// The four-bar at rest sticks while the crank's dry friction can hold it: the threshold is the
/// holding torque `lsdc statics` finds for the frictionless four-bar (an independent solve of
/// the loops' statics). Just above it the run keeps the linkage at rest without a switch; just
/// below, the crank slips at once.
#[test]
fn a_four_bar_sticks_while_its_friction_exceeds_the_holding_torque() {
    let frictionless = prepared(
        "four_bar_friction",
        &[("friction_revolute([0, 0, 1], 4, 0)", "revolute([0, 0, 1])")],
    );
    let holding = holding_efforts(&frictionless, &["crank.q".to_string()]).expect("statics");
    let torque = holding.efforts[0].effort.abs();
    for (scale, sticks) in [(1.001, true), (0.999, false)] {
        let dry = scale * torque;
        let text = variant(
            "four_bar_friction",
            &[(
                "friction_revolute([0, 0, 1], 4, 0)",
                &format!("friction_revolute([0, 0, 1], {dry}, 0)"),
            )],
        );
        let simulation = succeeded(run_text(&text, settings(1.0, 0.05, 1e-12)));
        let crank = column(&simulation, "crank.q");
        let last = simulation.samples.last().expect("samples");
        let moved = (last.coordinates[crank] - 1.0).abs();
        match sticks {
            true => {
                assert!(simulation.report.friction_switches.is_empty());
                assert!(
                    moved < 1e-12 && last.rates[crank].abs() < 1e-12,
                    "{moved:e}"
                );
            }
            // Driven by 0.1 % of the holding torque, it turns by about 2e-3 rad in 1 s.
            false => assert!(moved > 1e-4, "{moved:e}"),
        }
    }
}
