//! Exact evaluation of the equations' expressions at an exact configuration, by the
//! half-angle substitution of Papegay (1992, §4.3.1, `trigfree`): an angle θ of the mechanism
//! enters only through cos θ and sin θ, which are rational in t = tan(θ/2),
//! cos θ = (1 − t²)/(1 + t²) and sin θ = 2t/(1 + t²). Here an angle is carried as the exact pair
//! (cos θ, sin θ) itself, so that θ = π (where t is infinite) is allowed too; sums and integer
//! multiples of angles (`sin(q1 + q2)`, `cos(2 q)`) and constant angles whose sine and cosine are
//! numbers of the field follow by the addition formulas. Anything else (a coordinate outside a
//! sine or cosine, `exp`, an unknown without a value) is refused with its reason.

use std::collections::HashMap;

use super::field::Number;
use super::recognise::Recogniser;
use crate::symbolic::expr::{topological_order, ExprId, Function, Node, Pool};

/// The exact value of one symbol of the pool.
#[derive(Clone, Debug, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SymbolValue {
    /// A length, a rate or a parameter.
    Number(Number),
    /// An angle, by its cosine and sine.
    Angle { cos: Number, sin: Number },
}

pub struct Evaluator<'a> {
    pool: &'a Pool,
    /// By symbol index; `None` for a symbol without an exact value.
    symbols: Vec<Option<SymbolValue>>,
    numbers: HashMap<ExprId, Result<Number, String>>,
    angles: HashMap<ExprId, Result<(Number, Number), String>>,
}

