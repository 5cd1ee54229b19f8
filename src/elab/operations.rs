//! Operations on values: coercions (the literal `0` as a zero vector, a body as its frame…),
//! arithmetic on scalars, vectors and matrices, rotations applied to vectors, and the built-in
//! functions, folded to numbers when their arguments are numbers.

use std::sync::Arc;

use super::elaborator::internal;
use super::value::*;
use crate::diag::Diagnostic;
use crate::source::Span;
use crate::syntax::ast::BinaryOp;

type Result<T> = std::result::Result<T, Diagnostic>;

pub(super) fn as_scalar(value: Value, span: Span) -> Result<Scalar> {
    match value {
        Value::Scalar(s) => Ok(s),
        Value::Zero => Ok(num(0.0)),
        Value::One => Ok(num(1.0)),
        _ => Err(internal(format!("expected a scalar at {span:?}"))),
    }
}

pub(super) fn as_vector(value: Value, span: Span) -> Result<Vector> {
    match value {
        Value::Vector(v) => Ok(v),
        Value::Zero => Ok(zero_vector()),
        _ => Err(internal(format!("expected a vector at {span:?}"))),
    }
}

pub(super) fn as_join(value: Value, span: Span) -> Result<JoinId> {
    match value {
        Value::Join(id) => Ok(id),
        _ => Err(internal(format!("expected a join at {span:?}"))),
    }
}

pub(super) fn as_displacement(value: Value, span: Span) -> Result<Displacement> {
    match value {
        Value::Displacement(d) | Value::Rotation(d) => Ok(d),
        Value::Vector(t) => Ok(Displacement(vec![Elementary::Translation(t)])),
        Value::Zero | Value::One => Ok(Displacement::default()),
        _ => Err(internal(format!("expected a displacement at {span:?}"))),
    }
}

pub(super) fn as_rotation(value: Value, span: Span) -> Result<Displacement> {
    match value {
        Value::Rotation(d) => Ok(d),
        Value::One => Ok(Displacement::default()),
        _ => Err(internal(format!("expected a rotation at {span:?}"))),
    }
}

pub(super) fn as_frame(value: Value, span: Span) -> Result<Frame> {
    match value {
        Value::Frame(f) => Ok(f),
        Value::Body(body) => Ok(Frame {
            body,
            displacement: Displacement::default(),
        }),
        _ => Err(internal(format!("expected a frame at {span:?}"))),
    }
}

pub(super) fn vector_or_matrix(values: Vec<Value>, span: Span) -> Result<Value> {
    if values
        .iter()
        .all(|v| matches!(v, Value::Scalar(_) | Value::Zero | Value::One))
    {
        let scalars = values
            .into_iter()
            .map(|v| as_scalar(v, span))
            .collect::<Result<Vec<_>>>()?;
        let vector: Vector = scalars
            .try_into()
            .map_err(|_| internal("vector of the wrong size"))?;
        return Ok(Value::Vector(vector));
    }
    let rows = values
        .into_iter()
        .map(|v| as_vector(v, span))
        .collect::<Result<Vec<_>>>()?;
    let matrix: Matrix = rows
        .try_into()
        .map_err(|_| internal("matrix of the wrong size"))?;
    Ok(Value::Matrix(Box::new(matrix)))
}

pub(super) fn binary(op: BinaryOp, left: Value, right: Value, span: Span) -> Result<Value> {
    match op {
        BinaryOp::Rotation => {
            let angle = as_scalar(left, span)?;
            let axis = as_vector(right, span)?;
            Ok(Value::Rotation(Displacement(vec![Elementary::Rotation {
                angle,
                axis,
            }])))
        }
        BinaryOp::Displacement => {
            let translation = as_vector(left, span)?;
            let rotation = as_rotation(right, span)?;
            Ok(Value::Displacement(
                Displacement(vec![Elementary::Translation(translation)]).then(&rotation),
            ))
        }
        BinaryOp::Frame => {
            let displacement = as_displacement(left, span)?;
            let base = as_frame(right, span)?;
            Ok(Value::Frame(Frame {
                body: base.body,
                displacement: base.displacement.then(&displacement),
            }))
        }
        _ => arithmetic(op, left, right, span),
    }
}

fn symbol(op: BinaryOp) -> char {
    match op {
        BinaryOp::Add => '+',
        BinaryOp::Sub => '-',
        BinaryOp::Mul => '*',
        BinaryOp::Div => '/',
        _ => '^',
    }
}

