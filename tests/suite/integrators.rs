//! The ODE integrators against problems with known solutions, their costs on a stiff problem,
//! their dense output, their orders of convergence and their failure reports.

use std::f64::consts::PI;

use crate::common::max_difference;

use lsdc::integrate::{
    integrate, CallbackError, Failure, IntegrationError, Method, OdeSystem, Settings, Stats,
};

/// A system from a closure, for problems that cannot fail.
struct Ode<F> {
    dimension: usize,
    f: F,
}

impl<F: FnMut(f64, &[f64], &mut [f64])> OdeSystem for Ode<F> {
    fn dimension(&self) -> usize {
        self.dimension
    }

    fn rhs(&mut self, t: f64, y: &[f64], dydt: &mut [f64]) -> Result<(), CallbackError> {
        (self.f)(t, y, dydt);
        Ok(())
    }
}

fn ode<F: FnMut(f64, &[f64], &mut [f64])>(dimension: usize, f: F) -> Ode<F> {
    Ode { dimension, f }
}

fn tolerances(rtol: f64, atol: f64) -> Settings {
    Settings {
        rtol,
        atol,
        ..Settings::default()
    }
}

/// The (t, y) pairs handed to the observer.
type Observed = Vec<(f64, Vec<f64>)>;

/// What `solve` returns: the end state, the work done and the outputs, or why the integration
/// stopped and the outputs before it.
type Solved = Result<(Vec<f64>, Stats, Observed), Box<(IntegrationError, Observed)>>;

/// Integrates and collects the observed (t, y) pairs.
fn solve(
    method: &Method,
    system: &mut dyn OdeSystem,
    y0: &[f64],
    span: (f64, f64),
    outputs: &[f64],
    settings: &Settings,
) -> Solved {
    let mut observed = Vec::new();
    let mut observer = |t: f64, y: &[f64]| {
        observed.push((t, y.to_vec()));
        Ok(())
    };
    match integrate(
        method,
        system,
        span.0,
        y0,
        span.1,
        outputs,
        settings,
        &mut observer,
    ) {
        Ok((y, stats)) => Ok((y, stats, observed)),
        Err(error) => Err(Box::new((error, observed))),
    }
}

fn linspace(start: f64, end: f64, count: usize) -> Vec<f64> {
    (0..count)
        .map(|i| start + (end - start) * i as f64 / (count - 1) as f64)
        .collect()
}

fn oscillator() -> Ode<impl FnMut(f64, &[f64], &mut [f64])> {
    ode(2, |_, y, dydt| {
        dydt[0] = y[1];
        dydt[1] = -y[0];
    })
}

/// Harmonic oscillator x'' = −x from (1, 0): after 100 periods x = cos t returns to (1, 0).
fn oscillator_after_100_periods(method: &Method, settings: &Settings) -> (f64, f64, Stats) {
    let t_end = 200.0 * PI;
    let (y, stats, _) = solve(
        method,
        &mut oscillator(),
        &[1.0, 0.0],
        (0.0, t_end),
        &[],
        settings,
    )
    .unwrap();
    let amplitude_error = (y[0].hypot(y[1]) - 1.0).abs();
    let phase_error = (-y[1]).atan2(y[0]).abs();
    (amplitude_error, phase_error, stats)
}

#[test]
fn dormand_prince_keeps_phase_and_amplitude_of_an_oscillator_over_100_periods() {
    let (amplitude, phase, stats) =
        oscillator_after_100_periods(&Method::DormandPrince, &tolerances(1e-13, 1e-13));
    eprintln!("oscillator DOPRI5 1e-13: amplitude {amplitude:.1e} phase {phase:.1e} {stats:?}");
    assert!(
        amplitude < 1e-10 && phase < 1e-10,
        "amplitude error {amplitude:e}, phase error {phase:e}"
    );
}

#[test]
fn rk4_and_rosenbrock_follow_an_oscillator_over_100_periods() {
    let (amplitude, phase, stats) =
        oscillator_after_100_periods(&Method::Rk4 { step: 0.01 }, &Settings::default());
    eprintln!("oscillator RK4 h=0.01: amplitude {amplitude:.1e} phase {phase:.1e} {stats:?}");
    assert!(
        amplitude < 1e-7 && phase < 1e-7,
        "amplitude error {amplitude:e}, phase error {phase:e}"
    );
    let (amplitude, phase, stats) =
        oscillator_after_100_periods(&Method::Rosenbrock, &tolerances(1e-6, 1e-9));
    eprintln!("oscillator Rosenbrock 1e-6: amplitude {amplitude:.1e} phase {phase:.1e} {stats:?}");
    // L-stable methods damp oscillations: the amplitude suffers more than the phase.
    assert!(
        amplitude < 1e-3 && phase < 1e-5,
        "amplitude error {amplitude:e}, phase error {phase:e}"
    );
}

