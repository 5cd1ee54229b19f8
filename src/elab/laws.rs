//! The reference laws of time (`quintic(time, t0, q0, t1, q1)`, …, `spline(time, t0, q0, t1, q1,
//! ...)`), written as program scalars with `select` (see `piecewise`), and `derivative(law)`.
//!
//! A law between two rests is q0 + (q1 − q0) s(τ) with τ = (t − t0)/(t1 − t0) and s a normalised
//! profile from s(0) = 0 to s(1) = 1 (Biagiotti & Melchiorri, *Trajectory Planning for Automatic
//! Machines and Robots*, 2008, ch. 2: the Delta seed's reference [2]); before t0 it is q0 and
//! from t1 on q1. Being expressions, the laws are differentiated exactly where they are used
//! (drives differentiate their law twice, `derivative` once). The positions are scalars (a
//! joint's law) or vectors (a point moving on the segment between two points).

use super::elaborator::internal;
use super::operations::{as_scalar, as_vector, builtin_scalar};
use super::piecewise::{select, shown};
use super::value::{arith, constant, num, Scalar, Value};
use crate::check::types::{reference_law, LawArguments};
use crate::diag::Diagnostic;
use crate::source::Span;

type Result<T> = std::result::Result<T, Diagnostic>;

/// A law's positions: one component for a joint, three for a point.
type Positions = Vec<Scalar>;

/// The value of a call of the reference law `name`; `spans` are its arguments'.
pub(super) fn law(name: &str, values: Vec<Value>, spans: &[Span], span: Span) -> Result<Value> {
    let vector = values.iter().any(|v| matches!(v, Value::Vector(_)));
    let arguments = reference_law(name).ok_or_else(|| internal(format!("`{name}` is no law")))?;
    let mut scalars: Vec<Scalar> = Vec::new();
    let mut positions: Vec<Positions> = Vec::new();
    for (k, value) in values.into_iter().enumerate() {
        match (arguments.is_position(k), vector) {
            (true, true) => positions.push(as_vector(value, span)?.to_vec()),
            (true, false) => positions.push(vec![as_scalar(value, span)?]),
            (false, _) => scalars.push(as_scalar(value, span)?),
        }
    }
    let time = &scalars[0];
    let components = match arguments {
        LawArguments::Through => through(time, &scalars[1..], &positions, spans)?,
        LawArguments::Between(_) => {
            let (t0, t1) = (&scalars[1], &scalars[2]);
            let duration = arith('-', t1, t0);
            if let Some(d) = constant(&duration).filter(|d| *d <= 0.0) {
                return Err(Diagnostic::error(
                    "E0650",
                    format!(
                        "`{name}` from t0 = {} to t1 = {}: a law lasts a positive time",
                        shown_scalar(t0),
                        shown_scalar(t1)
                    ),
                )
                .primary(
                    spans[3],
                    if d == 0.0 {
                        "the end is the start"
                    } else {
                        "the end is before the start"
                    },
                )
                .secondary(spans[1], "the start")
                .help(format!("write `{name}(time, t0, q0, t1, q1)` with t1 > t0")));
            }
            let tau = arith('/', &arith('-', time, t0), &duration);
            let profile = profile(name, &tau, &scalars[3..], &duration, spans)?;
            let (start, end) = (&positions[0], &positions[1]);
            (start.iter().zip(end))
                .map(|(q0, q1)| {
                    let moving = arith('+', q0, &arith('*', &arith('-', q1, q0), &profile));
                    let started = select(&arith('-', time, t0), &moving, q0);
                    select(&arith('-', time, t1), q1, &started)
                })
                .collect()
        }
    };
    Ok(match vector {
        true => Value::Vector([0, 1, 2].map(|i| components[i].clone())),
        false => Value::Scalar(components[0].clone()),
    })
}

