//! Numeric evaluation of symbolic scalars, with forward-mode derivatives: the value, and the
//! first and second derivatives along a direction of the link's coordinates (a "jet"). The
//! direction is a unit vector for partial derivatives, or the coordinate rates for time
//! derivatives of a motion.

use std::collections::HashMap;

use crate::elab::value::{SExpr, UnknownId};
use crate::symbolic::expr::{ExprId, Function, Pool, Tape};

/// Values of the program's unknowns (written `?s` and generic quantities).
pub type UnknownValues = HashMap<UnknownId, f64>;

#[derive(Clone, Debug, PartialEq)]
pub enum EvalError {
    /// An unknown without a value.
    Missing(UnknownId),
    /// Something that is not a function of the link's coordinates alone (a derivative `x'`,
    /// another join's coordinate, the time): not allowed in geometry.
    NotGeometric(&'static str),
}

/// How messages name an unknown: `` `L` `` (its `let` name), `` `mass(arm)` `` (a generic
/// quantity) or "an unknown `?s`".
pub fn unknown_label(mechanism: &crate::elab::mechanism::Mechanism, id: UnknownId) -> String {
    let unknown = &mechanism.unknowns[id.0 as usize];
    match (&unknown.name, unknown.origin) {
        (Some(name), _) => format!("`{name}`"),
        (None, crate::elab::mechanism::Origin::Written) => "an unknown `?s`".to_string(),
        (None, origin) => format!("`{}`", mechanism.generic_name(origin)),
    }
}

/// A sentence for people about an evaluation error.
pub fn describe(error: &EvalError, mechanism: &crate::elab::mechanism::Mechanism) -> String {
    match error {
        EvalError::Missing(id) => format!("no value for {}", unknown_label(mechanism, *id)),
        EvalError::NotGeometric(what) => format!("it depends on {what}"),
    }
}

/// Lowering a program scalar into the pool: numbers, arithmetic and calls lower alike
/// everywhere; what the leaves (unknowns, coordinates, rates, the time, frames) become depends
/// on the use (constants and symbols of a dof chain, slots of the effort tape).
pub trait Lower {
    fn pool(&mut self) -> &mut Pool;

    /// A scalar that is neither a number, arithmetic nor a call.
    fn leaf(&mut self, s: &SExpr) -> Result<ExprId, EvalError>;

    /// Lowers `s` (override to remember subexpressions already lowered).
    fn lower(&mut self, s: &SExpr) -> Result<ExprId, EvalError> {
        lower_structure(self, s)
    }
}

/// The node of `s`, its operands lowered through `lowering`.
pub fn lower_structure<L: Lower + ?Sized>(
    lowering: &mut L,
    s: &SExpr,
) -> Result<ExprId, EvalError> {
    let binary = |lowering: &mut L, a: &SExpr, b: &SExpr| -> Result<_, EvalError> {
        Ok((lowering.lower(a)?, lowering.lower(b)?))
    };
    Ok(match s {
        SExpr::Num(v) => lowering.pool().constant(*v),
        SExpr::Neg(a) => {
            let a = lowering.lower(a)?;
            lowering.pool().neg(a)
        }
        SExpr::Add(a, b) => {
            let (a, b) = binary(lowering, a, b)?;
            lowering.pool().add(a, b)
        }
        SExpr::Sub(a, b) => {
            let (a, b) = binary(lowering, a, b)?;
            lowering.pool().sub(a, b)
        }
        SExpr::Mul(a, b) => {
            let (a, b) = binary(lowering, a, b)?;
            lowering.pool().mul(a, b)
        }
        SExpr::Div(a, b) => {
            let (a, b) = binary(lowering, a, b)?;
            lowering.pool().div(a, b)
        }
        SExpr::Pow(a, b) => {
            let (a, b) = binary(lowering, a, b)?;
            lowering.pool().pow(a, b)
        }
        SExpr::Call(name, args) => {
            let argument = |k: usize| {
                args.get(k)
                    .ok_or(EvalError::NotGeometric("a call without its arguments"))
            };
            let x = lowering.lower(argument(0)?)?;
            if *name == "atan2" {
                let second = lowering.lower(argument(1)?)?;
                return Ok(lowering.pool().atan2(x, second));
            }
            let function =
                Function::from_name(name).ok_or(EvalError::NotGeometric("an unknown function"))?;
            lowering.pool().apply(function, x)
        }
        leaf => lowering.leaf(leaf)?,
    })
}

/// The leaves of geometry: unknowns are constants (their values are known), the enclosing
/// link's coordinates are `coordinates` (symbols of a dof chain, or none for constants);
/// nothing else may appear.
pub struct Geometric<'a> {
    pub pool: Pool,
    pub unknowns: &'a UnknownValues,
    pub coordinates: Vec<ExprId>,
}