#[test]
fn every_method_follows_exponential_decay() {
    let times = linspace(0.0, 10.0, 21);
    let cases = [
        (Method::Rk4 { step: 0.05 }, 1e-7),
        (Method::DormandPrince, 1e-9),
        (Method::Dop853, 1e-9),
        (Method::Rosenbrock, 1e-7),
    ];
    for (method, bound) in cases {
        let mut decay = ode(1, |_, y, dydt| dydt[0] = -0.7 * y[0]);
        let (y, stats, observed) = solve(
            &method,
            &mut decay,
            &[2.0],
            (0.0, 10.0),
            &times,
            &tolerances(1e-9, 1e-12),
        )
        .unwrap();
        let worst = observed
            .iter()
            .map(|(t, y)| (y[0] - 2.0 * (-0.7 * t).exp()).abs())
            .fold(0.0, f64::max);
        eprintln!("decay {method:?}: max error {worst:.1e} {stats:?}");
        assert_eq!(observed.len(), times.len());
        assert!(worst < bound, "{method:?}: error {worst:e}");
        assert_eq!(
            y,
            observed.last().unwrap().1,
            "the last output is the final state"
        );
    }
}

#[test]
fn dormand_prince_reaches_relative_accuracy_1e_12_on_a_blowing_up_solution() {
    // y' = y² from 1 is 1 / (1 − t), which grows tenfold by t = 0.9.
    let mut square = ode(1, |_, y, dydt| dydt[0] = y[0] * y[0]);
    let times = linspace(0.0, 0.9, 10);
    let (_, stats, observed) = solve(
        &Method::DormandPrince,
        &mut square,
        &[1.0],
        (0.0, 0.9),
        &times,
        &tolerances(1e-14, 1e-14),
    )
    .unwrap();
    let worst = observed
        .iter()
        .map(|(t, y)| (y[0] * (1.0 - t) - 1.0).abs())
        .fold(0.0, f64::max);
    eprintln!("y' = y^2 DOPRI5 1e-14: max relative error {worst:.1e} {stats:?}");
    assert!(worst < 1e-12, "relative error {worst:e}");
}

#[test]
fn rosenbrock_follows_a_blowing_up_solution() {
    // y' = y³ from 1 is 1 / √(1 − 2t). (Not y' = y²: RODAS3 with an exact Jacobian solves that
    // Riccati equation exactly, which would test nothing.)
    let mut cube = ode(1, |_, y, dydt| dydt[0] = y[0].powi(3));
    let times = linspace(0.0, 0.45, 10);
    let (_, stats, observed) = solve(
        &Method::Rosenbrock,
        &mut cube,
        &[1.0],
        (0.0, 0.45),
        &times,
        &tolerances(1e-9, 1e-9),
    )
    .unwrap();
    let worst = observed
        .iter()
        .map(|(t, y)| (y[0] * (1.0 - 2.0 * t).sqrt() - 1.0).abs())
        .fold(0.0, f64::max);
    eprintln!("y' = y^3 Rosenbrock 1e-9: max relative error {worst:.1e} {stats:?}");
    assert!(worst < 1e-7, "relative error {worst:e}");
}

/// The Kepler orbit of eccentricity e, semi-major axis 1 and period 2π at time t, from Kepler's
/// equation, starting at the pericentre: (x, y, vx, vy).
fn kepler_orbit(e: f64, t: f64) -> [f64; 4] {
    let mean_anomaly = t;
    let mut anomaly = mean_anomaly;
    for _ in 0..50 {
        anomaly -= (anomaly - e * anomaly.sin() - mean_anomaly) / (1.0 - e * anomaly.cos());
    }
    let (sin, cos) = anomaly.sin_cos();
    let root = (1.0 - e * e).sqrt();
    let rate = 1.0 / (1.0 - e * cos);
    [cos - e, root * sin, -sin * rate, root * cos * rate]
}

fn kepler() -> Ode<impl FnMut(f64, &[f64], &mut [f64])> {
    ode(4, |_, y, dydt| {
        let r3 = y[0].hypot(y[1]).powi(3);
        dydt[0] = y[2];
        dydt[1] = y[3];
        dydt[2] = -y[0] / r3;
        dydt[3] = -y[1] / r3;
    })
}

fn kepler_energy(y: &[f64]) -> f64 {
    0.5 * (y[2] * y[2] + y[3] * y[3]) - 1.0 / y[0].hypot(y[1])
}

#[test]
fn dormand_prince_keeps_energy_and_period_of_a_kepler_orbit() {
    let e = 0.5;
    let y0 = kepler_orbit(e, 0.0);
    let periods = 10.0;
    let times = linspace(0.0, periods * 2.0 * PI, 401);
    let (y, stats, observed) = solve(
        &Method::DormandPrince,
        &mut kepler(),
        &y0,
        (0.0, times[400]),
        &times,
        &tolerances(1e-12, 1e-12),
    )
    .unwrap();
    let energy_drift = observed
        .iter()
        .map(|(_, y)| (kepler_energy(y) + 0.5).abs())
        .fold(0.0, f64::max);
    let path_error = observed
        .iter()
        .map(|(t, y)| max_difference(y, &kepler_orbit(e, *t)))
        .fold(0.0, f64::max);
    let period_error = max_difference(&y, &y0);
    eprintln!(
        "Kepler DOPRI5 1e-12: energy {energy_drift:.1e}, path {path_error:.1e}, return {period_error:.1e} {stats:?}"
    );
    assert!(energy_drift < 1e-9, "energy drift {energy_drift:e}");
    assert!(
        period_error < 1e-8,
        "after {periods} periods the state is {y:?}"
    );
    assert!(path_error < 1e-8, "path error {path_error:e}");
}

