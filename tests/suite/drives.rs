//! Prescribed motions (`drive crank.q = law`): the driven four-bar's torque against the closed
//! form of virtual power, the driven coordinate on its law and the energy balance with the
//! drive's work, with every integrator of the registry (or its refusal); a driven tree against
//! its inverse dynamics; the refusals.

use crate::common::programs::{column, example_text, output, refusal_codes, run_text};
use lsdc::integrators::{Feature, INTEGRATORS};
use lsdc::prepare::{Integrator, Settings};
use lsdc::simulate::run::Simulation;

fn settings(integrator: Integrator) -> Settings {
    Settings {
        integrator,
        duration: 1.0,
        output: 0.01,
        rtol: 1e-12,
        atol: 1e-12,
        step: Some(1e-3),
        ..Settings::default()
    }
}

/// The planar four-bar of `four_bar_driven.lsd` in closed form along its crank angle θ₁ with
/// ω₁ = 2π, α₁ = 0: the coupler and rocker angles from the intersection of two circles (the
/// assembly mode of the start, C above BD, kept over the turn of a Grashof crank-rocker), their
/// rates and accelerations from the loop's equation differentiated once and twice, then the
/// crank torque by virtual power, τ ω₁ = d(T + V)/dt = Σ m a_G·v_G + I α ω + m g v_G,y.
fn four_bar_torque(theta1: f64) -> f64 {
    four_bar_torque_moving(theta1, 2.0 * std::f64::consts::PI, 0.0)
}

/// As [`four_bar_torque`], the crank at the rate ω₁ and the acceleration α₁.
pub fn four_bar_torque_moving(theta1: f64, w1: f64, a1: f64) -> f64 {
    let (l0, l1, l2, l3, g) = (4.0, 1.0, 3.5, 3.0, 9.81);
    let e = |t: f64| [t.cos(), t.sin()];
    let n = |t: f64| [-t.sin(), t.cos()];
    let b = [l1 * theta1.cos(), l1 * theta1.sin()];
    let d = [l0, 0.0];
    // C on both circles, on the side of BD that the program's start has (left of B → D).
    let bd = [d[0] - b[0], d[1] - b[1]];
    let s = (bd[0] * bd[0] + bd[1] * bd[1]).sqrt();
    let along = (l2 * l2 - l3 * l3 + s * s) / (2.0 * s);
    let off = (l2 * l2 - along * along).sqrt();
    let (u, perp) = ([bd[0] / s, bd[1] / s], [-bd[1] / s, bd[0] / s]);
    let c = [
        b[0] + along * u[0] + off * perp[0],
        b[1] + along * u[1] + off * perp[1],
    ];
    let theta2 = (c[1] - b[1]).atan2(c[0] - b[0]);
    let theta3 = (c[1] - d[1]).atan2(c[0] - d[0]);
    // l₁ω₁ n₁ + l₂ω₂ n₂ − l₃ω₃ n₃ = 0, solved for ω₂, ω₃ (Cramer).
    let solve = |r: [f64; 2]| {
        let (p, q) = (n(theta2), n(theta3));
        let (m00, m01, m10, m11) = (l2 * p[0], -l3 * q[0], l2 * p[1], -l3 * q[1]);
        let det = m00 * m11 - m01 * m10;
        [
            (r[0] * m11 - m01 * r[1]) / det,
            (m00 * r[1] - r[0] * m10) / det,
        ]
    };
    let [w2, w3] = solve([-l1 * w1 * n(theta1)[0], -l1 * w1 * n(theta1)[1]]);
    // The same, differentiated: the α terms on the left, the centripetal ones on the right.
    let centripetal = |k: usize| {
        l1 * (a1 * n(theta1)[k] - w1 * w1 * e(theta1)[k]) - l2 * w2 * w2 * e(theta2)[k]
            + l3 * w3 * w3 * e(theta3)[k]
    };
    let [a2, a3] = solve([-centripetal(0), -centripetal(1)]);
    // Each bar's centre of mass: its velocity and acceleration from its pivot's.
    let bar = |pivot_v: [f64; 2], pivot_a: [f64; 2], l: f64, t: f64, w: f64, a: f64| {
        let v = [
            pivot_v[0] + l / 2.0 * w * n(t)[0],
            pivot_v[1] + l / 2.0 * w * n(t)[1],
        ];
        let acc = [
            pivot_a[0] + l / 2.0 * (a * n(t)[0] - w * w * e(t)[0]),
            pivot_a[1] + l / 2.0 * (a * n(t)[1] - w * w * e(t)[1]),
        ];
        let (mass, inertia) = (l, l * l * l / 12.0);
        mass * (acc[0] * v[0] + acc[1] * v[1]) + inertia * a * w + mass * g * v[1]
    };
    let vb = [l1 * w1 * n(theta1)[0], l1 * w1 * n(theta1)[1]];
    let ab = [
        l1 * (a1 * n(theta1)[0] - w1 * w1 * e(theta1)[0]),
        l1 * (a1 * n(theta1)[1] - w1 * w1 * e(theta1)[1]),
    ];
    let power = bar([0.0; 2], [0.0; 2], l1, theta1, w1, a1)
        + bar(vb, ab, l2, theta2, w2, a2)
        + bar([0.0; 2], [0.0; 2], l3, theta3, w3, a3);
    power / w1
}

