//! The projection hook of the integrators, `OdeSystem::project`: called once per accepted step,
//! the integration continues from its result, outputs at step ends see it, derivatives cached at a
//! step's end are taken at the projected state, and a failing projection stops the integration.

use std::f64::consts::PI;

use lsdc::integrate::{
    integrate, CallbackError, Failure, IntegrationError, Method, OdeSystem, Settings, Stats,
};

/// A point moving at unit speed on the unit circle, in Cartesian coordinates (x, y, vx, vy): the
/// acceleration is the centripetal one, −(vx² + vy²)·(x, y). Nothing keeps it on the circle but
/// the accuracy of the integration.
struct Circle;

impl OdeSystem for Circle {
    fn dimension(&self) -> usize {
        4
    }

    fn rhs(&mut self, _t: f64, s: &[f64], dsdt: &mut [f64]) -> Result<(), CallbackError> {
        let speed_squared = s[2] * s[2] + s[3] * s[3];
        dsdt[0] = s[2];
        dsdt[1] = s[3];
        dsdt[2] = -speed_squared * s[0];
        dsdt[3] = -speed_squared * s[1];
        Ok(())
    }
}

/// The circle whose projection puts the point back on it and removes the radial velocity,
/// counting its calls and the times it was called at.
#[derive(Default)]
struct ProjectedCircle {
    times: Vec<f64>,
    moved: usize,
}

impl OdeSystem for ProjectedCircle {
    fn dimension(&self) -> usize {
        4
    }

    fn rhs(&mut self, t: f64, s: &[f64], dsdt: &mut [f64]) -> Result<(), CallbackError> {
        Circle.rhs(t, s, dsdt)
    }

    fn project(&mut self, t: f64, s: &mut [f64]) -> Result<bool, CallbackError> {
        self.times.push(t);
        let before = s.to_vec();
        let radius = s[0].hypot(s[1]);
        s[0] /= radius;
        s[1] /= radius;
        let radial = s[2] * s[0] + s[3] * s[1];
        s[2] -= radial * s[0];
        s[3] -= radial * s[1];
        let moved = s != before.as_slice();
        self.moved += usize::from(moved);
        Ok(moved)
    }
}

const START: [f64; 4] = [1.0, 0.0, 0.0, 1.0];

fn methods() -> [Method; 4] {
    [
        Method::Rk4 { step: 0.1 },
        Method::DormandPrince,
        Method::Rosenbrock,
        Method::Automatic,
    ]
}

/// The (t, state) pairs handed to the observer.
type Observed = Vec<(f64, Vec<f64>)>;

/// Integrates with the default tolerances and collects the observed (t, state) pairs.
fn solve(
    method: &Method,
    system: &mut dyn OdeSystem,
    y0: &[f64],
    t_end: f64,
    outputs: &[f64],
) -> Result<(Vec<f64>, Stats, Observed), IntegrationError> {
    solve_with(method, system, y0, t_end, outputs, &Settings::default())
}

fn solve_with(
    method: &Method,
    system: &mut dyn OdeSystem,
    y0: &[f64],
    t_end: f64,
    outputs: &[f64],
    settings: &Settings,
) -> Result<(Vec<f64>, Stats, Observed), IntegrationError> {
    let mut observed = Vec::new();
    let mut observer = |t: f64, y: &[f64]| {
        observed.push((t, y.to_vec()));
        Ok(())
    };
    let (y, stats) = integrate(
        method,
        system,
        0.0,
        y0,
        t_end,
        outputs,
        settings,
        &mut observer,
    )?;
    Ok((y, stats, observed))
}

fn radius_error(s: &[f64]) -> f64 {
    (s[0].hypot(s[1]) - 1.0).abs()
}