impl<'a> Evaluator<'a> {
    pub fn new(pool: &'a Pool, symbols: Vec<Option<SymbolValue>>) -> Evaluator<'a> {
        Evaluator {
            pool,
            symbols,
            numbers: HashMap::new(),
            angles: HashMap::new(),
        }
    }

    /// The exact values of `roots`.
    pub fn values(
        &mut self,
        roots: &[ExprId],
        recogniser: &mut Recogniser,
    ) -> Result<Vec<Number>, String> {
        let pool = self.pool;
        let order = topological_order(roots, |id| match pool.node(id) {
            // A sine's argument is read as an angle, not evaluated as a number.
            Node::Apply(Function::Sin | Function::Cos | Function::Tan, _) => Vec::new(),
            _ => pool.operands(id),
        });
        for id in order {
            if !self.numbers.contains_key(&id) {
                let value = self.number(id, recogniser);
                self.numbers.insert(id, value);
            }
        }
        roots
            .iter()
            .map(|r| self.numbers[r].clone())
            .collect::<Result<Vec<_>, _>>()
    }

    fn operand(&self, id: ExprId) -> Result<Number, String> {
        self.numbers[&id].clone()
    }

    /// One node, its operands already evaluated.
    fn number(&mut self, id: ExprId, recogniser: &mut Recogniser) -> Result<Number, String> {
        let pool = self.pool;
        Ok(match pool.node(id) {
            Node::Constant(bits) => {
                let x = f64::from_bits(bits);
                recogniser.number(x).ok_or_else(|| {
                    format!("the constant {x:e} is not a number this reads exactly (a rational or a number of ℚ(√d))")
                })?
            }
            Node::Symbol(i) => match &self.symbols[i as usize] {
                Some(SymbolValue::Number(n)) => n.clone(),
                Some(SymbolValue::Angle { .. }) => {
                    return Err(format!(
                        "the angle `{}` appears outside a sine or cosine (a helical joint?), where its half-angle form is no exact value",
                        pool.symbol_name(i)
                    ))
                }
                None => return Err(format!("`{}` has no exact value", pool.symbol_name(i))),
            },
            Node::Add(a, b) => self.operand(a)?.add(&self.operand(b)?),
            Node::Mul(a, b) => self.operand(a)?.mul(&self.operand(b)?),
            Node::Neg(a) => self.operand(a)?.neg(),
            Node::Div(a, b) => self
                .operand(a)?
                .div(&self.operand(b)?)
                .ok_or("a division by zero at this configuration")?,
            Node::Pow(a, b) => {
                let base = self.operand(a)?;
                let exponent = pool.as_constant(b).filter(|e| e.fract() == 0.0 && e.abs() <= 64.0);
                let exponent = exponent.ok_or("a power whose exponent is not a small integer")?;
                let mut power = Number::integer(1, base.radicand);
                for _ in 0..exponent.abs() as u32 {
                    power = power.mul(&base);
                }
                if exponent < 0.0 {
                    power.inverse().ok_or("a division by zero at this configuration")?
                } else {
                    power
                }
            }
            Node::Apply(f @ (Function::Sin | Function::Cos | Function::Tan), a) => {
                let (cos, sin) = self.angle(a, recogniser)?;
                match f {
                    Function::Sin => sin,
                    Function::Cos => cos,
                    _ => sin.div(&cos).ok_or("a tangent of a right angle")?,
                }
            }
            Node::Apply(f, _) => {
                return Err(format!(
                    "`{}` of a coordinate has no exact value here",
                    f.name()
                ))
            }
            Node::Atan2(..) | Node::Select { .. } => {
                return Err("`atan2` or a piecewise law of a coordinate has no exact value here".into())
            }
        })
    }

    /// (cos θ, sin θ) of an angle expression.
    fn angle(
        &mut self,
        id: ExprId,
        recogniser: &mut Recogniser,
    ) -> Result<(Number, Number), String> {
        if let Some(known) = self.angles.get(&id) {
            return known.clone();
        }
        let found = self.angle_uncached(id, recogniser);
        self.angles.insert(id, found.clone());
        found
    }

    fn angle_uncached(
        &mut self,
        id: ExprId,
        recogniser: &mut Recogniser,
    ) -> Result<(Number, Number), String> {
        let pool = self.pool;
        match pool.node(id) {
            Node::Symbol(i) => match &self.symbols[i as usize] {
                Some(SymbolValue::Angle { cos, sin }) => Ok((cos.clone(), sin.clone())),
                Some(SymbolValue::Number(_)) => Err(format!(
                    "`{}` is a length but appears in a sine or cosine",
                    pool.symbol_name(i)
                )),
                None => Err(format!("`{}` has no exact value", pool.symbol_name(i))),
            },
            Node::Constant(bits) => {
                let x = f64::from_bits(bits);
                let cos = recogniser.number(x.cos());
                let sin = recogniser.number(x.sin());
                match (cos, sin) {
                    (Some(c), Some(s)) => Ok((c, s)),
                    _ => Err(format!(
                        "the constant angle {x:e} has no exact sine and cosine here"
                    )),
                }
            }
            Node::Neg(a) => {
                let (c, s) = self.angle(a, recogniser)?;
                Ok((c, s.neg()))
            }
            Node::Add(a, b) => {
                let (ca, sa) = self.angle(a, recogniser)?;
                let (cb, sb) = self.angle(b, recogniser)?;
                Ok((ca.mul(&cb).sub(&sa.mul(&sb)), sa.mul(&cb).add(&ca.mul(&sb))))
            }
            Node::Mul(a, b) => {
                let (k, angle) = match (pool.as_constant(a), pool.as_constant(b)) {
                    (Some(k), _) => (k, b),
                    (_, Some(k)) => (k, a),
                    _ => return Err("a product of two angles".into()),
                };
                if k.fract() != 0.0 || k.abs() > 64.0 {
                    return Err(format!("an angle times {k}, not a small integer"));
                }
                let (c, s) = self.angle(angle, recogniser)?;
                let s = if k < 0.0 { s.neg() } else { s };
                let (mut cos, mut sin) = (
                    Number::integer(1, c.radicand),
                    Number::integer(0, c.radicand),
                );
                for _ in 0..k.abs() as u32 {
                    (cos, sin) = (cos.mul(&c).sub(&sin.mul(&s)), sin.mul(&c).add(&cos.mul(&s)));
                }
                Ok((cos, sin))
            }
            _ => Err("a sine or cosine of something other than a sum of angles".into()),
        }
    }
}