fn arithmetic(op: BinaryOp, left: Value, right: Value, span: Span) -> Result<Value> {
    use Value::*;
    let c = symbol(op);
    Ok(match (left, right) {
        (Zero, Vector(v)) | (Vector(v), Zero) if matches!(op, BinaryOp::Add) => Vector(v),
        (Vector(v), Zero) if matches!(op, BinaryOp::Sub) => Vector(v),
        (Zero, Vector(v)) if matches!(op, BinaryOp::Sub) => Vector(v.map(|s| negate(&s))),
        (Vector(a), Vector(b)) => Vector([0, 1, 2].map(|i| arith(c, &a[i], &b[i]))),
        (Matrix(a), Matrix(b)) if matches!(op, BinaryOp::Add | BinaryOp::Sub) => Matrix(Box::new(
            [0, 1, 2].map(|i| [0, 1, 2].map(|j| arith(c, &a[i][j], &b[i][j]))),
        )),
        (Matrix(a), Matrix(b)) => Matrix(Box::new([0, 1, 2].map(|i| {
            [0, 1, 2].map(|j| dot_row(&a[i], &[b[0][j].clone(), b[1][j].clone(), b[2][j].clone()]))
        }))),
        (Matrix(a), Vector(v)) => Vector([0, 1, 2].map(|i| dot_row(&a[i], &v))),
        (Rotation(a), Rotation(b)) => Rotation(a.then(&b)),
        (Rotation(r), Vector(v)) => Vector(rotate(&r, v)),
        (
            a @ (Displacement(_) | Rotation(_) | Vector(_)),
            b @ (Displacement(_) | Rotation(_) | Vector(_)),
        ) => Displacement(as_displacement(a, span)?.then(&as_displacement(b, span)?)),
        (Vector(v), s) => {
            let s = as_scalar(s, span)?;
            Vector(v.map(|x| arith(c, &x, &s)))
        }
        (s, Vector(v)) => {
            let s = as_scalar(s, span)?;
            Vector(v.map(|x| arith(c, &s, &x)))
        }
        (Matrix(m), s) => {
            let s = as_scalar(s, span)?;
            Matrix(Box::new((*m).map(|row| row.map(|x| arith(c, &x, &s)))))
        }
        (s, Matrix(m)) => {
            let s = as_scalar(s, span)?;
            Matrix(Box::new((*m).map(|row| row.map(|x| arith(c, &s, &x)))))
        }
        (a, b) => Scalar(arith(c, &as_scalar(a, span)?, &as_scalar(b, span)?)),
    })
}

/// Applies a rotation chain to a vector (Rodrigues' formula, symbolic).
pub(super) fn rotate(rotation: &Displacement, v: Vector) -> Vector {
    rotation.0.iter().rev().fold(v, |v, step| match step {
        Elementary::Rotation { angle, axis } => rotate_about(angle, axis, &v),
        Elementary::Translation(_) => v,
    })
}

fn rotate_about(angle: &Scalar, axis: &Vector, v: &Vector) -> Vector {
    let length = builtin_scalar("sqrt", &dot_row(axis, axis));
    let k = axis.clone().map(|c| arith('/', &c, &length));
    let (c, s) = (builtin_scalar("cos", angle), builtin_scalar("sin", angle));
    let k_cross_v = cross(&k, v);
    let k_dot_v = dot_row(&k, v);
    let one_minus_c = arith('-', &num(1.0), &c);
    [0, 1, 2].map(|i| {
        let along = arith('*', &arith('*', &k[i], &k_dot_v), &one_minus_c);
        arith(
            '+',
            &arith('+', &arith('*', &v[i], &c), &arith('*', &k_cross_v[i], &s)),
            &along,
        )
    })
}

pub(super) fn builtin_scalar(name: &'static str, x: &Scalar) -> Scalar {
    match fold_builtin(name, std::slice::from_ref(x)) {
        Some(v) => num(v),
        None => Arc::new(SExpr::call(name, vec![x.clone()])),
    }
}

fn cross(a: &Vector, b: &Vector) -> Vector {
    let term =
        |i: usize, j: usize| arith('-', &arith('*', &a[i], &b[j]), &arith('*', &a[j], &b[i]));
    [term(1, 2), term(2, 0), term(0, 1)]
}

fn dot_row(a: &Vector, b: &Vector) -> Scalar {
    let products: Vec<Scalar> = (0..3).map(|i| arith('*', &a[i], &b[i])).collect();
    arith('+', &arith('+', &products[0], &products[1]), &products[2])
}