impl Lower for Geometric<'_> {
    fn pool(&mut self) -> &mut Pool {
        &mut self.pool
    }

    fn leaf(&mut self, s: &SExpr) -> Result<ExprId, EvalError> {
        match s {
            SExpr::Unknown(id) => {
                let value = *self.unknowns.get(id).ok_or(EvalError::Missing(*id))?;
                Ok(self.pool.constant(value))
            }
            SExpr::UnknownFunction(id, _) => Err(EvalError::Missing(*id)),
            SExpr::Coordinate { index, order: 0 } => self
                .coordinates
                .get(*index as usize)
                .copied()
                .ok_or(EvalError::NotGeometric("a coordinate of another link")),
            SExpr::Coordinate { order: 1, .. } => Err(EvalError::NotGeometric("a time derivative")),
            SExpr::Coordinate { .. } => Err(EvalError::NotGeometric("a second time derivative")),
            SExpr::JoinCoordinate { .. } => Err(EvalError::NotGeometric("a coordinate of a join")),
            SExpr::Time => Err(EvalError::NotGeometric("the time")),
            _ => Err(EvalError::NotGeometric(
                "the state of a frame (position, velocity, …)",
            )),
        }
    }
}

/// The value of a constant scalar: lowered into a pool, where constants fold (a tape evaluates
/// what does not fold to a finite number, such as `log(0)`).
pub fn eval(s: &SExpr, unknowns: &UnknownValues) -> Result<f64, EvalError> {
    let mut lowering = Geometric {
        pool: Pool::new(),
        unknowns,
        coordinates: Vec::new(),
    };
    let root = lowering.lower(s)?;
    Ok(match lowering.pool.as_constant(root) {
        Some(value) => value,
        None => Tape::new(&lowering.pool, &[root]).eval(&[])[0],
    })
}

/// What a geometric expression may refer to besides numbers and unknowns: the enclosing link's
/// coordinates. (Efforts, which may also use rates, other joins, the time and frames, are
/// compiled into a tape instead: see `dynamics::compiled`.)
#[derive(Clone, Copy, Default)]
pub struct Env<'a> {
    /// The enclosing link's coordinates (`Coordinate { order: 0 }`).
    pub coordinates: &'a [f64],
}

/// A value with its first and second derivatives along a direction.
#[derive(Clone, Copy, Debug)]
pub struct Jet {
    pub value: f64,
    pub first: f64,
    pub second: f64,
}

impl Jet {
    fn constant(value: f64) -> Jet {
        Jet {
            value,
            first: 0.0,
            second: 0.0,
        }
    }

    /// f(self), given f, f' and f'' at self.value.
    fn chain(self, f: f64, f1: f64, f2: f64) -> Jet {
        Jet {
            value: f,
            first: f1 * self.first,
            second: f2 * self.first * self.first + f1 * self.second,
        }
    }

    fn mul(self, b: Jet) -> Jet {
        Jet {
            value: self.value * b.value,
            first: self.first * b.value + self.value * b.first,
            second: self.second * b.value + 2.0 * self.first * b.first + self.value * b.second,
        }
    }

    fn div(self, b: Jet) -> Jet {
        let value = self.value / b.value;
        let first = (self.first - value * b.first) / b.value;
        let second = (self.second - 2.0 * first * b.first - value * b.second) / b.value;
        Jet {
            value,
            first,
            second,
        }
    }
}

