//! Mimic joints (links' `mimic`, `mimic_multiplier`, `mimic_offset`): the coupling against the
//! closed form of two meshed gears, held to round-off over long runs with every integrator,
//! energy conserved with gravity, impacts that keep it, and the refusals.

use crate::common::programs::{column, example_text, refusal_codes, run_text};
use lsdc::prepare::{Integrator, Settings};
use lsdc::simulate::run::Simulation;

fn settings(integrator: Integrator, duration: f64, tolerance: f64) -> Settings {
    Settings {
        integrator,
        duration,
        output: 0.1,
        rtol: tolerance,
        atol: tolerance,
        step: Some(2e-4),
        ..Settings::default()
    }
}

/// The largest |q_f − (m q_l + o)| and |q̇_f − m q̇_l| over the samples.
fn coupling_error(simulation: &Simulation, leader: &str, follower: &str, m: f64, o: f64) -> f64 {
    let (l, f) = (column(simulation, leader), column(simulation, follower));
    simulation
        .samples
        .iter()
        .map(|s| {
            let position = s.coordinates[f] - (m * s.coordinates[l] + o);
            let rate = s.rates[f] - m * s.rates[l];
            position.abs().max(rate.abs())
        })
        .fold(0.0, f64::max)
}

/// The gears of `meshed_gears` are one oscillator of inertia I_wheel + m² I_pinion: the
/// wheel's angle is 0.5 cos(ω t), ω² = k / I, and the pinion's follows it.
#[test]
fn meshed_gears_oscillate_as_one_body_of_reduced_inertia() {
    let text = example_text("meshed_gears", &[]);
    let omega = (8.0f64 / (0.02 + 9.0 * 0.004)).sqrt();
    for integrator in [Integrator::DormandPrince, Integrator::Dop853] {
        let simulation = run_text(&text, settings(integrator.clone(), 2.0, 1e-12));
        assert!(simulation.report.failure.is_none());
        let drive = column(&simulation, "drive.q");
        for sample in &simulation.samples {
            let expected = 0.5 * (omega * sample.time).cos();
            let rate = -0.5 * omega * (omega * sample.time).sin();
            let error = (sample.coordinates[drive] - expected).abs();
            let rate_error = (sample.rates[drive] - rate).abs();
            assert!(
                error < 1e-9 && rate_error < 1e-8,
                "{integrator:?} at {}: {error:e} {rate_error:e}",
                sample.time
            );
        }
        assert!(coupling_error(&simulation, "drive.q", "driven.q", -3.0, 0.2) < 1e-12);
    }
}

/// Two pendulums coupled through their angles, under gravity: the coupling holds to round-off
/// over 40 s whatever the integrator (it is a linear invariant of the eliminated dynamics), and
/// the energy is conserved to the integrator's accuracy.
#[test]
fn the_coupling_holds_to_round_off_with_every_integrator() {
    let text = "import joints;\n\
        let rod = body mass = 1, iframe = [0, 0, -0.5] ++ 1, inertia = [0.1, 0.1, 0.01] end;\n\
        let arm = body mass = 2, iframe = [0, 0, -0.3] ++ 1, inertia = [0.05, 0.05, 0.01] end;\n\
        join earth and rod with revolute([1, 0, 0]) as a;\n\
        join [0.5, 0, 0] ++ 1 @ earth and arm with mimic_revolute([1, 0, 0], a, -2, 0.1) as b;\n\
        apply force value = [0, 0, -9.81 * rod.mass], body = earth end on rod.iframe;\n\
        apply force value = [0, 0, -9.81 * arm.mass], body = earth end on arm.iframe;\n\
        initial a.q = 0.3, b.q = 5;\n";
    let cases = [
        (Integrator::DormandPrince, 1e-10, 1e-8),
        (Integrator::Dop853, 1e-10, 1e-8),
        (Integrator::Rk4, 1e-10, 1e-8),
        (Integrator::Implicit, 1e-8, 1e-5),
    ];
    for (integrator, tolerance, drift) in cases {
        let simulation = run_text(text, settings(integrator.clone(), 40.0, tolerance));
        assert!(
            simulation.report.failure.is_none(),
            "{:?}",
            simulation.report.failure
        );
        // `initial b.q = 5` is overridden: the follower starts where its leader puts it.
        let error = coupling_error(&simulation, "a.q", "b.q", -2.0, 0.1);
        assert!(error < 1e-12, "{integrator:?}: coupling off by {error:e}");
        let energy = |k: usize| {
            let s = &simulation.samples[k];
            s.kinetic_energy + s.potential_energy.expect("conservative")
        };
        let first = energy(0);
        let worst = (0..simulation.samples.len())
            .map(|k| (energy(k) - first).abs())
            .fold(0.0, f64::max);
        assert!(
            worst < drift * first.abs(),
            "{integrator:?}: energy drift {worst:e}"
        );
    }
}

