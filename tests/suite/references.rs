//! The reference laws of time (`quintic(time, t0, q0, t1, q1)`, …, `spline`), `saturate`,
//! `dead_zone` and `derivative`: each law's position, rate and acceleration, as a drive
//! differentiates it on the expression pool, against hand-written closed forms at many times,
//! the ends and the inner breaks included (where the acceleration jumps, the right-hand value);
//! the spline against an independent construction (second derivatives at the knots, Ahlberg,
//! Nilson & Walsh's moment equations, solved densely); `derivative` in outputs and in an effort
//! that makes a mass follow a law.

use crate::common::programs::{prepared_text, run_text};
use lsdc::prepare::{Integrator, Settings};
use std::f64::consts::PI;

/// Start, end and positions of the laws: the times and the breaks of the parabolic and
/// trapezoidal laws are binary fractions, so that the breaks fall on exact instants.
const T0: f64 = 0.25;
const T1: f64 = 2.25;
const Q0: f64 = -0.4;
const Q1: f64 = 1.1;
const RAMP: f64 = 0.5;

/// A law's position, rate and acceleration.
type Triple = [f64; 3];

/// The drive of a prismatic joint along `law` (a scalar law of `time`), evaluated at `times`.
fn drive_values(law: &str, times: &[f64]) -> Vec<Triple> {
    let text = format!(
        "import joints ;\n\
         let slider = body mass = 1, iframe = 0, inertia = [1, 1, 1] end ;\n\
         join earth and slider with prismatic([1, 0, 0]) as x ;\n\
         drive x.q = {law} ;\n"
    );
    let prepared = prepared_text(&text);
    let drive = &prepared.model.drives[0];
    times
        .iter()
        .map(|&t| {
            let at = drive.at(t);
            [at.position, at.rate, at.acceleration]
        })
        .collect()
}

/// Times from before the start to after the end, with the start, the end and `breaks`.
fn times(breaks: &[f64]) -> Vec<f64> {
    let mut times: Vec<f64> = (0..=400)
        .map(|k| T0 - 0.3 + 2.6 * k as f64 / 400.0)
        .collect();
    times.extend([T0, T1]);
    times.extend(breaks);
    times
}

/// The largest difference between the drive's values and `closed` over `times`, each
/// derivative order relative to its scale (h/Tᵏ for a law of height h over T).
fn worst_error(law: &str, times: &[f64], closed: impl Fn(f64) -> Triple) -> f64 {
    let (h, duration) = ((Q1 - Q0).abs(), T1 - T0);
    let scales = [
        h.max(Q0.abs()).max(Q1.abs()),
        h / duration,
        h / (duration * duration),
    ];
    worst_error_on(law, times, closed, scales)
}

/// [`worst_error`] with each derivative order relative to `scales`.
fn worst_error_on(law: &str, times: &[f64], closed: impl Fn(f64) -> Triple, scales: Triple) -> f64 {
    let values = drive_values(law, times);
    let mut worst: f64 = 0.0;
    for (&t, got) in times.iter().zip(&values) {
        let want = closed(t);
        for k in 0..3 {
            let error = (got[k] - want[k]).abs() / scales[k];
            assert!(
                error < 1e-13,
                "{law} at t = {t}: derivative {k} is {}, the closed form {}",
                got[k],
                want[k]
            );
            worst = worst.max(error);
        }
    }
    worst
}

/// A law between rests from its normalised profile (s, s', s'') of τ ∈ [0, 1): q0 before the
/// start, q1 from the end on.
fn between(profile: impl Fn(f64) -> Triple) -> impl Fn(f64) -> Triple {
    move |t| {
        let (h, duration) = (Q1 - Q0, T1 - T0);
        if t < T0 {
            return [Q0, 0.0, 0.0];
        }
        if t >= T1 {
            return [Q1, 0.0, 0.0];
        }
        let [s, ds, dds] = profile((t - T0) / duration);
        [
            Q0 + h * s,
            h * ds / duration,
            h * dds / (duration * duration),
        ]
    }
}

fn call(name: &str, extra: &str) -> String {
    format!("{name}(time, {T0}, {Q0}, {T1}, {Q1}{extra})")
}

