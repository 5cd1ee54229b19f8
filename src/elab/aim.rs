//! `aim(u)` and `aim(u, v)`: the rotation that turns a frame's z axis to the direction of `u`
//! (and, with `v`, its x axis toward the part of `v` orthogonal to `u`).
//!
//! Written as `acos(dot(u, z)) || cross(z, u)`, the minimal rotation has no axis at u = ±z. Here
//! it is the chain `Rz(φ) · Ry(θ) · Rz(−φ)` of rotations about the frame's own axes, with
//! φ = atan2(u_y, u_x) the azimuth of u and θ = atan2(√(u_x² + u_y²), u_z) its angle from z: the
//! rotation by θ about Rz(φ)·y, which is along z × u, so the same minimal rotation, and every
//! step is defined at u = ±z (θ = 0 or π, φ = atan2(0, ±0) = 0 or ±π). Its rotated z axis is
//! (sin θ cos φ, sin θ sin φ, cos θ) = u / |u| (the spherical angles of u). At u = −z the
//! rotation is the half turn about y (about ±y, the same rotation, whatever the signs of the
//! zeros), a choice: every half turn about an axis of the xy-plane takes z to −z.
//!
//! With `v`, a last turn ψ about the new z axis takes the new x axis toward v: ψ is the azimuth
//! of v in the aimed frame (`R⁻¹ v`), and the whole chain is `Rz(φ) · Ry(θ) · Rz(ψ − φ)`.
//!
//! The arguments are parameters: numbers and unknowns, not coordinates, `time` or the state of
//! frames (E0612). A displacement that moves is written with its coordinates (`q || axis`); the
//! atan2 of an azimuth has no derivative at u = ±z. Numbers are checked where they are written: a
//! zero `u`, or a `v` parallel to `u`, leaves the rotation undefined (E0611). Unknowns are
//! not checked once given: there atan2(0, 0) = 0, so a zero `u` gives the identity and a
//! parallel `v` the x axis of `aim(u)`.

use nalgebra::Vector3;

use super::elaborator::internal;
use super::operations::{as_scalar, as_vector, builtin_call, rotate};
use super::value::*;
use crate::diag::Diagnostic;
use crate::source::Span;

type Result<T> = std::result::Result<T, Diagnostic>;

/// Below this sine of the angle between `u` and `v`, `v` is taken as parallel to `u`: its
/// component orthogonal to `u` would be round-off (a relative 1e-16 for each product), and the
/// x axis it gives would turn with the last digits of the numbers.
const PARALLEL_SINE: f64 = 1e-12;

/// `aim(u)` or `aim(u, v)` with the arguments' values and their spans, for the call at `span`.
pub(super) fn aim(values: Vec<Value>, arg_spans: &[Span], span: Span) -> Result<Value> {
    let mut vectors = Vec::with_capacity(values.len());
    for (value, &arg_span) in values.into_iter().zip(arg_spans) {
        let vector = as_vector(value, arg_span)?;
        refuse_motion(&vector, arg_span)?;
        vectors.push(match numbers(&vector) {
            Some(n) => power_of_two_scaled(n).map(num).into(),
            None => vector,
        });
    }
    let u = vectors
        .first()
        .ok_or_else(|| internal("missing argument"))?;
    if numbers(u).is_some_and(|u| u.norm() == 0.0) {
        return Err(Diagnostic::error("E0611", "`aim` toward a zero vector")
            .primary(arg_spans[0], "this vector has length 0")
            .help("`aim(u)` turns the z axis toward u: give a non-zero direction"));
    }
    let phi = atan2(&u[1], &u[0], span)?;
    let along_z = builtin_call(
        "sqrt",
        vec![Value::Scalar(arith(
            '+',
            &arith('*', &u[0], &u[0]),
            &arith('*', &u[1], &u[1]),
        ))],
        span,
    )?;
    let theta = atan2(&as_scalar(along_z, span)?, &u[2], span)?;
    let spin = match vectors.get(1) {
        None => num(0.0),
        Some(v) => {
            if let (Some(u), Some(v)) = (numbers(u), numbers(v)) {
                if u.cross(&v).norm() <= PARALLEL_SINE * u.norm() * v.norm() {
                    return Err(Diagnostic::error(
                        "E0611",
                        "`aim(u, v)` with v parallel to u",
                    )
                    .primary(arg_spans[1], "parallel to the first direction (or zero)")
                    .secondary(arg_spans[0], "the direction of z")
                    .help("the x axis turns toward the part of v orthogonal to u: give a v that is not along u"));
                }
            }
            // v in the frame `aim(u)` gives, through the inverse chain Rz(φ) · Ry(−θ) · Rz(−φ).
            let inverse = Displacement(vec![
                about_z(phi.clone()),
                about_y(negate(&theta)),
                about_z(negate(&phi)),
            ]);
            let seen = rotate(&inverse, v.clone());
            atan2(&seen[1], &seen[0], span)?
        }
    };
    Ok(Value::Rotation(Displacement(vec![
        about_z(phi.clone()),
        about_y(theta),
        about_z(arith('-', &spin, &phi)),
    ])))
}

/// Refuses an argument that changes during a motion, at the place it is written.
fn refuse_motion(vector: &Vector, span: Span) -> Result<()> {
    if !vector.iter().any(|s| s.varies_with_motion()) {
        return Ok(());
    }
    Err(Diagnostic::error("E0612", "`aim` of a direction that moves")
        .primary(span, "depends on a coordinate, `time` or the state of a frame")
        .help("`aim` is for fixed geometry (numbers and unknowns); write a moving rotation with its coordinates, `q || axis`"))
}

fn about_z(angle: Scalar) -> Elementary {
    Elementary::Rotation {
        angle,
        axis: [num(0.0), num(0.0), num(1.0)],
    }
}

fn about_y(angle: Scalar) -> Elementary {
    Elementary::Rotation {
        angle,
        axis: [num(0.0), num(1.0), num(0.0)],
    }
}

/// `atan2(y, x)`, folded on numbers like the builtin.
fn atan2(y: &Scalar, x: &Scalar, span: Span) -> Result<Scalar> {
    let value = builtin_call(
        "atan2",
        vec![Value::Scalar(y.clone()), Value::Scalar(x.clone())],
        span,
    )?;
    as_scalar(value, span)
}

/// A direction of numbers scaled by a power of two, exactly, to bring its largest component into
/// [1, 2): its squares neither overflow nor vanish, so `[1e200, 0, 1e200]` and
/// `[1e-200, 0, 1e-200]` aim like `[1, 0, 1]`.
fn power_of_two_scaled(v: Vector3<f64>) -> Vector3<f64> {
    let largest = v.amax();
    if largest == 0.0 || !largest.is_finite() {
        return v;
    }
    let exponent = largest.log2().floor() as i32;
    // In two factors: 2^1074, for the smallest subnormals, is not a double.
    let half = -exponent / 2;
    v * 2f64.powi(half) * 2f64.powi(-exponent - half)
}

/// The components of a vector of numbers.
fn numbers(v: &Vector) -> Option<Vector3<f64>> {
    Some(Vector3::new(
        constant(&v[0])?,
        constant(&v[1])?,
        constant(&v[2])?,
    ))
}