/// The normalised profile s(τ) of a law between rests, for 0 ≤ τ < 1 (Biagiotti & Melchiorri
/// §2.1–2.2, §3.2 for the trapezoid); `extra` are the law's parameters after its ends.
fn profile(
    name: &str,
    tau: &Scalar,
    extra: &[Scalar],
    duration: &Scalar,
    spans: &[Span],
) -> Result<Scalar> {
    let n = |x: f64| num(x);
    let (add, sub, mul) = (
        |a: &Scalar, b: &Scalar| arith('+', a, b),
        |a: &Scalar, b: &Scalar| arith('-', a, b),
        |a: &Scalar, b: &Scalar| arith('*', a, b),
    );
    let pi = std::f64::consts::PI;
    let square = |a: &Scalar| mul(a, a);
    Ok(match name {
        // Constant velocity: its velocity jumps at both ends.
        "linear" => tau.clone(),
        // Constant acceleration then deceleration, each for half the time: s = 2τ² then
        // 1 − 2(1 − τ)²; its acceleration jumps at the start, the middle and the end.
        "parabolic" => {
            let rising = mul(&n(2.0), &square(tau));
            let falling = sub(&n(1.0), &mul(&n(2.0), &square(&sub(&n(1.0), tau))));
            select(&sub(tau, &n(0.5)), &falling, &rising)
        }
        // 3τ² − 2τ³: velocity 0 at both ends, acceleration jumps there.
        "cubic" => mul(&square(tau), &sub(&n(3.0), &mul(&n(2.0), tau))),
        // 10τ³ − 15τ⁴ + 6τ⁵: velocity and acceleration 0 at both ends.
        "quintic" => {
            let inner = add(&n(10.0), &mul(tau, &sub(&mul(&n(6.0), tau), &n(15.0))));
            mul(&mul(&square(tau), tau), &inner)
        }
        // (1 − cos πτ)/2: acceleration proportional to the displacement from the middle.
        "harmonic" => {
            let cosine = builtin_scalar("cos", &mul(&n(pi), tau));
            mul(&n(0.5), &sub(&n(1.0), &cosine))
        }
        // τ − sin(2πτ)/(2π): velocity and acceleration 0 at both ends.
        "cycloidal" => {
            let sine = builtin_scalar("sin", &mul(&n(2.0 * pi), tau));
            sub(tau, &arith('/', &sine, &n(2.0 * pi)))
        }
        "trapezoidal" => trapezoid(tau, &extra[0], duration, spans[5])?,
        "exponential" => exponential(tau, &extra[0], &extra[1], [spans[5], spans[6]])?,
        _ => return Err(internal(format!("no profile for `{name}`"))),
    })
}

/// The trapezoidal velocity profile: constant acceleration during `ramp` (α = ramp / duration
/// of the normalised time), constant velocity v = 1/(1 − α), constant deceleration during
/// `ramp`; with α = 1/2 the velocity is a triangle. s = vτ²/(2α), then v(τ − α/2), then
/// 1 − v(1 − τ)²/(2α).
fn trapezoid(tau: &Scalar, ramp: &Scalar, duration: &Scalar, ramp_span: Span) -> Result<Scalar> {
    if let (Some(r), Some(d)) = (constant(ramp), constant(duration)) {
        if !(r > 0.0 && 2.0 * r <= d) {
            return Err(Diagnostic::error(
                "E0650",
                format!("`trapezoidal` with a ramp of {} over a duration of {}: each ramp lasts more than 0 and at most half the duration", shown(r), shown(d)),
            )
            .primary(ramp_span, "the time to accelerate")
            .help("the ramp is the time of the acceleration (and of the deceleration): 0 < ramp ≤ (t1 - t0)/2"));
        }
    }
    let n = |x: f64| num(x);
    let alpha = arith('/', ramp, duration);
    let velocity = arith('/', &n(1.0), &arith('-', &n(1.0), &alpha));
    let half_acceleration = arith('/', &velocity, &arith('*', &n(2.0), &alpha));
    let accelerating = arith('*', &half_acceleration, &arith('*', tau, tau));
    let cruising = arith(
        '*',
        &velocity,
        &arith('-', tau, &arith('/', &alpha, &n(2.0))),
    );
    let left = arith('-', &n(1.0), tau);
    let decelerating = arith(
        '-',
        &n(1.0),
        &arith('*', &half_acceleration, &arith('*', &left, &left)),
    );
    let braking = arith('-', tau, &arith('-', &n(1.0), &alpha));
    let cruising_or_accelerating = select(&arith('-', tau, &alpha), &cruising, &accelerating);
    Ok(select(&braking, &decelerating, &cruising_or_accelerating))
}