/// Evaluates `s` with its derivatives along `direction` (over the link's coordinates).
pub fn eval_jet(
    s: &SExpr,
    unknowns: &UnknownValues,
    env: &Env<'_>,
    direction: &[f64],
) -> Result<Jet, EvalError> {
    let go = |e: &SExpr| eval_jet(e, unknowns, env, direction);
    Ok(match s {
        SExpr::Num(v) => Jet::constant(*v),
        SExpr::Time => return Err(EvalError::NotGeometric("the time")),
        SExpr::FrameState(..) => {
            return Err(EvalError::NotGeometric(
                "the state of a frame (position, velocity, …)",
            ))
        }
        SExpr::Unknown(id) => Jet::constant(*unknowns.get(id).ok_or(EvalError::Missing(*id))?),
        SExpr::UnknownFunction(id, _) => return Err(EvalError::Missing(*id)),
        SExpr::Coordinate { index, order: 0 } => {
            let i = *index as usize;
            let value = *env
                .coordinates
                .get(i)
                .ok_or(EvalError::NotGeometric("a coordinate of another link"))?;
            Jet {
                value,
                first: direction.get(i).copied().unwrap_or(0.0),
                second: 0.0,
            }
        }
        SExpr::Coordinate { order: 1, .. } => {
            return Err(EvalError::NotGeometric("a time derivative"))
        }
        SExpr::Coordinate { .. } => {
            return Err(EvalError::NotGeometric("a second time derivative"))
        }
        SExpr::JoinCoordinate { .. } => {
            return Err(EvalError::NotGeometric("a coordinate of a join"))
        }
        SExpr::Neg(a) => {
            let a = go(a)?;
            Jet {
                value: -a.value,
                first: -a.first,
                second: -a.second,
            }
        }
        SExpr::Add(a, b) => {
            let (a, b) = (go(a)?, go(b)?);
            Jet {
                value: a.value + b.value,
                first: a.first + b.first,
                second: a.second + b.second,
            }
        }
        SExpr::Sub(a, b) => {
            let (a, b) = (go(a)?, go(b)?);
            Jet {
                value: a.value - b.value,
                first: a.first - b.first,
                second: a.second - b.second,
            }
        }
        SExpr::Mul(a, b) => go(a)?.mul(go(b)?),
        SExpr::Div(a, b) => go(a)?.div(go(b)?),
        SExpr::Pow(a, b) => {
            let (a, b) = (go(a)?, go(b)?);
            if b.first == 0.0 && b.second == 0.0 {
                let n = b.value;
                a.chain(
                    a.value.powf(n),
                    n * a.value.powf(n - 1.0),
                    n * (n - 1.0) * a.value.powf(n - 2.0),
                )
            } else {
                // a^b = exp(b ln a)
                let ln = a.chain(a.value.ln(), 1.0 / a.value, -1.0 / (a.value * a.value));
                let exponent = b.mul(ln);
                let e = exponent.value.exp();
                exponent.chain(e, e, e)
            }
        }
        SExpr::Call(name, args) => {
            let x = go(args
                .first()
                .ok_or(EvalError::NotGeometric("a call without arguments"))?)?;
            let v = x.value;
            match *name {
                "sin" => x.chain(v.sin(), v.cos(), -v.sin()),
                "cos" => x.chain(v.cos(), -v.sin(), -v.cos()),
                "tan" => {
                    let sec2 = 1.0 / v.cos().powi(2);
                    x.chain(v.tan(), sec2, 2.0 * sec2 * v.tan())
                }
                "asin" => x.chain(
                    v.asin(),
                    1.0 / (1.0 - v * v).sqrt(),
                    v / (1.0 - v * v).powf(1.5),
                ),
                "acos" => x.chain(
                    v.acos(),
                    -1.0 / (1.0 - v * v).sqrt(),
                    -v / (1.0 - v * v).powf(1.5),
                ),
                "atan" => x.chain(
                    v.atan(),
                    1.0 / (1.0 + v * v),
                    -2.0 * v / (1.0 + v * v).powi(2),
                ),
                "sqrt" => x.chain(v.sqrt(), 0.5 / v.sqrt(), -0.25 / v.powf(1.5)),
                "exp" => x.chain(v.exp(), v.exp(), v.exp()),
                "log" => x.chain(v.ln(), 1.0 / v, -1.0 / (v * v)),
                "abs" => x.chain(v.abs(), v.signum(), 0.0),
                "atan2" => {
                    let y = x;
                    let x = go(args
                        .get(1)
                        .ok_or(EvalError::NotGeometric("atan2 needs two arguments"))?)?;
                    let n = x.value * y.first - y.value * x.first;
                    let d = x.value * x.value + y.value * y.value;
                    let n1 = x.value * y.second - y.value * x.second;
                    let d1 = 2.0 * (x.value * x.first + y.value * y.first);
                    Jet {
                        value: y.value.atan2(x.value),
                        first: n / d,
                        second: (n1 * d - n * d1) / (d * d),
                    }
                }
                _ => return Err(EvalError::NotGeometric("an unknown function")),
            }
        }
    })
}

/// The value of `s` at link coordinates `q` and its derivative with respect to `q[wrt]`.
pub fn eval_dual(
    s: &SExpr,
    unknowns: &UnknownValues,
    q: &[f64],
    wrt: Option<usize>,
) -> Result<Jet, EvalError> {
    let mut direction = vec![0.0; q.len()];
    if let Some(k) = wrt.filter(|&k| k < q.len()) {
        direction[k] = 1.0;
    }
    eval_jet(s, unknowns, &Env { coordinates: q }, &direction)
}

pub fn eval_by_trees(s: &SExpr, unknowns: &UnknownValues, q: &[f64]) -> Result<f64, EvalError> {
    eval_jet(s, unknowns, &Env { coordinates: q }, &[]).map(|j| j.value)
}