/// The largest distance from the analytic orbit over 10 periods of a Kepler orbit of
/// eccentricity 0.5, and the work, with `method` at tolerance `tolerance`.
fn kepler_path_error(method: &Method, tolerance: f64) -> (f64, Stats) {
    let e = 0.5;
    let times = linspace(0.0, 20.0 * PI, 401);
    let (_, stats, observed) = solve(
        method,
        &mut kepler(),
        &kepler_orbit(e, 0.0),
        (0.0, times[400]),
        &times,
        &tolerances(tolerance, tolerance),
    )
    .unwrap();
    let path_error = observed
        .iter()
        .map(|(t, y)| max_difference(y, &kepler_orbit(e, *t)))
        .fold(0.0, f64::max);
    (path_error, stats)
}

#[test]
fn dop853_follows_a_kepler_orbit_with_fewer_evaluations_than_dormand_prince_at_tight_tolerance() {
    let (dop853_error, dop853) = kepler_path_error(&Method::Dop853, 1e-12);
    let (dopri5_error, dopri5) = kepler_path_error(&Method::DormandPrince, 1e-12);
    eprintln!(
        "Kepler 1e-12: DOP853 {dop853_error:.1e} {dop853:?}; DOPRI5 {dopri5_error:.1e} {dopri5:?}"
    );
    assert!(dop853_error < 1e-8, "path error {dop853_error:e}");
    assert!(
        dop853.rhs_evaluations < dopri5.rhs_evaluations / 2,
        "DOP853 {dop853:?}, DOPRI5 {dopri5:?}"
    );
}

#[test]
fn rosenbrock_keeps_a_kepler_orbit_at_moderate_tolerance() {
    let e = 0.5;
    let y0 = kepler_orbit(e, 0.0);
    let (y, stats, _) = solve(
        &Method::Rosenbrock,
        &mut kepler(),
        &y0,
        (0.0, 2.0 * PI),
        &[],
        &tolerances(1e-9, 1e-9),
    )
    .unwrap();
    let period_error = max_difference(&y, &y0);
    let energy_error = (kepler_energy(&y) + 0.5).abs();
    eprintln!(
        "Kepler Rosenbrock 1e-9: return {period_error:.1e}, energy {energy_error:.1e} {stats:?}"
    );
    assert!(
        period_error < 1e-5 && energy_error < 1e-6,
        "return error {period_error:e}, energy error {energy_error:e}"
    );
}

/// y' = A y with A symmetric, eigenvalues −1 and −1e6 (eigenvectors (1, 1) and (1, −1)), from (1, 0).
fn stiff_linear() -> Ode<impl FnMut(f64, &[f64], &mut [f64])> {
    let (slow, fast) = (-1.0, -1.0e6);
    let (diagonal, coupling) = (0.5 * (slow + fast), 0.5 * (slow - fast));
    ode(2, move |_, y, dydt| {
        dydt[0] = diagonal * y[0] + coupling * y[1];
        dydt[1] = coupling * y[0] + diagonal * y[1];
    })
}

fn stiff_linear_exact(t: f64) -> [f64; 2] {
    let (slow, fast) = ((-t).exp(), (-1.0e6 * t).exp());
    [0.5 * (slow + fast), 0.5 * (slow - fast)]
}

#[test]
fn rosenbrock_solves_a_stiff_system_with_a_hundredth_of_the_work_of_dormand_prince() {
    let t_end = 0.2;
    let settings = tolerances(1e-6, 1e-9);
    let exact = stiff_linear_exact(t_end);
    let (implicit, implicit_stats, _) = solve(
        &Method::Rosenbrock,
        &mut stiff_linear(),
        &[1.0, 0.0],
        (0.0, t_end),
        &[],
        &settings,
    )
    .unwrap();
    let (explicit, explicit_stats, _) = solve(
        &Method::DormandPrince,
        &mut stiff_linear(),
        &[1.0, 0.0],
        (0.0, t_end),
        &[],
        &settings,
    )
    .unwrap();
    eprintln!(
        "stiff Rosenbrock: error {:.1e} {implicit_stats:?}",
        max_difference(&implicit, &exact)
    );
    eprintln!(
        "stiff DOPRI5: error {:.1e} {explicit_stats:?}",
        max_difference(&explicit, &exact)
    );
    assert!(max_difference(&implicit, &exact) < 1e-6);
    assert!(max_difference(&explicit, &exact) < 1e-6);
    assert!(max_difference(&implicit, &explicit) < 1e-6);
    let ratio = implicit_stats.rhs_evaluations as f64 / explicit_stats.rhs_evaluations as f64;
    assert!(
        ratio < 0.01,
        "Rosenbrock used {ratio} of Dormand–Prince's evaluations"
    );
    assert!(implicit_stats.jacobian_evaluations <= implicit_stats.steps + 1);
    assert_eq!(
        explicit_stats.jacobian_evaluations + explicit_stats.lu_decompositions,
        0
    );
}

fn van_der_pol(mu: f64) -> Ode<impl FnMut(f64, &[f64], &mut [f64])> {
    ode(2, move |_, y, dydt| {
        dydt[0] = y[1];
        dydt[1] = mu * (1.0 - y[0] * y[0]) * y[1] - y[0];
    })
}