/// The exponential law's profile (the Delta seed's, Biagiotti & Melchiorri §2.3): its velocity
/// is v_c exp(−σ (2τ')²/|1 − (2τ')²|^λ) with τ' = τ − 1/2, its position a quadrature node of
/// the pool (`symbolic::exponential_profile`). σ and λ are numbers (they decide the
/// normalisation, computed once), both positive (E0650): with λ = 0 the velocity would not
/// vanish at the ends, with σ ≤ 0 it would not be a law between rests.
fn exponential(tau: &Scalar, sigma: &Scalar, lambda: &Scalar, spans: [Span; 2]) -> Result<Scalar> {
    for (value, span, name) in [(sigma, spans[0], "σ"), (lambda, spans[1], "λ")] {
        match constant(value) {
            Some(v) if v > 0.0 && v.is_finite() => {}
            Some(v) => {
                return Err(Diagnostic::error(
                    "E0650",
                    format!("`exponential` with {name} = {}: σ and λ are positive", shown(v)),
                )
                .primary(span, "not positive")
                .help("the velocity v_c exp(-σ (2τ')²/|1 - (2τ')²|^λ) vanishes at both ends when σ > 0 and λ > 0"))
            }
            None => {
                return Err(Diagnostic::error(
                    "E0650",
                    format!("the {name} of an `exponential` law must be a number"),
                )
                .primary(span, "not a number")
                .help("write σ and λ with numbers and constants: they decide the law's normalisation, computed once"))
            }
        }
    }
    Ok(std::sync::Arc::new(super::value::SExpr::call(
        "exponential_profile",
        vec![tau.clone(), sigma.clone(), lambda.clone()],
    )))
}

/// The cubic spline through via points (t_k, q_k) at rest at both ends: continuous position,
/// velocity and acceleration (Biagiotti & Melchiorri §4.4.1). The velocities v_k at the inner
/// points solve the tridiagonal system of the acceleration's continuity,
/// T_k v_{k−1} + 2(T_{k−1} + T_k) v_k + T_{k−1} v_{k+1} = 3 (T_k Δ_{k−1}/T_{k−1} + T_{k−1} Δ_k/T_k),
/// with T_k = t_{k+1} − t_k and Δ_k = q_{k+1} − q_k, v_0 = v_n = 0, by Thomas's elimination;
/// each segment is then the cubic of its ends' positions and velocities. The times are numbers,
/// increasing (E0651); the positions may be any scalars, whose combinations the system gives.
fn through(
    time: &Scalar,
    times: &[Scalar],
    positions: &[Positions],
    spans: &[Span],
) -> Result<Vec<Scalar>> {
    let span_of_time = |k: usize| spans[1 + 2 * k];
    let mut knots = Vec::with_capacity(times.len());
    for (k, t) in times.iter().enumerate() {
        let Some(value) = constant(t) else {
            return Err(Diagnostic::error(
                "E0651",
                "the times of a spline's via points must be numbers",
            )
            .primary(span_of_time(k), "not a number")
            .help("write the times with numbers and constants: they decide the spline's pieces"));
        };
        if let Some(&previous) = knots.last() {
            if value <= previous {
                return Err(Diagnostic::error(
                    "E0651",
                    format!("the via points of a spline must be in increasing time: {} comes after {}", shown(value), shown(previous)),
                )
                .primary(span_of_time(k), "not after the previous time")
                .secondary(span_of_time(k - 1), "the previous time")
                .help("list the via points in the order the motion passes them, each time later than the one before"));
            }
        }
        knots.push(value);
    }
    let components = positions[0].len();
    Ok((0..components)
        .map(|c| {
            let q: Vec<Scalar> = positions.iter().map(|p| p[c].clone()).collect();
            spline_component(time, &knots, &q)
        })
        .collect())
}