#[test]
fn the_polynomial_laws_derivatives_equal_their_closed_forms() {
    let all = times(&[T0 + (T1 - T0) / 2.0]);
    let linear = worst_error(&call("linear", ""), &all, between(|u| [u, 1.0, 0.0]));
    let cubic = worst_error(
        &call("cubic", ""),
        &all,
        between(|u| {
            [
                3.0 * u * u - 2.0 * u.powi(3),
                6.0 * u - 6.0 * u * u,
                6.0 - 12.0 * u,
            ]
        }),
    );
    let quintic = worst_error(
        &call("quintic", ""),
        &all,
        between(|u| {
            [
                10.0 * u.powi(3) - 15.0 * u.powi(4) + 6.0 * u.powi(5),
                30.0 * u * u - 60.0 * u.powi(3) + 30.0 * u.powi(4),
                60.0 * u - 180.0 * u * u + 120.0 * u.powi(3),
            ]
        }),
    );
    // Constant acceleration 4 for the first half, −4 for the second (the break at τ = 1/2).
    let parabolic = worst_error(
        &call("parabolic", ""),
        &all,
        between(|u| match u < 0.5 {
            true => [2.0 * u * u, 4.0 * u, 4.0],
            false => [1.0 - 2.0 * (1.0 - u).powi(2), 4.0 * (1.0 - u), -4.0],
        }),
    );
    println!("worst relative errors: linear {linear:.1e}, cubic {cubic:.1e}, quintic {quintic:.1e}, parabolic {parabolic:.1e}");
}

#[test]
fn the_trigonometric_laws_derivatives_equal_their_closed_forms() {
    let all = times(&[]);
    let harmonic = worst_error(
        &call("harmonic", ""),
        &all,
        between(|u| {
            let w = PI * u;
            [
                (1.0 - w.cos()) / 2.0,
                PI * w.sin() / 2.0,
                PI * PI * w.cos() / 2.0,
            ]
        }),
    );
    let cycloidal = worst_error(
        &call("cycloidal", ""),
        &all,
        between(|u| {
            let w = 2.0 * PI * u;
            [u - w.sin() / (2.0 * PI), 1.0 - w.cos(), 2.0 * PI * w.sin()]
        }),
    );
    println!("worst relative errors: harmonic {harmonic:.1e}, cycloidal {cycloidal:.1e}");
}

/// Biagiotti & Melchiorri (3.8): acceleration a = h/(Ta (T − Ta)) during Ta, cruise at
/// v = h/(T − Ta), deceleration during the last Ta.
#[test]
fn the_trapezoidal_laws_derivatives_equal_their_closed_forms() {
    for ramp in [RAMP, (T1 - T0) / 2.0] {
        let all = times(&[T0 + ramp, T1 - ramp]);
        let law = call("trapezoidal", &format!(", {ramp}"));
        let closed = |t: f64| {
            let (h, duration) = (Q1 - Q0, T1 - T0);
            let (v, a) = (h / (duration - ramp), h / (ramp * (duration - ramp)));
            let u = t - T0;
            if t < T0 {
                [Q0, 0.0, 0.0]
            } else if u < ramp {
                [Q0 + a * u * u / 2.0, a * u, a]
            } else if u < duration - ramp {
                [Q0 + v * (u - ramp / 2.0), v, 0.0]
            } else if t < T1 {
                let left = duration - u;
                [Q1 - a * left * left / 2.0, a * left, -a]
            } else {
                [Q1, 0.0, 0.0]
            }
        };
        let worst = worst_error(&law, &all, closed);
        println!("trapezoidal with a ramp of {ramp}: worst relative error {worst:.1e}");
    }
}