#[test]
fn rosenbrock_crosses_a_relaxation_jump_of_van_der_pol_with_mu_1000() {
    // Slow drift from x = 2 to x = 1, a jump to x ≈ −2 near t ≈ 807, then slow drift again.
    let times = linspace(0.0, 1000.0, 101);
    let run = |rtol: f64| {
        solve(
            &Method::Rosenbrock,
            &mut van_der_pol(1000.0),
            &[2.0, 0.0],
            (0.0, 1000.0),
            &times,
            &tolerances(rtol, rtol),
        )
        .unwrap()
    };
    let (coarse, stats, observed) = run(1e-6);
    let (fine, fine_stats, _) = run(1e-9);
    eprintln!(
        "Van der Pol mu=1000 Rosenbrock 1e-6: x(1000) = {:.8} {stats:?}",
        coarse[0]
    );
    eprintln!(
        "Van der Pol mu=1000 Rosenbrock 1e-9: x(1000) = {:.8} {fine_stats:?}",
        fine[0]
    );
    assert!(
        observed.iter().all(|(_, y)| y[0].abs() < 2.1),
        "x leaves the limit cycle"
    );
    assert!(
        observed[50].1[0] > 1.0 && coarse[0] < -1.0,
        "no jump between t = 500 and t = 1000"
    );
    assert!(
        (coarse[0] - fine[0]).abs() < 1e-4,
        "x(1000) is {} at 1e-6 and {} at 1e-9",
        coarse[0],
        fine[0]
    );
    assert!(stats.steps < 2000, "{stats:?}");
}

#[test]
fn dense_output_agrees_with_the_solution_between_steps() {
    // x = sin t, sampled far more densely than the steps (at least four outputs a step).
    let times = linspace(0.0, 20.0, 4001);
    let cases = [
        (Method::DormandPrince, tolerances(1e-10, 1e-10), 1e-8),
        (Method::Dop853, tolerances(1e-10, 1e-10), 1e-8),
        (Method::Rosenbrock, tolerances(1e-5, 1e-5), 1e-3),
        (Method::Rk4 { step: 0.05 }, Settings::default(), 1e-6),
    ];
    for (method, settings, bound) in cases {
        let (_, stats, observed) = solve(
            &method,
            &mut oscillator(),
            &[0.0, 1.0],
            (0.0, 20.0),
            &times,
            &settings,
        )
        .unwrap();
        let (_, bare_stats, _) = solve(
            &method,
            &mut oscillator(),
            &[0.0, 1.0],
            (0.0, 20.0),
            &[],
            &settings,
        )
        .unwrap();
        let worst = observed
            .iter()
            .map(|(t, y)| (y[0] - t.sin()).abs().max((y[1] - t.cos()).abs()))
            .fold(0.0, f64::max);
        eprintln!(
            "dense {method:?}: max error {worst:.1e} over {} outputs, {stats:?}",
            observed.len()
        );
        assert_eq!(observed.iter().map(|(t, _)| *t).collect::<Vec<_>>(), times);
        assert!(worst < bound, "{method:?}: dense output error {worst:e}");
        assert_eq!(
            stats.steps, bare_stats.steps,
            "{method:?}: outputs changed the steps"
        );
        assert!(stats.steps < times.len() / 4, "{method:?}: {stats:?}");
    }
}

#[test]
fn rk4_outputs_on_the_grid_are_the_step_states() {
    let times = linspace(0.0, 1.0, 11);
    let mut decay = ode(1, |_, y, dydt| dydt[0] = -y[0]);
    let (y, stats, observed) = solve(
        &Method::Rk4 { step: 0.1 },
        &mut decay,
        &[1.0],
        (0.0, 1.0),
        &times,
        &Settings::default(),
    )
    .unwrap();
    // One RK4 step of y' = −y multiplies by this polynomial of h = 0.1.
    let factor: f64 = 1.0 - 0.1 + 0.01 / 2.0 - 0.001 / 6.0 + 0.0001 / 24.0;
    for (k, (_, value)) in observed.iter().enumerate() {
        assert!(
            (value[0] - factor.powi(k as i32)).abs() < 1e-15,
            "output {k} is {value:?}"
        );
    }
    assert_eq!(y, observed[10].1);
    assert_eq!(stats.steps, 10);
    // Four stages per step, and the slope at the last step's end for its error estimate (every
    // other step's end slope is the next step's first stage).
    assert_eq!(
        stats.rhs_evaluations, 41,
        "outputs on the grid need no interpolation"
    );
}

/// A step longer than the run is one shortened step to the end, however much longer: with a
/// step over about 10^9 times the duration the run took no step and gave its start as its end.
#[test]
fn rk4_with_a_step_far_longer_than_the_run_takes_one_step_to_its_end() {
    for step in [2.0, 1e8, 1e9, 1e12, f64::MAX] {
        let mut decay = ode(1, |_, y, dydt| dydt[0] = -y[0]);
        let (y, stats, observed) = solve(
            &Method::Rk4 { step },
            &mut decay,
            &[1.0],
            (0.0, 1.0),
            &[0.0, 1.0],
            &Settings::default(),
        )
        .unwrap();
        // One RK4 step of y' = −y over h = 1.
        let one_step = 1.0 - 1.0 + 1.0 / 2.0 - 1.0 / 6.0 + 1.0 / 24.0;
        assert_eq!(stats.steps, 1, "step {step:e}");
        assert!((y[0] - one_step).abs() < 1e-15, "step {step:e}: {y:?}");
        assert_eq!(observed.last().map(|o| o.0), Some(1.0), "step {step:e}");
    }
}