/// The largest |τ_run − τ_closed form| over a full turn, relative to the largest |τ|; the
/// largest distance of the crank from its law, in position and in rate.
fn four_bar_errors(simulation: &Simulation) -> (f64, f64, f64) {
    let (crank, effort) = (
        column(simulation, "crank.q"),
        output(simulation, "crank.drive_effort"),
    );
    let tau = |s: &lsdc::simulate::run::Sample| four_bar_torque(s.coordinates[crank]);
    let largest = (simulation.samples.iter())
        .map(|s| tau(s).abs())
        .fold(0.0, f64::max);
    let (mut torque, mut position, mut rate) = (0.0f64, 0.0f64, 0.0f64);
    for sample in &simulation.samples {
        let law = 1.0 + 2.0 * std::f64::consts::PI * sample.time;
        torque = torque.max((sample.outputs[effort] - tau(sample)).abs() / largest);
        position = position.max((sample.coordinates[crank] - law).abs());
        rate = rate.max((sample.rates[crank] - 2.0 * std::f64::consts::PI).abs());
    }
    (torque, position, rate)
}

/// The four-bar's crank driven at one turn a second: the torque the run finds equals the
/// closed form to 1e-9 of its largest value at every sample of the turn, the crank stays on its
/// law to 1e-12, and the energy balance with the drive's work closes to 1e-9, with every
/// integrator of the registry; the one that does not handle drives says so.
#[test]
fn the_driven_four_bar_torque_is_the_virtual_power_closed_form_with_every_integrator() {
    let text = example_text("four_bar_driven", &[]);
    for entry in INTEGRATORS {
        let simulation = run_text(&text, settings(entry.integrator.clone()));
        if entry.unsupported.contains(&Feature::Drives) {
            let failure = simulation.report.failure.expect("refused");
            assert!(failure.message.contains("drives"), "{}", failure.message);
            continue;
        }
        assert!(simulation.report.failure.is_none(), "{}", entry.name);
        assert_eq!(simulation.samples.len(), 101);
        let (torque, position, rate) = four_bar_errors(&simulation);
        assert!(torque < 1e-9, "{}: torque {torque:e}", entry.name);
        assert!(
            position < 1e-12 && rate < 1e-12,
            "{}: {position:e} {rate:e}",
            entry.name
        );
        let balance = simulation.report.energy_balance.expect("work tracked");
        assert!(balance < 1e-9, "{}: energy balance {balance:e}", entry.name);
    }
}