#[test]
fn projection_keeps_the_point_on_the_circle_for_100_periods() {
    let t_end = 200.0 * PI;
    for method in methods() {
        let mut system = ProjectedCircle::default();
        // The Rosenbrock-W method is of order 3 with an order-2 estimate: at the default 1e-6
        // its phase error after 100 periods is 0.17 rad (RODAS3's, before it, was below
        // 0.05), so it is held to 1e-7 here, where it is 0.016.
        let settings = match method {
            Method::Rosenbrock => Settings {
                rtol: 1e-7,
                ..Settings::default()
            },
            _ => Settings::default(),
        };
        let (y, stats, observed) =
            solve_with(&method, &mut system, &START, t_end, &[t_end], &settings).unwrap();
        assert!(
            radius_error(&y) < 1e-14,
            "{method:?}: radius off by {:e}",
            radius_error(&y)
        );
        // The output at the end time is the projected state the integration ended with.
        assert_eq!(observed, vec![(t_end, y.clone())], "{method:?}");
        assert_eq!(
            system.times.len(),
            stats.steps,
            "{method:?}: one projection per accepted step"
        );
        assert!(
            system.times.windows(2).all(|pair| pair[0] < pair[1]),
            "{method:?}"
        );
        assert_eq!(system.times.last(), Some(&t_end), "{method:?}");
        // The projection does not spoil the motion along the circle: after 100 periods the point
        // is back near angle 0 (within the methods' phase errors of up to 0.03).
        assert!(y[1].atan2(y[0]).abs() < 0.05, "{method:?}: ended at {y:?}");
        assert!(
            (y[0] * y[2] + y[1] * y[3]).abs() < 1e-14,
            "{method:?}: radial velocity left"
        );
    }
}

#[test]
fn without_projection_the_point_drifts_off_the_circle() {
    let t_end = 200.0 * PI;
    let (y, ..) = solve(&Method::Rk4 { step: 0.1 }, &mut Circle, &START, t_end, &[]).unwrap();
    assert!(
        radius_error(&y) > 1e-10,
        "radius off by only {:e}",
        radius_error(&y)
    );
}

#[test]
fn outputs_at_step_ends_see_projected_states() {
    // With RK4 the step ends are known: every output on the grid coincides with one.
    let step = 0.1;
    let outputs: Vec<f64> = (1..=1000).map(|k| k as f64 * step).collect();
    let mut system = ProjectedCircle::default();
    let (_, stats, observed) =
        solve(&Method::Rk4 { step }, &mut system, &START, 100.0, &outputs).unwrap();
    assert_eq!(stats.steps, 1000);
    assert_eq!(observed.len(), 1000);
    for (t, s) in &observed {
        assert!(
            radius_error(s) < 1e-14,
            "t = {t}: radius off by {:e}",
            radius_error(s)
        );
        let radial_velocity = s[0] * s[2] + s[1] * s[3];
        assert!(
            radial_velocity.abs() < 1e-14,
            "t = {t}: radial velocity {radial_velocity:e}"
        );
    }
}

/// dy/dt = y whose projection resets y to 1 after every step, recording the state each step ended
/// with: if a step reused a derivative cached at the unprojected end, its start slope would be
/// e^h instead of 1 and its end would miss e^h.
#[derive(Default)]
struct Reset {
    step_ends: Vec<(f64, f64)>,
}

impl OdeSystem for Reset {
    fn dimension(&self) -> usize {
        1
    }

    fn rhs(&mut self, _t: f64, y: &[f64], dydt: &mut [f64]) -> Result<(), CallbackError> {
        dydt[0] = y[0];
        Ok(())
    }

    fn project(&mut self, t: f64, y: &mut [f64]) -> Result<bool, CallbackError> {
        self.step_ends.push((t, y[0]));
        let moved = y[0] != 1.0;
        y[0] = 1.0;
        Ok(moved)
    }
}