/// The clamped cubic spline through (t_k, q_k) at rest at both ends, by the moments M_k (the
/// accelerations at the knots; de Boor, *A Practical Guide to Splines*, ch. IV): a tridiagonal
/// system written out as a dense one and solved by Gaussian elimination with partial pivoting,
/// then each piece from its ends' moments. Independent of the library's velocity form.
fn spline_by_moments(knots: &[f64], q: &[f64]) -> impl Fn(f64) -> Triple {
    let n = knots.len() - 1;
    let h: Vec<f64> = knots.windows(2).map(|w| w[1] - w[0]).collect();
    let slope: Vec<f64> = (0..n).map(|k| (q[k + 1] - q[k]) / h[k]).collect();
    let size = n + 1;
    let mut a = vec![vec![0.0; size + 1]; size];
    a[0][0] = 2.0 * h[0];
    a[0][1] = h[0];
    a[0][size] = 6.0 * slope[0];
    for k in 1..n {
        a[k][k - 1] = h[k - 1];
        a[k][k] = 2.0 * (h[k - 1] + h[k]);
        a[k][k + 1] = h[k];
        a[k][size] = 6.0 * (slope[k] - slope[k - 1]);
    }
    a[n][n - 1] = h[n - 1];
    a[n][n] = 2.0 * h[n - 1];
    a[n][size] = -6.0 * slope[n - 1];
    for col in 0..size {
        let pivot = (col..size)
            .max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))
            .expect("rows");
        a.swap(col, pivot);
        for row in col + 1..size {
            let factor = a[row][col] / a[col][col];
            let pivot_row = a[col].clone();
            for (entry, pivot_entry) in a[row].iter_mut().zip(&pivot_row).skip(col) {
                *entry -= factor * pivot_entry;
            }
        }
    }
    let mut m = vec![0.0; size];
    for row in (0..size).rev() {
        let rest: f64 = (row + 1..size).map(|c| a[row][c] * m[c]).sum();
        m[row] = (a[row][size] - rest) / a[row][row];
    }
    let (knots, q) = (knots.to_vec(), q.to_vec());
    move |t: f64| {
        if t < knots[0] {
            return [q[0], 0.0, 0.0];
        }
        if t >= knots[n] {
            return [q[n], 0.0, 0.0];
        }
        let k = (0..n).rev().find(|&k| t >= knots[k]).expect("a segment");
        let (hk, left, right) = (h[k], knots[k + 1] - t, t - knots[k]);
        let position = m[k] * left.powi(3) / (6.0 * hk)
            + m[k + 1] * right.powi(3) / (6.0 * hk)
            + (q[k] / hk - m[k] * hk / 6.0) * left
            + (q[k + 1] / hk - m[k + 1] * hk / 6.0) * right;
        let rate = -m[k] * left * left / (2.0 * hk) + m[k + 1] * right * right / (2.0 * hk)
            - (q[k] / hk - m[k] * hk / 6.0)
            + (q[k + 1] / hk - m[k + 1] * hk / 6.0);
        let acceleration = (m[k] * left + m[k + 1] * right) / hk;
        [position, rate, acceleration]
    }
}

#[test]
fn the_spline_through_via_points_is_the_clamped_cubic_spline() {
    let knots = [T0, 0.75, 1.0, 1.625, T1];
    let q = [Q0, 0.3, 0.2, 1.4, Q1];
    let arguments: Vec<String> = knots
        .iter()
        .zip(&q)
        .map(|(t, q)| format!("{t}, {q}"))
        .collect();
    let law = format!("spline(time, {})", arguments.join(", "));
    let all = times(&knots);
    let worst = worst_error(&law, &all, spline_by_moments(&knots, &q));
    println!("spline: worst relative error {worst:.1e}");
    // Through the via points, with the rate and the acceleration continuous across each.
    let at = |ts: &[f64]| drive_values(&law, ts);
    for (k, &t) in knots.iter().enumerate() {
        let [before, on] = at(&[t - 1e-9, t])[..] else {
            unreachable!()
        };
        assert!(
            (on[0] - q[k]).abs() < 1e-15,
            "position {} at t = {t}",
            on[0]
        );
        if k > 0 && k < knots.len() - 1 {
            assert!((before[1] - on[1]).abs() < 1e-7, "rate jumps at t = {t}");
            assert!(
                (before[2] - on[2]).abs() < 1e-6,
                "acceleration jumps at t = {t}"
            );
        }
    }
    // Two points: the cubic between rests.
    let two = format!("spline(time, {T0}, {Q0}, {T1}, {Q1})");
    let cubic = drive_values(&call("cubic", ""), &all);
    for (got, want) in drive_values(&two, &all).iter().zip(&cubic) {
        for k in 0..3 {
            assert!((got[k] - want[k]).abs() < 1e-13, "{got:?} against {want:?}");
        }
    }
}

