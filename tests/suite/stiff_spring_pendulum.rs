//! The stiff spring pendulum (`examples/stiff_spring_pendulum.lsd`): a bob on a spring of
//! k / m = 1e8 /s², released on its slow manifold. Nothing in the motion excites the radial mode,
//! so Dormand–Prince's own stiffness estimate (along its last stages' difference) rarely sees
//! it, and the implicit integrator used to stay with the explicit method at its stability
//! limit or not depending on the tolerance and on the last digits of the start (1e-4, 1e-8 and
//! 1e-10 took dopri5's stability-bound steps, 1e-6 took a few hundred). It now decides on the
//! spectral radius of ∂f/∂y (`src/integrate/switching.rs`).

use crate::common::programs::{prepared, simulated};
use lsdc::prepare::{Integrator, Settings};
use lsdc::simulate::run::Simulation;

/// A run of the example, its text with `replacements`, with `integrator` at `tolerance`.
fn run_at(replacements: &[(&str, &str)], integrator: Integrator, tolerance: f64) -> Simulation {
    let mut pendulum = prepared("stiff_spring_pendulum", replacements);
    pendulum.settings = Settings {
        integrator,
        rtol: tolerance,
        atol: tolerance,
        output: 0.05,
        ..pendulum.settings
    };
    simulated(&pendulum)
}

/// The largest difference of the coordinates over the outputs.
fn coordinate_error(run: &Simulation, reference: &Simulation) -> f64 {
    assert_eq!(run.samples.len(), reference.samples.len());
    let mut largest = 0.0f64;
    for (sample, exact) in run.samples.iter().zip(&reference.samples) {
        assert!((sample.time - exact.time).abs() < 1e-12);
        for (a, b) in sample.coordinates.iter().zip(&exact.coordinates) {
            largest = largest.max((a - b).abs());
        }
    }
    largest
}

#[test]
fn the_implicit_integrator_reaches_dopri5s_accuracy_on_the_stiff_spring_pendulum_in_few_steps() {
    // Against Dormand–Prince at 1e-12 (stability holds its steps far below what that tolerance
    // needs: its error at 1e-10 is 1.5e-11), at every tolerance from 1e-4 to 1e-10: dopri5's
    // error there, and the loosest of the implicit integrator's tolerances 3, 1, 1/3, 1/10
    // times it that reaches that error. Measured: dopri5 takes 120,726 to 121,794 steps; the
    // implicit integrator reaches its error in 1,109 (at 3.3e-5, for dopri5's 1e-4), 248, 347,
    // 457, 791, 1,349 and 1,792 steps (at 3e-10, for dopri5's 1e-10, error 8.9e-12 against
    // 1.5e-11), switching after 23 explicit steps.
    let reference = run_at(&[], Integrator::DormandPrince, 1e-12);
    for tolerance in [1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10] {
        let explicit = run_at(&[], Integrator::DormandPrince, tolerance);
        let target = coordinate_error(&explicit, &reference);
        let reaching = [3.0, 1.0, 1.0 / 3.0, 0.1].into_iter().find_map(|factor| {
            let implicit = run_at(&[], Integrator::Implicit, factor * tolerance);
            let error = coordinate_error(&implicit, &reference);
            (error <= target).then_some((factor * tolerance, implicit, error))
        });
        let (reached_at, implicit, error) = reaching
            .unwrap_or_else(|| panic!("{tolerance:e}: dopri5's error {target:e} not reached"));
        let report = &implicit.report;
        eprintln!(
            "stiff spring pendulum, dopri5 at {tolerance:e}: {} steps, error {target:.1e}; implicit at {reached_at:.1e}: {} steps ({:?} stiff, {} evaluations), error {error:.1e}, energy balance {:.1e}",
            explicit.report.steps,
            report.steps,
            report.stiff_steps,
            report.function_evaluations,
            report.energy_balance.unwrap_or(f64::NAN),
        );
        assert!(report.steps <= 2_000, "{} steps", report.steps);
        assert!(explicit.report.steps > 100_000, "{}", explicit.report.steps);
        // The switch comes at the start (a check every 20 steps, three
        // in a row): the radial mode holds dopri5 from its first steps.
        assert!(report.stiff_steps.expect("counted") + 60 > report.steps);
        // An oracle that shares nothing with the reference: the spring's work (an applied
        // force, counted as non-conservative) balances the change of the energy.
        let balance = report.energy_balance.expect("balanced");
        assert!(balance < 10.0 * reached_at, "energy balance {balance:e}");
    }
}

#[test]
fn the_implicit_integrators_decision_does_not_hang_on_the_last_digits_of_the_start() {
    // A change of 1.5e-13 in the stretch moved the run at 1e-10 from 120,819 steps to 2,749
    // when the switch waited for Dormand–Prince's stage estimate to stay above 1 for 15 steps.
    let start = "stretch.r = l0 + g * bob.mass * cos(1) / k";
    let shifted = format!("{start} + 1.5e-13");
    for tolerance in [1e-4, 1e-6, 1e-8, 1e-10] {
        let steps = |replacements: &[(&str, &str)]| {
            let run = run_at(replacements, Integrator::Implicit, tolerance);
            (run.report.steps, run.report.stiff_steps.expect("counted"))
        };
        let (plain, shift) = (steps(&[]), steps(&[(start, &shifted)]));
        eprintln!("at {tolerance:e}: (steps, stiff) {plain:?}, shifted {shift:?}");
        // Both switch within their first steps (at most 120 explicit ones, where it took
        // 120,819 before) and take the rest with Radau IIA: 2,275 steps at equal tolerance at
        // 1e-10 (1,792 at dopri5's error, above). (They differ after the switch, 544 and 205 steps at 1e-4, 696 and
        // 547 at 1e-6: Radau IIA's steps on the radial mode that the first explicit steps left
        // at the tolerance's amplitude, not the decision.)
        for (steps, stiff) in [plain, shift] {
            assert!(
                steps - stiff <= 120 && steps <= 3_000,
                "{stiff} stiff of {steps}"
            );
        }
    }
}