#[test]
fn rk4_error_estimate_measures_the_local_error_of_its_steps() {
    // y' = λy, one step from y = 1, z = hλ: the order-4 solution is 1 + z + z²/2 + z³/6 + z⁴/24,
    // the embedded order-3 one (weights 1/6, 1/3, 1/3, 0, 1/6 on k1..k4 and the end slope k5)
    // is 1 + z + z²/2 + z³/6 + z⁴/36 + z⁵/144, so the estimate is |z⁴/72 − z⁵/144|: the
    // order-3 solution's local error, falling 16-fold when h is halved.
    let estimate = |h: f64, lambda: f64| {
        let mut growth = ode(1, move |_, y, dydt| dydt[0] = lambda * y[0]);
        let settings = tolerances(0.0, 1e-6);
        let method = Method::Rk4 { step: h };
        let (_, stats, _) =
            solve(&method, &mut growth, &[1.0], (0.0, h), &[0.0], &settings).expect("one step");
        stats
            .largest_step_error
            .expect("RK4 measures its steps")
            .norm
            * 1e-6
    };
    for h in [0.1, 0.05, 0.025] {
        let z: f64 = -h;
        let expected = (z.powi(4) / 72.0 - z.powi(5) / 144.0).abs();
        let measured = estimate(h, -1.0);
        assert!(
            (measured / expected - 1.0).abs() < 1e-8,
            "h = {h}: estimate {measured:e}, expected {expected:e}"
        );
    }
    let ratio = estimate(0.1, -1.0) / estimate(0.05, -1.0);
    assert!(
        (ratio - 16.0).abs() < 1.0,
        "halving h divides the estimate by {ratio}"
    );
    // Near the stability limit (hλ = −2.5, the limit is −2.79) the step is far too long for 1e-6.
    assert!(estimate(2.5, -1.0) > 1e-2);
}

/// Settings that hold an adaptive method to the step `h`: tolerances it always meets.
fn fixed_step(h: f64) -> Settings {
    Settings {
        rtol: 1e6,
        atol: 1e6,
        initial_step: Some(h),
        max_step: h,
        ..Settings::default()
    }
}

/// Error of x(2) for x'' = −x with a fixed step `h` (adaptive methods forced to it by a tolerance
/// they always meet).
fn fixed_step_error(method: &Method, h: f64) -> f64 {
    let settings = fixed_step(h);
    let (y, _, _) = solve(
        method,
        &mut oscillator(),
        &[1.0, 0.0],
        (0.0, 2.0),
        &[],
        &settings,
    )
    .unwrap();
    max_difference(&y, &[2.0f64.cos(), -(2.0f64).sin()])
}

#[test]
fn halving_the_step_divides_the_error_by_two_to_the_order() {
    for (method, h, order) in [
        (Method::Rk4 { step: 0.1 }, 0.1, 4),
        (Method::DormandPrince, 0.2, 5),
        (Method::Dop853, 0.5, 8),
        (Method::Rosenbrock, 0.1, 3),
        (Method::Rodas4, 0.1, 4),
        (Method::Radau5, 0.2, 5),
    ] {
        let method_with = |h: f64| match method {
            Method::Rk4 { .. } => Method::Rk4 { step: h },
            _ => method.clone(),
        };
        let coarse = fixed_step_error(&method_with(h), h);
        let fine = fixed_step_error(&method_with(h / 2.0), h / 2.0);
        let ratio = coarse / fine;
        let expected = 2f64.powi(order);
        eprintln!("order {method:?}: errors {coarse:.2e} {fine:.2e}, ratio {ratio:.2} (expected {expected})");
        assert!(
            (ratio / expected - 1.0).abs() < 0.15,
            "{method:?}: ratio {ratio}"
        );
    }
}

/// x' = 1, whose right-hand side turns into NaN from t = 0.5 on (or reports an error).
struct BreaksAtHalf {
    with_error: bool,
}

impl OdeSystem for BreaksAtHalf {
    fn dimension(&self) -> usize {
        1
    }

    fn rhs(&mut self, t: f64, _: &[f64], dydt: &mut [f64]) -> Result<(), CallbackError> {
        match (t >= 0.5, self.with_error) {
            (true, true) => Err("singular mass matrix".into()),
            (true, false) => {
                dydt[0] = f64::NAN;
                Ok(())
            }
            (false, _) => {
                dydt[0] = 1.0;
                Ok(())
            }
        }
    }
}

fn all_methods() -> [Method; 4] {
    [
        Method::Rk4 { step: 0.01 },
        Method::DormandPrince,
        Method::Dop853,
        Method::Rosenbrock,
    ]
}