/// A point's law between two points: each component is the scalar law between the
/// components.
#[test]
fn a_law_between_two_points_moves_each_component_on_the_scalar_law() {
    let (start, end) = ([0.1, -0.2, 0.3], [0.5, 0.4, -0.6]);
    let all = times(&[T0 + RAMP, T1 - RAMP]);
    for (name, extra) in [("quintic", ""), ("trapezoidal", ", 0.5"), ("cycloidal", "")] {
        for axis in 0..3 {
            let unit = ["[1, 0, 0]", "[0, 1, 0]", "[0, 0, 1]"][axis];
            let vector = format!(
                "dot({name}(time, {T0}, [{}, {}, {}], {T1}, [{}, {}, {}]{extra}), {unit})",
                start[0], start[1], start[2], end[0], end[1], end[2]
            );
            let scalar = format!(
                "{name}(time, {T0}, {}, {T1}, {}{extra})",
                start[axis], end[axis]
            );
            let (got, want) = (drive_values(&vector, &all), drive_values(&scalar, &all));
            for (g, w) in got.iter().zip(&want) {
                for k in 0..3 {
                    assert!(
                        (g[k] - w[k]).abs() < 1e-14,
                        "{name} axis {axis}: {g:?} against {w:?}"
                    );
                }
            }
        }
    }
}

/// `saturate(x, lo, hi)` and `dead_zone(x, width)` of a sine: the value and the derivatives of
/// the piece the sine is in, away from the corners (where the derivative is one-sided).
#[test]
fn saturation_and_dead_zone_have_the_derivatives_of_their_pieces() {
    let all: Vec<f64> = (0..=600).map(|k| k as f64 * 0.01).collect();
    let saturated = drive_values("saturate(sin(time), -0.5, 0.75)", &all);
    let zoned = drive_values("dead_zone(sin(time), 0.8)", &all);
    for ((&t, sat), zone) in all.iter().zip(&saturated).zip(&zoned) {
        let (x, dx, ddx) = (t.sin(), t.cos(), -t.sin());
        if (x + 0.5).abs() < 1e-6 || (x - 0.75).abs() < 1e-6 || (x.abs() - 0.4).abs() < 1e-6 {
            continue;
        }
        let want_sat = match x {
            x if x < -0.5 => [-0.5, 0.0, 0.0],
            x if x > 0.75 => [0.75, 0.0, 0.0],
            x => [x, dx, ddx],
        };
        let want_zone = match x {
            x if x > 0.4 => [x - 0.4, dx, ddx],
            x if x < -0.4 => [x + 0.4, dx, ddx],
            _ => [0.0, 0.0, 0.0],
        };
        for k in 0..3 {
            assert!(
                (sat[k] - want_sat[k]).abs() < 1e-15,
                "saturate at {t}: {sat:?}"
            );
            assert!(
                (zone[k] - want_zone[k]).abs() < 1e-15,
                "dead_zone at {t}: {zone:?}"
            );
        }
    }
}

/// `derivative` in outputs gives the law's rate and acceleration, and in an effort the
/// feed-forward of a computed force: a mass of 2 kg pushed by m q_ref'' + kp (q_ref − q) +
/// kd (q_ref' − q') from the law's start follows the law to the integrator's tolerance.
#[test]
fn derivative_gives_outputs_and_efforts_the_laws_rates() {
    let law = call("quintic", "");
    let text = format!(
        "import joints ;\n\
         let cart = body mass = 2, iframe = 0, inertia = [1, 1, 1] end ;\n\
         join earth and cart with prismatic([1, 0, 0]) as x ;\n\
         let reference = {law} ;\n\
         apply force value = [2 * derivative(derivative(reference)) + 400 * (reference - x.q) + 40 * (derivative(reference) - x.q'), 0, 0], body = earth end on cart ;\n\
         initial x.q = {Q0} ;\n\
         output rate = derivative(reference) ;\n\
         output acceleration = derivative(derivative(reference)) ;\n"
    );
    let settings = Settings {
        integrator: Integrator::DormandPrince,
        duration: 2.5,
        output: 0.01,
        rtol: 1e-11,
        atol: 1e-11,
        ..Settings::default()
    };
    let simulation = run_text(&text, settings);
    assert!(
        simulation.report.failure.is_none(),
        "{:?}",
        simulation.report.failure
    );
    let column = |name: &str| {
        (simulation.output_names.iter())
            .position(|n| n == name)
            .unwrap_or_else(|| panic!("no output {name}"))
    };
    let (rate, acceleration) = (column("rate"), column("acceleration"));
    let closed = between(|u| {
        [
            10.0 * u.powi(3) - 15.0 * u.powi(4) + 6.0 * u.powi(5),
            30.0 * u * u - 60.0 * u.powi(3) + 30.0 * u.powi(4),
            60.0 * u - 180.0 * u * u + 120.0 * u.powi(3),
        ]
    });
    let mut tracking: f64 = 0.0;
    for sample in &simulation.samples {
        let want = closed(sample.time);
        assert!((sample.outputs[rate] - want[1]).abs() < 1e-13);
        assert!((sample.outputs[acceleration] - want[2]).abs() < 1e-13);
        tracking = tracking.max((sample.coordinates[0] - want[0]).abs());
    }
    println!("the computed force follows the quintic within {tracking:.1e}");
    assert!(tracking < 1e-8, "tracking error {tracking}");
}

