//! Numeric evaluation of symbolic scalars, with forward-mode derivatives with respect to one
//! coordinate of a link (for motion subspaces and Jacobians).

use std::collections::HashMap;

use crate::elab::value::{SExpr, UnknownId};

/// Values of the program's unknowns (written `?s` and generic quantities).
pub type UnknownValues = HashMap<UnknownId, f64>;

#[derive(Clone, Debug, PartialEq)]
pub enum EvalError {
    /// An unknown without a value.
    Missing(UnknownId),
    /// Something that is not a function of the link's coordinates alone (a derivative `x'`,
    /// another join's coordinate): not allowed in geometry.
    NotGeometric(&'static str),
}

/// A value and its derivative with respect to the chosen coordinate.
#[derive(Clone, Copy, Debug)]
pub struct Dual {
    pub value: f64,
    pub derivative: f64,
}

impl Dual {
    fn constant(value: f64) -> Dual {
        Dual { value, derivative: 0.0 }
    }
}

/// Evaluates `s` at link coordinates `q`, differentiating with respect to `q[wrt]` if given.
pub fn eval_dual(s: &SExpr, unknowns: &UnknownValues, q: &[f64], wrt: Option<usize>) -> Result<Dual, EvalError> {
    let go = |e: &SExpr| eval_dual(e, unknowns, q, wrt);
    Ok(match s {
        SExpr::Num(v) => Dual::constant(*v),
        SExpr::Time => return Err(EvalError::NotGeometric("the time")),
        SExpr::Unknown(id) => Dual::constant(*unknowns.get(id).ok_or(EvalError::Missing(*id))?),
        SExpr::UnknownFunction(id, _) => return Err(EvalError::Missing(*id)),
        SExpr::Coordinate { index, order: 0 } => {
            let i = *index as usize;
            let value = *q.get(i).ok_or(EvalError::NotGeometric("a coordinate of another link"))?;
            Dual { value, derivative: if wrt == Some(i) { 1.0 } else { 0.0 } }
        }
        SExpr::Coordinate { .. } => return Err(EvalError::NotGeometric("a time derivative")),
        SExpr::JoinCoordinate { .. } => return Err(EvalError::NotGeometric("a coordinate of a join")),
        SExpr::Neg(a) => {
            let a = go(a)?;
            Dual { value: -a.value, derivative: -a.derivative }
        }
        SExpr::Add(a, b) => {
            let (a, b) = (go(a)?, go(b)?);
            Dual { value: a.value + b.value, derivative: a.derivative + b.derivative }
        }
        SExpr::Sub(a, b) => {
            let (a, b) = (go(a)?, go(b)?);
            Dual { value: a.value - b.value, derivative: a.derivative - b.derivative }
        }
        SExpr::Mul(a, b) => {
            let (a, b) = (go(a)?, go(b)?);
            Dual { value: a.value * b.value, derivative: a.derivative * b.value + a.value * b.derivative }
        }
        SExpr::Div(a, b) => {
            let (a, b) = (go(a)?, go(b)?);
            let value = a.value / b.value;
            Dual { value, derivative: (a.derivative - value * b.derivative) / b.value }
        }
        SExpr::Pow(a, b) => {
            let (a, b) = (go(a)?, go(b)?);
            let value = a.value.powf(b.value);
            let mut derivative = if a.derivative != 0.0 { b.value * a.value.powf(b.value - 1.0) * a.derivative } else { 0.0 };
            if b.derivative != 0.0 {
                derivative += value * a.value.ln() * b.derivative;
            }
            Dual { value, derivative }
        }
        SExpr::Call(name, args) => {
            let x = go(args.first().ok_or(EvalError::NotGeometric("a call without arguments"))?)?;
            let (value, slope) = match *name {
                "sin" => (x.value.sin(), x.value.cos()),
                "cos" => (x.value.cos(), -x.value.sin()),
                "tan" => (x.value.tan(), 1.0 / x.value.cos().powi(2)),
                "asin" => (x.value.asin(), 1.0 / (1.0 - x.value * x.value).sqrt()),
                "acos" => (x.value.acos(), -1.0 / (1.0 - x.value * x.value).sqrt()),
                "atan" => (x.value.atan(), 1.0 / (1.0 + x.value * x.value)),
                "sqrt" => (x.value.sqrt(), 0.5 / x.value.sqrt()),
                "exp" => (x.value.exp(), x.value.exp()),
                "log" => (x.value.ln(), 1.0 / x.value),
                "abs" => (x.value.abs(), x.value.signum()),
                "atan2" => {
                    let y = x;
                    let x = go(args.get(1).ok_or(EvalError::NotGeometric("atan2 needs two arguments"))?)?;
                    let r2 = x.value * x.value + y.value * y.value;
                    let derivative = (x.value * y.derivative - y.value * x.derivative) / r2;
                    return Ok(Dual { value: y.value.atan2(x.value), derivative });
                }
                _ => return Err(EvalError::NotGeometric("an unknown function")),
            };
            Dual { value, derivative: if x.derivative != 0.0 { slope * x.derivative } else { 0.0 } }
        }
    })
}

pub fn eval(s: &SExpr, unknowns: &UnknownValues, q: &[f64]) -> Result<f64, EvalError> {
    eval_dual(s, unknowns, q, None).map(|d| d.value)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::elab::value::{arith, num};
    use std::rc::Rc;

    #[test]
    fn derivatives_match_finite_differences() {
        let q0 = Rc::new(SExpr::Coordinate { index: 0, order: 0 });
        let q1 = Rc::new(SExpr::Coordinate { index: 1, order: 0 });
        let e = arith('*', &Rc::new(SExpr::Call("sin", vec![arith('*', &num(2.0), &q0)])), &arith('^', &q1, &num(3.0)));
        let e = arith('+', &e, &Rc::new(SExpr::Call("atan2", vec![q1.clone(), q0.clone()])));
        let unknowns = UnknownValues::new();
        let q = [0.3, 1.7];
        for k in 0..2 {
            let d = eval_dual(&e, &unknowns, &q, Some(k)).expect("evaluates").derivative;
            let h = 1e-6;
            let mut plus = q;
            plus[k] += h;
            let mut minus = q;
            minus[k] -= h;
            let fd = (eval(&e, &unknowns, &plus).expect("") - eval(&e, &unknowns, &minus).expect("")) / (2.0 * h);
            assert!((d - fd).abs() < 1e-8, "{d} vs {fd}");
        }
    }
}