#[test]
fn a_nan_derivative_stops_at_its_time_after_the_earlier_outputs() {
    let times = [0.0, 0.1, 0.2, 0.3, 0.4, 0.6, 0.8];
    for method in all_methods() {
        let mut system = BreaksAtHalf { with_error: false };
        let (error, observed) = *solve(
            &method,
            &mut system,
            &[0.0],
            (0.0, 1.0),
            &times,
            &Settings::default(),
        )
        .unwrap_err();
        eprintln!(
            "NaN at 0.5 {method:?}: stopped at {} {:?}",
            error.time, error.stats
        );
        assert_eq!(error.failure, Failure::NotFinite, "{method:?}");
        assert!(
            (error.time - 0.5).abs() < 0.011,
            "{method:?} stopped at {}",
            error.time
        );
        let delivered: Vec<f64> = observed.iter().map(|(t, _)| *t).collect();
        assert_eq!(delivered, [0.0, 0.1, 0.2, 0.3, 0.4], "{method:?}");
        assert!(
            observed.iter().all(|(t, y)| (y[0] - t).abs() < 1e-9),
            "{method:?}: {observed:?}"
        );
    }
}

#[test]
fn an_error_from_the_system_stops_with_its_message() {
    for method in all_methods() {
        let mut system = BreaksAtHalf { with_error: true };
        let settings = Settings {
            max_step: 0.1,
            ..Settings::default()
        };
        let (error, observed) = *solve(
            &method,
            &mut system,
            &[0.0],
            (0.0, 1.0),
            &[0.0, 0.25],
            &settings,
        )
        .unwrap_err();
        assert_eq!(
            error.failure,
            Failure::System("singular mass matrix".to_string()),
            "{method:?}"
        );
        // The time of the evaluation that failed: a stage of a step that reached past 0.5.
        assert!(
            (0.5..=1.0).contains(&error.time),
            "{method:?} stopped at {}",
            error.time
        );
        assert_eq!(observed.len(), 2, "{method:?}");
        assert!(error.stats.rhs_evaluations > 0);
    }
}

#[test]
fn an_error_from_the_observer_stops_the_integration() {
    for method in all_methods() {
        let mut observer = |t: f64, _: &[f64]| {
            if t > 0.3 {
                Err("enough".into())
            } else {
                Ok(())
            }
        };
        let times = [0.1, 0.2, 0.4, 0.5];
        let result = integrate(
            &method,
            &mut oscillator(),
            0.0,
            &[1.0, 0.0],
            1.0,
            &times,
            &Settings::default(),
            &mut observer,
        );
        let error = result.unwrap_err();
        assert_eq!(
            (error.time, error.failure),
            (0.4, Failure::Observer("enough".to_string())),
            "{method:?}"
        );
    }
}

#[test]
fn a_solution_that_blows_up_ends_in_a_failure_near_the_singularity() {
    // y' = y³ from 1 is infinite at t = 0.5.
    for method in [Method::DormandPrince, Method::Rosenbrock] {
        let mut cube = ode(1, |_, y, dydt| dydt[0] = y[0].powi(3));
        let (error, _) = *solve(
            &method,
            &mut cube,
            &[1.0],
            (0.0, 1.0),
            &[],
            &Settings::default(),
        )
        .unwrap_err();
        eprintln!("blow-up {method:?}: {error}, {:?}", error.stats);
        assert!(
            matches!(
                error.failure,
                Failure::StepUnderflow { .. } | Failure::NotFinite
            ),
            "{method:?}: {error}"
        );
        assert!((error.time - 0.5).abs() < 1e-4, "{method:?}: {error}");
    }
}

#[test]
fn limits_on_steps_are_enforced() {
    let settings = Settings {
        max_steps: 10,
        ..Settings::default()
    };
    for method in all_methods() {
        let (error, _) = *solve(
            &method,
            &mut oscillator(),
            &[1.0, 0.0],
            (0.0, 100.0),
            &[],
            &settings,
        )
        .unwrap_err();
        assert_eq!(error.failure, Failure::TooManySteps, "{method:?}");
        assert_eq!(error.stats.steps + error.stats.rejected, 10, "{method:?}");
    }
    let settings = Settings {
        min_step: 0.1,
        ..tolerances(1e-12, 1e-12)
    };
    for method in [Method::DormandPrince, Method::Rosenbrock] {
        let (error, _) = *solve(
            &method,
            &mut oscillator(),
            &[1.0, 0.0],
            (0.0, 10.0),
            &[],
            &settings,
        )
        .unwrap_err();
        assert!(
            matches!(error.failure, Failure::StepUnderflow { step } if step < 0.1),
            "{method:?}: {error}"
        );
    }
}