/// One component of the spline through (knots[k], q[k]).
fn spline_component(time: &Scalar, knots: &[f64], q: &[Scalar]) -> Scalar {
    let n = knots.len() - 1;
    let lengths: Vec<f64> = knots.windows(2).map(|w| w[1] - w[0]).collect();
    let steps: Vec<Scalar> = q.windows(2).map(|w| arith('-', &w[1], &w[0])).collect();
    let scaled = |c: f64, s: &Scalar| arith('*', &num(c), s);
    // Thomas's elimination on the inner velocities v_1 … v_{n−1}.
    let mut upper = vec![0.0; n];
    let mut right: Vec<Scalar> = vec![num(0.0); n];
    for k in 1..n {
        let (before, after) = (lengths[k - 1], lengths[k]);
        let rhs = arith(
            '+',
            &scaled(3.0 * after / before, &steps[k - 1]),
            &scaled(3.0 * before / after, &steps[k]),
        );
        let pivot = 2.0 * (before + after) - after * upper[k - 1];
        upper[k] = before / pivot;
        right[k] = arith(
            '/',
            &arith('-', &rhs, &scaled(after, &right[k - 1])),
            &num(pivot),
        );
    }
    let mut velocities: Vec<Scalar> = vec![num(0.0); n + 1];
    for k in (1..n).rev() {
        velocities[k] = arith('-', &right[k], &scaled(upper[k], &velocities[k + 1]));
    }
    // The pieces, nested from the first: q_0 before t_0, the cubic of segment k from t_k.
    let mut law = q[0].clone();
    for k in 0..n {
        let h = lengths[k];
        let (v0, v1) = (&velocities[k], &velocities[k + 1]);
        let slope = scaled(1.0 / h, &steps[k]);
        // a2 = (3Δ/T − 2v_k − v_{k+1})/T, a3 = (−2Δ/T + v_k + v_{k+1})/T².
        let a2 = scaled(
            1.0 / h,
            &arith('-', &arith('-', &scaled(3.0, &slope), &scaled(2.0, v0)), v1),
        );
        let a3 = scaled(
            1.0 / (h * h),
            &arith('+', &arith('-', v0, &scaled(2.0, &slope)), v1),
        );
        let s = arith('-', time, &num(knots[k]));
        let horner = arith(
            '+',
            v0,
            &arith('*', &s, &arith('+', &a2, &arith('*', &s, &a3))),
        );
        let piece = arith('+', &q[k], &arith('*', &s, &horner));
        law = select(&s, &piece, &law);
    }
    select(&arith('-', time, &num(knots[n])), &q[n], &law)
}

/// `derivative(law)`: the time derivative of a law of time (its components for a vector),
/// taken exactly where it is lowered (`symbolic::program`). 0 for a constant; a law that reads
/// the mechanism's state is refused (E0652): its rate is not a function of the time alone.
pub(super) fn derivative(value: Value, argument: Span, span: Span) -> Result<Value> {
    let of = |s: Scalar| -> Result<Scalar> {
        if s.reads_state() {
            return Err(Diagnostic::error("E0652", "`derivative` takes a law of time, and this one reads the mechanism's state")
                .primary(argument, "uses a coordinate, a rate or the state of a frame")
                .help("differentiate laws of `time`, numbers and constants; a coordinate's rate is written `crank.q'`"));
        }
        Ok(match s.varies_with_motion() {
            true => std::sync::Arc::new(super::value::SExpr::call("derivative", vec![s])),
            false => num(0.0),
        })
    };
    Ok(match value {
        Value::Vector(v) => {
            let [x, y, z] = v;
            Value::Vector([of(x)?, of(y)?, of(z)?])
        }
        other => Value::Scalar(of(as_scalar(other, span)?)?),
    })
}

/// A number written back, or the text of an expression.
fn shown_scalar(s: &Scalar) -> String {
    constant(s).map(shown).unwrap_or_else(|| s.to_string())
}