/// A stop on the leader: the impact keeps the follower coupled (its rate jumps with the
/// leader's), and the kinetic energy keeps e² of itself (one independent coordinate).
#[test]
fn an_impact_on_the_leader_keeps_the_coupling() {
    let text = example_text(
        "meshed_gears",
        &[(
            "join earth and wheel with link(q)\n  dof = q || [0, 0, 1],",
            "join earth and wheel with link(q)\n  dof = q || [0, 0, 1],\n  lower = -0.3,\n  restitution = 0.5,",
        )],
    );
    let simulation = run_text(&text, settings(Integrator::DormandPrince, 1.0, 1e-12));
    let report = &simulation.report;
    assert!(report.failure.is_none(), "{:?}", report.failure);
    assert!(!report.impacts.is_empty());
    let impact = &report.impacts[0];
    assert!((impact.rate_after + 0.5 * impact.rate_before).abs() < 1e-12);
    assert!((impact.kinetic_after / impact.kinetic_before - 0.25).abs() < 1e-12);
    assert!(coupling_error(&simulation, "drive.q", "driven.q", -3.0, 0.2) < 1e-12);
}

#[test]
fn unsupported_mimics_are_refused() {
    let base = "import joints;\n\
        let rod = body mass = 1, iframe = [0, 0, -0.5] ++ 1, inertia = [0.1, 0.1, 0.01] end;\n\
        let arm = body mass = 2, iframe = [0, 0, -0.3] ++ 1, inertia = [0.05, 0.05, 0.01] end;\n\
        let tip = body mass = 1, iframe = 0, inertia = [0.01, 0.01, 0.01] end;\n\
        join earth and rod with LEADER as a;\n\
        join earth and arm with FOLLOWER as b;\n\
        join earth and tip with THIRD as c;\n";
    let program = |leader: &str, follower: &str, third: &str| {
        base.replace("LEADER", leader)
            .replace("FOLLOWER", follower)
            .replace("THIRD", third)
    };
    let cases = [
        // A mimic of a mimic.
        (
            program(
                "revolute([1, 0, 0])",
                "mimic_revolute([1, 0, 0], a, 2, 0)",
                "mimic_revolute([1, 0, 0], b, 2, 0)",
            ),
            "E0472",
        ),
        // A cycle cannot be written: a join is named after its link is built (E0301).
        (
            program(
                "mimic_revolute([1, 0, 0], b, 1, 0)",
                "mimic_revolute([1, 0, 0], a, 1, 0)",
                "revolute([0, 1, 0])",
            ),
            "E0301",
        ),
        // A leader with two coordinates.
        (
            program(
                "universal([1, 0, 0], [0, 1, 0])",
                "mimic_revolute([1, 0, 0], a, 2, 0)",
                "revolute([0, 1, 0])",
            ),
            "E0470",
        ),
        // A follower with two coordinates.
        (
            program(
                "revolute([1, 0, 0])",
                "link(x, y) dof1 = x || [1, 0, 0], dof2 = y || [0, 1, 0], mimic = a end",
                "revolute([0, 1, 0])",
            ),
            "E0470",
        ),
        // A multiplier without a leader.
        (
            program(
                "revolute([1, 0, 0])",
                "link(q) dof = q || [1, 0, 0], mimic_multiplier = 2 end",
                "revolute([0, 1, 0])",
            ),
            "E0472",
        ),
    ];
    for (text, code) in cases {
        let codes = refusal_codes(&text);
        assert!(codes.iter().any(|c| c == code), "{code}: {codes:?}\n{text}");
    }
}