pub(super) fn builtin_call(name: &str, values: Vec<Value>, span: Span) -> Result<Value> {
    let static_name: &'static str = crate::syntax::names::BUILTIN_NAMES
        .iter()
        .find(|n| **n == name)
        .copied()
        .ok_or_else(|| internal(format!("unknown builtin `{name}`")))?;
    match name {
        "position" | "velocity" | "angular_velocity" | "orientation" | "distance" => {
            frame_state(name, values, span)
        }
        "norm" | "dot" | "cross" => {
            let vectors = values
                .into_iter()
                .map(|v| as_vector(v, span))
                .collect::<Result<Vec<_>>>()?;
            let a = vectors
                .first()
                .ok_or_else(|| internal("missing argument"))?;
            Ok(match name {
                "norm" => Value::Scalar(builtin_scalar("sqrt", &dot_row(a, a))),
                "dot" => Value::Scalar(dot_row(
                    a,
                    vectors.get(1).ok_or_else(|| internal("missing argument"))?,
                )),
                _ => Value::Vector(cross(
                    a,
                    vectors.get(1).ok_or_else(|| internal("missing argument"))?,
                )),
            })
        }
        "mod" => {
            let mut args = values.into_iter().map(|v| as_scalar(v, span));
            let missing = || internal("missing argument");
            let a = args.next().ok_or_else(missing)??;
            let b = args.next().ok_or_else(missing)??;
            Ok(Value::Scalar(floored_modulo(&a, &b)))
        }
        _ => {
            let args = values
                .into_iter()
                .map(|v| as_scalar(v, span))
                .collect::<Result<Vec<_>>>()?;
            if let Some(folded) = fold_builtin(name, &args) {
                return Ok(Value::Scalar(num(folded)));
            }
            Ok(Value::Scalar(Arc::new(SExpr::call(static_name, args))))
        }
    }
}

/// `mod(a, b)`, the floored modulo `a − b·floor(a / b)` (Knuth, TAOCP vol. 1, §1.2.4): its sign
/// is the divisor's, so `mod(-1, 3)` is 2, the index that wraps around an array. Written with
/// `floor` so that every emitter and evaluator has it without a function of its own.
fn floored_modulo(a: &Scalar, b: &Scalar) -> Scalar {
    let quotient = builtin_scalar("floor", &arith('/', a, b));
    arith('-', a, &arith('*', b, &quotient))
}

/// `position(F)`, `velocity(F)`, `angular_velocity(F)`, `orientation(F)`, `distance(A, B)`: the
/// state of frames at the current instant, in the fixed axes, as components to evaluate then.
fn frame_state(name: &str, values: Vec<Value>, span: Span) -> Result<Value> {
    let frames = values
        .into_iter()
        .map(|v| as_frame(v, span).map(Arc::new))
        .collect::<Result<Vec<_>>>()?;
    let frame = frames.first().ok_or_else(|| internal("missing argument"))?;
    let component = |frame: &Arc<Frame>, quantity: FrameQuantity| {
        Arc::new(SExpr::FrameState(frame.clone(), quantity))
    };
    let vector = |frame: &Arc<Frame>, make: fn(u8) -> FrameQuantity| -> Vector {
        [0, 1, 2].map(|i| component(frame, make(i)))
    };
    Ok(match name {
        "position" => Value::Vector(vector(frame, FrameQuantity::Position)),
        "velocity" => Value::Vector(vector(frame, FrameQuantity::Velocity)),
        "angular_velocity" => Value::Vector(vector(frame, FrameQuantity::AngularVelocity)),
        "orientation" => {
            Value::Matrix(Box::new([0u8, 1, 2].map(|i| {
                [0u8, 1, 2].map(|j| component(frame, FrameQuantity::Orientation(i, j)))
            })))
        }
        _ => {
            let other = frames.get(1).ok_or_else(|| internal("missing argument"))?;
            let (a, b) = (
                vector(frame, FrameQuantity::Position),
                vector(other, FrameQuantity::Position),
            );
            let gap: Vector = [0, 1, 2].map(|i| arith('-', &b[i], &a[i]));
            Value::Scalar(builtin_scalar("sqrt", &dot_row(&gap, &gap)))
        }
    })
}

