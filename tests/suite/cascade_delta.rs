//! The Delta seed's cascade control in closed loop (notes on the Delta seed, §6 and §5 R20,
//! R21, R23) on the Delta ISIR88 with the standard library's DC motors,
//! `examples/control/cascade_delta.lsd`: a PI current loop per motor with its pole at 2 b1, the
//! decoupler from the inverse dynamics, state feedback with integral action per decoupled axis;
//! the arms track their quintic references with every integrator that integrates states, and
//! reject the seed's input disturbance (a step at 0.1 s and a 10 Hz sinusoid from 0.5 s).

use crate::common::programs::run_example;
use crate::nonlinear_delta::{largest_error, settings};
use crate::states::refused;
use lsdc::integrators::INTEGRATORS;
use lsdc::prepare::{Integrator, Settings};
use lsdc::simulate::run::Simulation;

const EXAMPLE: &str = "control/cascade_delta";
/// The example's own settings and test signal, which the tests replace.
const SETTINGS: &str =
    "simulate duration = 1.5, output = 0.005, integrator = implicit, tolerance = 1e-8 end ;";
const SIGNAL: &str = "given A_in = 0 ;";

/// A run of the example with `replacements`, its `simulate` declaration replaced by `settings`.
fn cascade(replacements: &[(&str, &str)], settings: Settings) -> Simulation {
    run_example(EXAMPLE, SETTINGS, replacements, &settings)
}

/// The arms follow their quintic laws out (0.2 to 0.7 s) and back (1.0 to 1.5 s) within 1e-4
/// rad of the arm with every integrator that integrates states (measured with `implicit`:
/// 6.5e-5, the largest on the way back, 6.2e-5 on the way out); the seed reports errors of
/// order 1e-3 for its linear laws (R12).
#[test]
fn cascade_tracks_the_delta_references_with_every_integrator() {
    for entry in INTEGRATORS {
        let simulation = cascade(&[], settings(&entry.integrator, 1.5));
        if refused(&simulation, &entry.integrator) {
            continue;
        }
        let error = largest_error(&simulation, 0.0, 1.6);
        assert!(error < 1e-4, "{}: {error:e}", entry.name);
    }
}

/// The seed's R21 input disturbance at R23's amplitude A = 5: a 5 V step on every motor's
/// voltage at 0.1 s, a 10 Hz sinusoid of 5 V from 0.5 s. Measured: the step leaves at most
/// 9.9e-4 rad of the arm (the current loop's integral takes it up within milliseconds), the
/// sinusoid 2.1e-3 (at 62.8 rad/s, above the axes' poles at 40 s⁻¹: the current loop passes
/// 0.1 A of it to the arm): the seed's order, 1e-3. Without the current loop's integral action
/// (its gain 0: a proportional loop) the step stays as a bias of current that the axes' integral
/// must take up: 3.1e-2 rad, 31 times the PI's.
#[test]
fn cascade_rejects_the_seeds_input_disturbance() {
    let signal = "given A_in = 5 ;";
    let implicit = |duration| settings(&Integrator::Implicit, duration);
    let simulation = cascade(&[(SIGNAL, signal)], implicit(1.5));
    assert!(simulation.report.failure.is_none());
    let step = largest_error(&simulation, 0.1, 0.5);
    let sinusoid = largest_error(&simulation, 0.5, 1.6);
    assert!(
        step < 1.5e-3 && sinusoid < 3e-3,
        "step {step:e}, sinusoid {sinusoid:e}"
    );
    let proportional = cascade(
        &[
            (SIGNAL, signal),
            (
                "let current_integral_gain = -b1 * current_gain ;",
                "let current_integral_gain = 0 ;",
            ),
        ],
        implicit(0.5),
    );
    assert!(proportional.report.failure.is_none());
    let proportional_step = largest_error(&proportional, 0.1, 0.5);
    assert!(
        proportional_step > 10.0 * step,
        "proportional {proportional_step:e}, PI {step:e}"
    );
}
