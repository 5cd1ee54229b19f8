//! The variational integrator on spherical and free joints, which it steps on their groups
//! (SO(3), SE(3)): a heavy top, a torque-free asymmetric body, a satellite with springs, and the
//! Delta robot (ball joints in its tree and closing its loops).
//! Oracles, none of them computed by the integrator: the energy of a conservative run stays
//! bounded (a symplectic method's error oscillates; a non-symplectic one drifts), the momenta
//! the symmetries conserve (Noether) stay at their start, the quaternions stay unit, the error
//! against a tight dopri5 run falls fourfold when the step is halved (second order), and the
//! loops stay closed.

use crate::common::programs::{constraints, prepared, simulated};
use lsdc::dynamics::joint::JointType;
use lsdc::dynamics::loops::Stabilisation;
use lsdc::prepare::{Integrator, Prepared, Settings};
use lsdc::simulate::run::Simulation;
use lsdc::simulate::system::MechanicalSystem;
use lsdc::simulate::variational;

/// What a conserved momentum may change by over a run, relative to its size: a step's Newton
/// iterations stop at corrections of 1e-15 to 1e-13 of the positions (round-off), which is
/// 1e-13 to 1e-11 of the momentum for steps that turn a body by 1e-2 rad; tens of thousands of
/// steps add them up. Methods that are not variational change the momenta at their truncation
/// error: over the free body's 100 s, dopri5 at a tolerance of 1e-8 by 1.5e-6, RK4 with the
/// same 5 ms steps by 1e-8.
const NEWTON_TOLERANCE: f64 = 1e-10;

/// An example with another integrator, duration, output interval and step (symplectic) or
/// tolerance (dopri5).
/// The symplectic method is for conservative mechanisms: the Delta's shorted-motor brakes
/// (examples/lib/delta_masses.lsd) are left out, so that its arms fall freely (for 0.3 s: before
/// they reach, at 0.40 s, the singular pose where the three elbows meet).
const DELTA_UNBRAKED: [(&str, &str); 3] = [
    ("apply shorted_motor(arm1) on arm1 ;", ""),
    ("apply shorted_motor(arm2) on arm2 ;", ""),
    ("apply shorted_motor(arm3) on arm3 ;", ""),
];

fn example(
    name: &str,
    integrator: Integrator,
    duration: f64,
    output: f64,
    step: Option<f64>,
) -> Prepared {
    let conservative: &[(&str, &str)] = match name {
        "delta_isir88" => &DELTA_UNBRAKED,
        _ => &[],
    };
    let mut p = prepared(name, conservative);
    p.settings = Settings {
        integrator,
        duration,
        output,
        step,
        rtol: 1e-12,
        atol: 1e-12,
        ..p.settings
    };
    p
}

fn symplectic(name: &str, duration: f64, output: f64, step: f64) -> Simulation {
    simulated(&example(
        name,
        Integrator::Symplectic,
        duration,
        output,
        Some(step),
    ))
}