#[test]
fn each_step_starts_from_the_derivative_at_the_projected_state() {
    // Many outputs, so that RK4 caches the end derivative for its interpolant; tolerances tight
    // enough that a stale slope shows well above the local error.
    let outputs: Vec<f64> = (0..=200).map(|k| k as f64 * 0.005).collect();
    let settings = Settings {
        rtol: 1e-8,
        atol: 1e-10,
        ..Settings::default()
    };
    for method in methods() {
        let method = match method {
            Method::Rk4 { .. } => Method::Rk4 { step: 0.01 },
            other => other,
        };
        let mut system = Reset::default();
        let (y, ..) = solve_with(&method, &mut system, &[1.0], 1.0, &outputs, &settings).unwrap();
        assert_eq!(y, vec![1.0]);
        let mut t_start = 0.0;
        for &(t, y_end) in &system.step_ends {
            let exact = (t - t_start).exp();
            assert!(
                (y_end - exact).abs() < 1e-8 * exact,
                "{method:?}: step to t = {t} ends at {y_end}, not {exact}"
            );
            t_start = t;
        }
    }
}

#[test]
fn a_reprojection_costs_one_evaluation_only_when_the_state_moved() {
    let t_end = 20.0 * PI;
    // Dormand–Prince: one evaluation at the start, one for the initial step estimate, six per
    // attempt, and one to refresh the first-same-as-last stage after each projection that moved.
    let mut system = ProjectedCircle::default();
    let (_, stats, _) = solve(&Method::DormandPrince, &mut system, &START, t_end, &[]).unwrap();
    assert!(
        system.moved > stats.steps / 2,
        "the projection should usually move the state"
    );
    assert_eq!(
        stats.rhs_evaluations,
        2 + 6 * (stats.steps + stats.rejected) + system.moved
    );
    // RK4 projects before deriving anything from a step's end: four evaluations per step, and
    // the last step's end slope (for its error estimate).
    let mut system = ProjectedCircle::default();
    let (_, stats, _) = solve(&Method::Rk4 { step: 0.1 }, &mut system, &START, t_end, &[]).unwrap();
    assert_eq!(stats.rhs_evaluations, 4 * stats.steps + 1);
}

/// The circle with a projection that only counts its calls and never moves the state.
#[derive(Default)]
struct IdleProjection {
    calls: usize,
}

impl OdeSystem for IdleProjection {
    fn dimension(&self) -> usize {
        4
    }

    fn rhs(&mut self, t: f64, s: &[f64], dsdt: &mut [f64]) -> Result<(), CallbackError> {
        Circle.rhs(t, s, dsdt)
    }

    fn project(&mut self, _t: f64, _s: &mut [f64]) -> Result<bool, CallbackError> {
        self.calls += 1;
        Ok(false)
    }
}

#[test]
fn a_projection_that_does_not_move_the_state_changes_nothing() {
    let t_end = 20.0 * PI;
    let outputs: Vec<f64> = (0..=100).map(|k| k as f64 * t_end / 100.0).collect();
    for method in methods() {
        let plain = solve(&method, &mut Circle, &START, t_end, &outputs).unwrap();
        let mut idle = IdleProjection::default();
        let projected = solve(&method, &mut idle, &START, t_end, &outputs).unwrap();
        assert_eq!(plain, projected, "{method:?}");
        assert_eq!(idle.calls, plain.1.steps, "{method:?}");
    }
}

/// The circle with a projection that fails from t = 1 on.
struct FailingProjection;

impl OdeSystem for FailingProjection {
    fn dimension(&self) -> usize {
        4
    }

    fn rhs(&mut self, t: f64, s: &[f64], dsdt: &mut [f64]) -> Result<(), CallbackError> {
        Circle.rhs(t, s, dsdt)
    }

    fn project(&mut self, t: f64, _s: &mut [f64]) -> Result<bool, CallbackError> {
        match t < 1.0 {
            true => Ok(false),
            false => Err("the constraints cannot be satisfied".into()),
        }
    }
}

#[test]
fn a_failing_projection_stops_the_integration_like_a_failing_rhs() {
    for method in methods() {
        let error = solve(&method, &mut FailingProjection, &START, 2.0, &[]).unwrap_err();
        assert_eq!(
            error.failure,
            Failure::System("the constraints cannot be satisfied".to_string()),
            "{method:?}"
        );
        assert!(
            (1.0..2.0).contains(&error.time),
            "{method:?}: stopped at {}",
            error.time
        );
        assert!(error.stats.steps > 0, "{method:?}");
    }
}