#[test]
fn inconsistent_input_is_reported_not_panicked_on() {
    let settings = Settings::default();
    let reject =
        |method: &Method, y0: &[f64], span: (f64, f64), outputs: &[f64], settings: &Settings| {
            let (error, observed) =
                *solve(method, &mut oscillator(), y0, span, outputs, settings).unwrap_err();
            assert!(matches!(error.failure, Failure::InvalidInput(_)), "{error}");
            assert!(observed.is_empty());
        };
    reject(&Method::DormandPrince, &[1.0], (0.0, 1.0), &[], &settings);
    reject(
        &Method::DormandPrince,
        &[1.0, 0.0],
        (1.0, 0.0),
        &[],
        &settings,
    );
    reject(
        &Method::DormandPrince,
        &[1.0, 0.0],
        (0.0, 1.0),
        &[0.5, 0.2],
        &settings,
    );
    reject(
        &Method::Rosenbrock,
        &[1.0, 0.0],
        (0.0, 1.0),
        &[2.0],
        &settings,
    );
    reject(
        &Method::Rk4 { step: 0.0 },
        &[1.0, 0.0],
        (0.0, 1.0),
        &[],
        &settings,
    );
    reject(
        &Method::DormandPrince,
        &[1.0, 0.0],
        (0.0, 1.0),
        &[],
        &tolerances(-1.0, 0.0),
    );
    let (error, _) = *solve(
        &Method::Rosenbrock,
        &mut oscillator(),
        &[f64::NAN, 0.0],
        (0.0, 1.0),
        &[],
        &settings,
    )
    .unwrap_err();
    assert_eq!((error.time, error.failure), (0.0, Failure::NotFinite));
}

#[test]
fn an_empty_span_returns_the_initial_state_at_every_output() {
    for method in all_methods() {
        let (y, stats, observed) = solve(
            &method,
            &mut oscillator(),
            &[1.0, 2.0],
            (3.0, 3.0),
            &[3.0, 3.0],
            &Settings::default(),
        )
        .unwrap();
        assert_eq!(y, [1.0, 2.0]);
        assert_eq!(stats.steps, 0);
        assert_eq!(observed, [(3.0, vec![1.0, 2.0]), (3.0, vec![1.0, 2.0])]);
    }
}

/// The circular Kepler orbit y'' = −y / |y|³ from (1, 0) with velocity (0, 1): y = (cos t, sin t).
fn circular_orbit() -> Ode<impl FnMut(f64, &[f64], &mut [f64])> {
    ode(4, |_, y, dydt| {
        let cube = y[0].hypot(y[1]).powi(3);
        dydt[0] = y[2];
        dydt[1] = y[3];
        dydt[2] = -y[0] / cube;
        dydt[3] = -y[1] / cube;
    })
}

#[test]
fn the_rosenbrock_w_method_converges_at_order_three_on_a_closed_form_orbit() {
    // Fixed steps (tolerances that accept every step), on a nonlinear problem whose Jacobian
    // turns with the orbit, so that some steps use a Jacobian formed at an earlier point (which
    // a W-method's order allows). Error at t = 2 against the closed form, for h = 0.1, 0.05,
    // 0.025: the observed order over the four-fold refinement is 3 (2.8 measured: the steps whose
    // Jacobian is not fresh differ between the runs).
    let mut errors = Vec::new();
    for h in [0.1, 0.05, 0.025] {
        let settings = Settings {
            rtol: 1e6,
            atol: 1e6,
            initial_step: Some(h),
            max_step: h,
            ..Settings::default()
        };
        let (y, stats, _) = solve(
            &Method::Rosenbrock,
            &mut circular_orbit(),
            &[1.0, 0.0, 0.0, 1.0],
            (0.0, 2.0),
            &[],
            &settings,
        )
        .unwrap();
        let exact = [2f64.cos(), 2f64.sin(), -(2f64.sin()), 2f64.cos()];
        eprintln!(
            "W-method h = {h}: error {:.2e} {stats:?}",
            max_difference(&y, &exact)
        );
        assert!(
            stats.jacobian_evaluations < stats.steps,
            "h = {h}: {stats:?}"
        );
        errors.push(max_difference(&y, &exact));
    }
    let order = (errors[0] / errors[2]).log2() / 2.0;
    assert!(
        (2.6..3.4).contains(&order),
        "order {order}, errors {errors:?}"
    );
}

#[test]
fn the_switching_method_takes_the_stiff_system_with_the_w_method_and_few_steps() {
    // y' = A y with eigenvalues −1 and −1e6: Dormand–Prince is held at its stability boundary
    // (about 3.3e-6) over the whole span; the switching method starts with it, finds the steps
    // held there and goes on with the Rosenbrock-W method.
    let t_end = 0.2;
    let settings = tolerances(1e-6, 1e-9);
    let exact = stiff_linear_exact(t_end);
    let run = |method: &Method| {
        solve(
            method,
            &mut stiff_linear(),
            &[1.0, 0.0],
            (0.0, t_end),
            &[],
            &settings,
        )
        .unwrap()
    };
    let (automatic, stats, _) = run(&Method::Automatic);
    let (explicit, explicit_stats, _) = run(&Method::DormandPrince);
    eprintln!("stiff switching: {stats:?}; dopri5: {explicit_stats:?}");
    assert!(max_difference(&automatic, &exact) < 1e-6);
    assert!(max_difference(&explicit, &exact) < 1e-6);
    assert!(stats.method_switches >= 1 && stats.stiff_steps > 0);
    assert!(
        100 * stats.steps < explicit_stats.steps,
        "{} steps against dopri5's {}",
        stats.steps,
        explicit_stats.steps
    );
}