/// A pendulum driven by `q = a sin(ω t)` needs the torque of its inverse dynamics,
/// τ = m L² q̈ + I q̈ + m g L sin q (the rod's centre at L from the pivot).
#[test]
fn a_driven_pendulum_needs_the_torque_of_its_inverse_dynamics() {
    let text = "import joints;
let rod = body mass = 1.2, iframe = [0, 0, -0.5] ++ 1, inertia = [0.1, 0.1, 0.001] end;
join earth and rod with revolute([1, 0, 0]) as swing;
apply force value = [0, 0, -9.81 * rod.mass], body = earth end on rod.iframe;
drive swing.q = 0.7 * sin(3 * time);
";
    for integrator in [Integrator::Rk4, Integrator::DormandPrince] {
        let simulation = run_text(text, settings(integrator));
        assert!(simulation.report.failure.is_none());
        let (swing, effort) = (
            column(&simulation, "swing.q"),
            output(&simulation, "swing.drive_effort"),
        );
        for sample in &simulation.samples {
            let t = sample.time;
            let (q, acceleration) = (0.7 * (3.0 * t).sin(), -6.3 * (3.0 * t).sin());
            assert!((sample.coordinates[swing] - q).abs() < 1e-12);
            let expected = (1.2 * 0.25 + 0.1) * acceleration + 1.2 * 9.81 * 0.5 * q.sin();
            let error = (sample.outputs[effort] - expected).abs();
            assert!(error < 1e-11 * (1.0 + expected.abs()), "t = {t}: {error:e}");
        }
    }
}

/// The same pendulum with dry and viscous friction in its driven pivot: the drive's torque
/// gains F_c sign q̇ + c q̇ on either side of every reversal of the law's rate (t = π/6, π/2, …),
/// the friction never holds the joint (it sticks nowhere, no switch is reported), and the
/// energy balance counts its work.
#[test]
fn a_driven_joint_with_friction_needs_its_friction_on_both_sides_of_each_reversal() {
    let text = "import joints;
let rod = body mass = 1.2, iframe = [0, 0, -0.5] ++ 1, inertia = [0.1, 0.1, 0.001] end;
join earth and rod with friction_revolute([1, 0, 0], 2.5, 0.4) as swing;
apply force value = [0, 0, -9.81 * rod.mass], body = earth end on rod.iframe;
drive swing.q = 0.7 * sin(3 * time);
";
    for integrator in [Integrator::Rk4, Integrator::DormandPrince] {
        let name = format!("{integrator:?}");
        let simulation = run_text(
            text,
            Settings {
                duration: 2.0,
                ..settings(integrator)
            },
        );
        assert!(simulation.report.failure.is_none());
        assert!(simulation.report.friction_switches.is_empty());
        let effort = output(&simulation, "swing.drive_effort");
        let mut reversed = (false, false);
        for sample in &simulation.samples {
            let t = sample.time;
            let q = 0.7 * (3.0 * t).sin();
            let (rate, acceleration) = (2.1 * (3.0 * t).cos(), -6.3 * (3.0 * t).sin());
            let friction = 2.5 * rate.signum() + 0.4 * rate;
            let expected =
                (1.2 * 0.25 + 0.1) * acceleration + 1.2 * 9.81 * 0.5 * q.sin() + friction;
            let error = (sample.outputs[effort] - expected).abs();
            assert!(error < 1e-11 * (1.0 + expected.abs()), "t = {t}: {error:e}");
            match rate > 0.0 {
                true => reversed.0 = true,
                false => reversed.1 = true,
            }
        }
        assert_eq!(
            reversed,
            (true, true),
            "the run crosses reversals both ways"
        );
        let balance = simulation.report.energy_balance.expect("an energy balance");
        assert!(balance.abs() < 1e-8, "{name}: energy balance {balance:e}");
    }
}