/// The largest difference of a declared coordinate (not a rate) between two runs with the same
/// outputs.
fn largest_difference(a: &Simulation, b: &Simulation) -> f64 {
    assert_eq!(a.samples.len(), b.samples.len());
    let pairs = a.samples.iter().zip(&b.samples);
    pairs
        .flat_map(|(x, y)| x.coordinates.iter().zip(&y.coordinates))
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

/// The largest change of the momentum components `components` (of the fixed-frame angular
/// momentum about the origin, then the linear) over a run, relative to the momentum's size.
fn momentum_change(simulation: &Simulation, components: std::ops::Range<usize>) -> f64 {
    let start = simulation.samples[0].momentum;
    let size = components
        .clone()
        .map(|k| start[k].abs())
        .fold(0.0, f64::max);
    let samples = simulation.samples.iter();
    let change = samples
        .flat_map(|s| {
            components
                .clone()
                .map(move |k| (s.momentum[k] - start[k]).abs())
        })
        .fold(0.0, f64::max);
    // A momentum that starts at zero is compared as it is.
    change / if size > 0.0 { size } else { 1.0 }
}

/// The errors against a tight dopri5 run at steps 2h and h, and their ratio.
fn convergence(name: &str, duration: f64, output: f64, h: f64) -> (f64, f64, f64) {
    let reference = simulated(&example(
        name,
        Integrator::DormandPrince,
        duration,
        output,
        None,
    ));
    let coarse = largest_difference(&symplectic(name, duration, output, 2.0 * h), &reference);
    let fine = largest_difference(&symplectic(name, duration, output, h), &reference);
    (coarse, fine, coarse / fine)
}

#[test]
fn the_heavy_top_keeps_its_energy_bounded_and_its_vertical_momentum() {
    let short = symplectic("heavy_top", 20.0, 0.1, 4e-3);
    let long = symplectic("heavy_top", 200.0, 0.1, 4e-3);
    let (short_drift, long_drift) = (
        short.report.energy_drift.expect("conservative"),
        long.report.energy_drift.expect("conservative"),
    );
    assert!(long_drift < 1e-5, "energy error {long_drift:e}");
    assert!(
        long_drift < 2.0 * short_drift,
        "energy error grows: {short_drift:e} over 20 s, {long_drift:e} over 200 s"
    );
    // Gravity has no moment about the vertical through the fixed point: the vertical angular
    // momentum is conserved, by the discrete Noether theorem, to the tolerance of the Newton
    // iterations (see `NEWTON_TOLERANCE`).
    let vertical = momentum_change(&long, 2..3);
    assert!(
        vertical < NEWTON_TOLERANCE,
        "vertical angular momentum changed by {vertical:e}"
    );
}

#[test]
fn torque_free_bodies_keep_their_momenta_to_the_newton_tolerance_and_their_energy_bounded() {
    // Principal moments 1, 2, 3, spun about the intermediate axis: it flips over and back.
    // Steps of 5 ms, large for the flips: momentum is conserved whatever the step.
    for name in ["free_body", "satellite_springs"] {
        let short = symplectic(name, 10.0, 0.05, 5e-3);
        let long = symplectic(name, 100.0, 0.05, 5e-3);
        let angular = momentum_change(&long, 0..3);
        let linear = momentum_change(&long, 3..6);
        assert!(
            angular < NEWTON_TOLERANCE,
            "{name}: angular momentum changed by {angular:e}"
        );
        // The free body drifts 10 m away over the run, and the positions' corrections are
        // measured against 1 + |q|: ten times the tolerance, on a linear momentum 40 times
        // smaller than the angular one.
        assert!(
            linear < 10.0 * NEWTON_TOLERANCE,
            "{name}: linear momentum changed by {linear:e}"
        );
        if let (Some(short_drift), Some(long_drift)) =
            (short.report.energy_drift, long.report.energy_drift)
        {
            assert!(long_drift < 1e-4, "{name}: energy error {long_drift:e}");
            assert!(
                long_drift < 2.0 * short_drift,
                "{name}: energy error grows: {short_drift:e} over 10 s, {long_drift:e} over 100 s"
            );
        }
    }
}

#[test]
fn the_quaternions_stay_unit_along_a_run() {
    let p = example("free_body", Integrator::Symplectic, 20.0, 0.01, Some(1e-2));
    let model = &p.model;
    let (q0, v0) = model
        .state_from_declared(&p.coordinates, &p.rates)
        .expect("a state");
    let mut y0 = q0;
    y0.extend_from_slice(&v0);
    let reference = p.coordinates.clone();
    let mut system = MechanicalSystem::new(model, reference, Stabilisation::Integrator);
    let free = model
        .joints
        .iter()
        .find(|j| matches!(j.kind, JointType::Free { .. }))
        .expect("a free joint");
    let quaternion = free.q_offset + 3..free.q_offset + 7;
    let mut worst: f64 = 0.0;
    let outputs: Vec<f64> = (0..=2000).map(|k| k as f64 * 0.01).collect();
    let mut observer = |_: &mut MechanicalSystem<'_>, _t: f64, y: &[f64]| {
        let norm = y[quaternion.clone()]
            .iter()
            .map(|x| x * x)
            .sum::<f64>()
            .sqrt();
        worst = worst.max((norm - 1.0).abs());
        Ok(())
    };
    let steps = variational::FixedStep {
        step: 1e-2,
        rtol: 1e-6,
        atol: 1e-9,
        max_steps: usize::MAX,
        interrupt: None,
    };
    let (end, stats) =
        variational::integrate(&mut system, 0.0, &y0, 20.0, steps, &outputs, &mut observer)
            .expect("integrates");
    assert_eq!(stats.steps, 2000);
    let norm = end[quaternion].iter().map(|x| x * x).sum::<f64>().sqrt();
    worst = worst.max((norm - 1.0).abs());
    assert!(worst < 1e-14, "a quaternion's norm left 1 by {worst:e}");
}

#[test]
fn the_heavy_top_converges_at_second_order() {
    let (coarse, fine, ratio) = convergence("heavy_top", 1.0, 0.1, 1e-3);
    assert!(
        fine < 1e-4 && (3.6..4.4).contains(&ratio),
        "errors {coarse:e} at h = 2e-3, {fine:e} at h = 1e-3"
    );
}

#[test]
fn the_delta_robot_runs_with_its_loops_closed_and_converges_at_second_order() {
    let run = symplectic("delta_isir88", 0.3, 0.01, 1e-3);
    // Every step's end is measured (not projected): the loops close within Newton's tolerance.
    let residual = constraints(&run).position_residual;
    assert!(residual < 1e-10, "loops open by {residual:e}");
    let drift = run.report.energy_drift.expect("conservative");
    assert!(drift < 1e-5, "energy error {drift:e}");
    let (coarse, fine, ratio) = convergence("delta_isir88", 0.3, 0.01, 1e-3);
    assert!(
        fine < 1e-5 && (3.6..4.4).contains(&ratio),
        "errors {coarse:e} at h = 2e-3, {fine:e} at h = 1e-3"
    );
}