/// ∫ₐᵇ f by adaptive Simpson with Richardson's correction (Lyness, "Notes on the adaptive
/// Simpson quadrature routine", J. ACM 16(3), 1969), to `tolerance`: independent of the
/// composite Gauss–Legendre rule of the law.
fn adaptive_simpson(f: &dyn Fn(f64) -> f64, a: f64, b: f64, tolerance: f64) -> f64 {
    fn step(
        f: &dyn Fn(f64) -> f64,
        (a, fa): (f64, f64),
        (m, fm): (f64, f64),
        (b, fb): (f64, f64),
        whole: f64,
        tolerance: f64,
        depth: usize,
    ) -> f64 {
        let (left, right) = (0.5 * (a + m), 0.5 * (m + b));
        let (fl, fr) = (f(left), f(right));
        let first = (m - a) / 6.0 * (fa + 4.0 * fl + fm);
        let second = (b - m) / 6.0 * (fm + 4.0 * fr + fb);
        let difference = first + second - whole;
        if depth == 0 || difference.abs() <= 15.0 * tolerance {
            return first + second + difference / 15.0;
        }
        step(
            f,
            (a, fa),
            (left, fl),
            (m, fm),
            first,
            tolerance / 2.0,
            depth - 1,
        ) + step(
            f,
            (m, fm),
            (right, fr),
            (b, fb),
            second,
            tolerance / 2.0,
            depth - 1,
        )
    }
    let m = 0.5 * (a + b);
    let (fa, fm, fb) = (f(a), f(m), f(b));
    let whole = (b - a) / 6.0 * (fa + 4.0 * fm + fb);
    step(f, (a, fa), (m, fm), (b, fb), whole, tolerance, 30)
}

/// The exponential law (the Delta seed's §III.6.2.3, Biagiotti & Melchiorri §2.3): velocity
/// v_c exp(−σ f(τ', λ)), f = (2τ')²/|1 − (2τ')²|^λ, τ' = τ − 1/2. With g = 4τ(1 − τ) the
/// profile's rate is r/R, r = exp(−σ (1 − g) g^−λ), and its acceleration r'/R with
/// r' = r σ g' g^(−λ−1) (g + λ (1 − g)), g' = 4 − 8τ: the drive's rate and acceleration against
/// these closed forms, its position (a quadrature node) against adaptive Simpson on r.
#[test]
fn the_exponential_laws_rate_and_acceleration_are_exact_and_its_position_the_quadrature() {
    for (sigma, lambda) in [(7.1, 0.5), (1.0, 0.2), (30.0, 2.0), (3.0, 1.0)] {
        let rate = move |u: f64| {
            let g = 4.0 * u * (1.0 - u);
            match g <= 0.0 {
                true => 0.0,
                false => (-sigma * (1.0 - g) / g.powf(lambda)).exp(),
            }
        };
        let total = adaptive_simpson(&rate, 0.0, 1.0, 1e-15);
        let profile = move |u: f64| {
            let g = 4.0 * u * (1.0 - u);
            let r = rate(u);
            let slope = match g <= 0.0 {
                true => 0.0,
                false => {
                    r * sigma * (4.0 - 8.0 * u) * g.powf(-lambda - 1.0) * (g + lambda * (1.0 - g))
                }
            };
            [
                adaptive_simpson(&rate, 0.0, u, 1e-15) / total,
                r / total,
                slope / total,
            ]
        };
        // Each derivative relative to the law's largest (the acceleration of a steep law, σ = 30,
        // is 60 times h/T²): round-off is relative to the values computed.
        let all = times(&[]);
        let closed = between(profile);
        let largest: Vec<Triple> = all.iter().map(|&t| closed(t)).collect();
        let scales: Triple = std::array::from_fn(|k| {
            (largest.iter().map(|v| v[k].abs())).fold(Q0.abs().max(Q1.abs()), f64::max)
        });
        let law = call("exponential", &format!(", {sigma}, {lambda}"));
        let worst = worst_error_on(&law, &all, closed, scales);
        println!("exponential σ = {sigma}, λ = {lambda}: worst relative error {worst:.1e}");
    }
}