/// Friction in a driven joint changes the drive's effort, never the motion: the free link of a
/// double pendulum whose first joint is driven moves the same with and without it.
#[test]
fn friction_in_a_driven_joint_leaves_the_free_joints_motion_unchanged() {
    let program = |pivot: &str| {
        format!(
            "import joints;
let upper = body mass = 1.0, iframe = [0, 0, -0.5] ++ 1, inertia = [0.08, 0.08, 0.001] end;
let lower = body mass = 1.0, iframe = [0, 0, -0.5] ++ 1, inertia = [0.08, 0.08, 0.001] end;
join earth and upper with {pivot} as shoulder;
join [0, 0, -1] ++ 1 @ upper and lower with revolute([1, 0, 0]) as elbow;
apply force value = [0, 0, -9.81], body = earth end on upper.iframe;
apply force value = [0, 0, -9.81], body = earth end on lower.iframe;
drive shoulder.q = 0.9 * sin(2 * time);
initial elbow.q = 0.3;
"
        )
    };
    let plain = run_text(
        &program("revolute([1, 0, 0])"),
        settings(Integrator::DormandPrince),
    );
    let rubbing = run_text(
        &program("friction_revolute([1, 0, 0], 3, 0.5)"),
        settings(Integrator::DormandPrince),
    );
    let elbow = column(&plain, "elbow.q");
    assert_eq!(elbow, column(&rubbing, "elbow.q"));
    assert_eq!(plain.samples.len(), rubbing.samples.len());
    let effort = output(&plain, "shoulder.drive_effort");
    let mut largest_change = 0.0_f64;
    for (a, b) in plain.samples.iter().zip(&rubbing.samples) {
        let moved = (a.coordinates[elbow] - b.coordinates[elbow]).abs();
        assert!(
            moved < 1e-10,
            "t = {}: the elbow moved by {moved:e}",
            a.time
        );
        let change = (b.outputs[effort] - a.outputs[effort]).abs();
        largest_change = largest_change.max(change);
    }
    // The shoulder's friction (3 N m dry, up to 0.5 x 1.8 N m viscous) is in its drive's effort.
    assert!(largest_change > 3.0, "{largest_change}");
}

#[test]
fn drives_that_cannot_be_imposed_are_refused() {
    let pendulum = "import joints;
let a = body mass = 1, iframe = 0, inertia = [1, 1, 1] end;
let b = body mass = 1, iframe = 0, inertia = [1, 1, 1] end;
join earth and a with revolute([1, 0, 0]) as first;
join earth and b with spherical as ball;
";
    let codes = |drives: &str| refusal_codes(&format!("{pendulum}{drives}"));
    assert_eq!(
        codes("drive first.q = time; drive first.q = 2 * time;"),
        ["E0485"]
    );
    assert_eq!(codes("drive first.q = floor(time);"), ["E0484"]);
    assert_eq!(codes("drive first.q = abs(time - 1);"), ["E0484"]);
    assert_eq!(codes("drive first.q = ball.a;"), ["E0483"]);
    assert_eq!(codes("drive ball.a = time;"), ["E0482"]);
    assert_eq!(codes("drive first.q' = time;"), ["E0481"]);
    assert_eq!(codes("drve first.q = time;"), ["E0480"]);
    assert!(codes("drive first.q = sin(time) ^ 2;").is_empty());
}

/// `lsdc inverse` on the driven four-bar: its torque column is the closed form, the crank's
/// reaction moment about its axis is that torque, and the power is torque × rate; a program
/// without drives is refused (exit code 2) with what to declare.
#[test]
fn inverse_gives_the_driving_torque_its_reaction_and_its_power() {
    let (code, out, err) = crate::common::lsdc(&[
        "inverse",
        "examples/four_bar_driven.lsd",
        "--every",
        "0.05",
        "--reactions",
    ]);
    assert_eq!(code, 0, "{err}");
    let mut lines = out.lines();
    let header: Vec<&str> = lines.next().expect("header").split(',').collect();
    let at = |name: &str| header.iter().position(|h| *h == name).expect(name);
    let (angle, torque, power, moment) = (
        at("crank.q"),
        at("crank.drive_effort"),
        at("power"),
        at("crank.reaction.mz"),
    );
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|x| x.parse().expect("a number")).collect())
        .collect();
    assert_eq!(rows.len(), 21);
    let largest = rows.iter().map(|r| r[torque].abs()).fold(0.0, f64::max);
    for row in &rows {
        let expected = four_bar_torque(row[angle]);
        assert!((row[torque] - expected).abs() < 1e-9 * largest, "{row:?}");
        assert!(
            (row[moment] - row[torque]).abs() < 1e-9 * largest,
            "{row:?}"
        );
        let rate = 2.0 * std::f64::consts::PI;
        assert!((row[power] - rate * row[torque]).abs() < 1e-12 * rate * largest);
    }
    let (code, _, err) = crate::common::lsdc(&["inverse", "examples/four_bar.lsd"]);
    assert_eq!(code, 2);
    assert!(err.contains("drives no coordinate"), "{err}");
}