#[test]
fn the_switching_method_stays_explicit_on_a_problem_that_is_not_stiff() {
    let settings = tolerances(1e-10, 1e-12);
    let run = |method: &Method| {
        solve(
            method,
            &mut circular_orbit(),
            &[1.0, 0.0, 0.0, 1.0],
            (0.0, 20.0),
            &[],
            &settings,
        )
        .unwrap()
    };
    let (automatic, stats, _) = run(&Method::Automatic);
    let (explicit, explicit_stats, _) = run(&Method::DormandPrince);
    assert_eq!(stats.stiff_steps, 0);
    assert_eq!(stats.rhs_evaluations, explicit_stats.rhs_evaluations);
    assert_eq!(automatic, explicit);
}

/// Prothero and Robinson's problem y' = λ (y − sin t) + cos t, y(0) = 0, whose solution is
/// sin t whatever λ.
fn prothero_robinson(lambda: f64) -> Ode<impl FnMut(f64, &[f64], &mut [f64])> {
    ode(1, move |t, y, dydt| {
        dydt[0] = lambda * (y[0] - t.sin()) + t.cos()
    })
}

/// The error at t = 1 on Prothero and Robinson's problem with fixed steps `h` (tolerances that
/// accept every step).
fn prothero_robinson_error(method: &Method, lambda: f64, h: f64) -> (f64, Stats) {
    let settings = fixed_step(h);
    let (y, stats, _) = solve(
        method,
        &mut prothero_robinson(lambda),
        &[0.0],
        (0.0, 1.0),
        &[],
        &settings,
    )
    .unwrap();
    ((y[0] - 1f64.sin()).abs(), stats)
}

#[test]
fn rodas4_error_on_the_stiff_prothero_robinson_problem_shrinks_with_the_stiffness() {
    // Fixed steps (tolerances that accept every step) to t = 1, 100 to 1e5 times the stiff
    // mode's time scale. There a Rosenbrock method's error is not its classical order's
    // (Hairer and Wanner, VI.4 and VI.7, order reduction): RODAS4's is about 0.02 h / |λ|
    // (2.2e-9 for h = 0.1, λ = −1e6, the same in an independent transcription with the exact
    // ∂f/∂t), first order in h but a 1/|λ| smaller the stiffer the problem. A method whose stiff
    // limit were not this accurate (or a wrong ∂f/∂t term) would leave an error of order h.
    for lambda in [-1e4, -1e6] {
        for h in [0.1, 0.025] {
            let (error, stats) = prothero_robinson_error(&Method::Rodas4, lambda, h);
            let constant = error * lambda.abs() / h;
            eprintln!("RODAS4 on Prothero-Robinson, λ = {lambda:e}, h = {h}: error {error:.2e} = {constant:.3} h / |λ|");
            assert_eq!(stats.jacobian_evaluations, stats.steps, "h = {h}");
            assert!(constant < 0.03, "λ = {lambda:e}, h = {h}: error {error:e}");
        }
    }
}

#[test]
fn rodas4_and_radau5_meet_a_tight_reference_on_van_der_pol_with_mu_1000() {
    // x(t), x'(t) at t = 3000 (three relaxation cycles), RODAS4 and Radau IIA against RODAS4 at
    // a thousandth of the tolerance, each run also checked against the W-method's run at the tightest tolerance.
    let run = |method: &Method, rtol: f64| {
        solve(
            method,
            &mut van_der_pol(1000.0),
            &[2.0, 0.0],
            (0.0, 3000.0),
            &[],
            &tolerances(rtol, rtol),
        )
        .unwrap()
    };
    let (reference, _, _) = run(&Method::Rodas4, 1e-11);
    let (independent, _, _) = run(&Method::Rosenbrock, 1e-11);
    assert!(
        (reference[0] - independent[0]).abs() < 1e-6,
        "references {reference:?} and {independent:?}"
    );
    for method in [Method::Rodas4, Method::Radau5] {
        for rtol in [1e-6, 1e-8] {
            let (y, stats, _) = run(&method, rtol);
            let error = (y[0] - reference[0]).abs();
            eprintln!("{method:?} on Van der Pol, {rtol:e}: x error {error:.2e} {stats:?}");
            assert!(error < 1e3 * rtol, "{method:?}, {rtol:e}: error {error:e}");
        }
    }
}

#[test]
fn radau5_keeps_its_order_on_the_stiff_prothero_robinson_problem() {
    // Fixed steps to t = 1, 100 to 1e5 times the stiff mode's time scale. Radau IIA's stage
    // order 3 bounds its error there by about h⁴ / |λ| (Hairer and Wanner, VI.7), far below
    // RODAS4's 0.02 h / |λ|: halving h divides it by more than 8.
    for lambda in [-1e4, -1e6] {
        let error = |h: f64| prothero_robinson_error(&Method::Radau5, lambda, h).0;
        let (coarse, fine) = (error(0.1), error(0.05));
        eprintln!(
            "Radau IIA on Prothero-Robinson, λ = {lambda:e}: errors {coarse:.2e}, {fine:.2e}"
        );
        assert!(
            coarse < 0.01 * 0.1 / lambda.abs(),
            "λ = {lambda:e}: {coarse:e}"
        );
        assert!(
            coarse / fine > 6.0 || fine < 1e-15,
            "λ = {lambda:e}: {coarse:e} {fine:e}"
        );
    }
}