/// Evaluates a built-in function on numbers (`sin(pi/2)` is the number 1).
fn fold_builtin(name: &str, args: &[Scalar]) -> Option<f64> {
    let x = constant(args.first()?)?;
    let value = match name {
        "sin" => x.sin(),
        "cos" => x.cos(),
        "tan" => x.tan(),
        "asin" => x.asin(),
        "acos" => x.acos(),
        "atan" => x.atan(),
        "sqrt" => x.sqrt(),
        "exp" => x.exp(),
        "log" => x.ln(),
        "abs" => x.abs(),
        "floor" => x.floor(),
        "atan2" => x.atan2(constant(args.get(1)?)?),
        _ => return None,
    };
    value.is_finite().then_some(value)
}

/// A number literal too large for a double (`1e309`): refused where it is written.
pub(super) fn finite_literal(x: f64, span: Span) -> Result<f64> {
    if x.is_finite() {
        return Ok(x);
    }
    Err(Diagnostic::error("E0606", "this number is too large")
        .primary(span, "larger than 1.8e308, the largest finite number")
        .help("write a finite number; constant parts of a program must be finite"))
}

/// Refuses the axis of a rotation `angle || axis` whose value is known and has length 0
/// (`[0, 0, 0]`, `0`, or components so small that their squares vanish): such a rotation
/// turns about nothing. An axis that depends on unknowns is checked once they have values.
pub(super) fn check_axis(axis: &Value, span: Span) -> Result<()> {
    let components = match axis {
        Value::Zero => Some([0.0; 3]),
        Value::Vector(v) => (|| Some([constant(&v[0])?, constant(&v[1])?, constant(&v[2])?]))(),
        _ => None,
    };
    let Some(components) = components else {
        return Ok(());
    };
    if components.iter().map(|c| c * c).sum::<f64>().sqrt() != 0.0 {
        return Ok(());
    }
    Err(Diagnostic::error("E0609", "a rotation about a zero axis")
        .primary(span, "this axis has length 0")
        .help("`angle || axis` turns about a non-zero vector, such as `[0, 0, 1]`"))
}

/// Whether a value is the number 0 (or a vector of them), as a divisor.
pub(super) fn is_zero(value: &Value) -> bool {
    let zero = |s: &Scalar| constant(s) == Some(0.0);
    match value {
        Value::Zero => true,
        Value::Scalar(s) => zero(s),
        Value::Vector(v) => v.iter().any(zero),
        _ => false,
    }
}

/// The built-in functions folded on numbers by [`fold_builtin`].
const FOLDED: [&str; 12] = [
    "sin", "cos", "tan", "asin", "acos", "atan", "sqrt", "exp", "log", "abs", "atan2", "floor",
];

/// Whether a scalar is an operation on numbers that folding left alone because its result is
/// not a finite number (`1/0`, `0/0`, `log(0)`, `1e200 * 1e200`).
fn undefined(s: &Scalar) -> bool {
    match &**s {
        SExpr::Add(a, b)
        | SExpr::Sub(a, b)
        | SExpr::Mul(a, b)
        | SExpr::Div(a, b)
        | SExpr::Pow(a, b) => constant(a).is_some() && constant(b).is_some(),
        SExpr::Call(call) => {
            let args = &call.args;
            FOLDED.contains(&call.function)
                && !args.is_empty()
                && args.iter().all(|a| constant(a).is_some())
        }
        _ => false,
    }
}

/// Refuses the value of an operation (`operator`: a binary one, and whether its divisor is 0)
/// or of a call when its constant parts have no finite value, at the place it is written.
pub(super) fn check_finite(
    value: &Value,
    operator: Option<(BinaryOp, bool)>,
    span: Span,
) -> Result<()> {
    let bad = match value {
        Value::Scalar(s) => undefined(s),
        Value::Vector(v) => v.iter().any(undefined),
        Value::Matrix(m) => m.iter().flatten().any(undefined),
        _ => false,
    };
    if !bad {
        return Ok(());
    }
    Err(match operator {
        Some((BinaryOp::Div, true)) => Diagnostic::error("E0607", "division by zero")
            .primary(span, "the divisor of this constant is 0")
            .help("constant parts of a program must be finite numbers: check the divisor"),
        Some((op, _)) => Diagnostic::error(
            "E0607",
            format!("`{}` on these numbers has no finite value", op.symbol()),
        )
        .primary(span, "this is not a finite number")
        .help("constant parts of a program must be finite numbers"),
        None => Diagnostic::error("E0607", "this function has no finite value here")
            .primary(span, "not a finite number (outside the function's domain)")
            .help("constant parts of a program must be finite numbers: check the argument"),
    })
}
