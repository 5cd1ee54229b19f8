//! The exact configuration: each coordinate a length or an angle, given on the command line
//! (`--at hinge.q=t:1/2`, the half-angle tangent) or read from the assembled configuration
//! when its value is an exact number there (an angle by its cosine and sine).

use std::collections::{HashMap, HashSet};

use super::evaluate::SymbolValue;
use super::failure::ExactFailure;
use super::field::Number;
use super::rational::Rational;
use super::recognise::Recogniser;
use crate::symbolic::expr::{ExprId, Function, Node, Pool};
use crate::symbolic::lower::Variable;

/// `--at NAME=VALUE`.
#[derive(Clone, Debug)]
pub struct Given {
    pub name: String,
    pub value: GivenValue,
}

#[derive(Clone, Debug, PartialEq)]
pub enum GivenValue {
    /// A length, or the angle 0: `3/2`, `0.25`, `1e-7` (decimals are exact).
    Plain(Rational),
    /// An angle by the tangent of its half: `t:1/2` (cos = 3/5, sin = 4/5).
    HalfAngle(Rational),
    /// An angle in degrees whose cosine and sine are numbers of a quadratic field: `deg:120`.
    Degrees(Rational),
}

impl Given {
    /// Reads `NAME=VALUE`.
    pub fn parse(text: &str) -> Result<Given, String> {
        let (name, value) = text
            .split_once('=')
            .ok_or_else(|| format!("`{text}` is not NAME=VALUE (e.g. `crank.q=t:1/2`)"))?;
        let number = |v: &str| {
            Rational::parse(v).ok_or_else(|| {
                format!("`{v}` is not an exact number (write `3/4`, `0.25` or `1e-7`)")
            })
        };
        let value = if let Some(t) = value.strip_prefix("t:") {
            GivenValue::HalfAngle(number(t)?)
        } else if let Some(d) = value.strip_prefix("deg:") {
            GivenValue::Degrees(number(d)?)
        } else {
            GivenValue::Plain(number(value)?)
        };
        Ok(Given {
            name: name.trim().to_string(),
            value,
        })
    }

    /// The value as a double, for the numeric assembly that holds it (radians for an angle).
    pub fn approximate(&self) -> f64 {
        match &self.value {
            GivenValue::Plain(x) => x.to_f64(),
            GivenValue::HalfAngle(t) => 2.0 * t.to_f64().atan(),
            GivenValue::Degrees(d) => d.to_f64().to_radians(),
        }
    }
}

/// One coordinate at the exact configuration.
#[derive(Clone, Debug, serde::Serialize)]
pub struct ExactCoordinate {
    pub name: String,
    pub value: SymbolValue,
    /// Given on the command line (otherwise read from the assembled configuration).
    pub given: bool,
    /// The assembled value, radians for an angle.
    pub approximate: f64,
}

impl ExactCoordinate {
    /// `t = 1/2` (tan of half the angle), `cos = -1, sin = 0` at a half-turn, or the length.
    pub fn describe(&self) -> String {
        match &self.value {
            SymbolValue::Number(x) => x.to_string(),
            SymbolValue::Angle { cos, sin } => {
                let one = Number::integer(1, cos.radicand);
                match one.add(cos).inverse() {
                    Some(inverse) => format!("t = {}", sin.mul(&inverse)),
                    None => format!("cos = {cos}, sin = {sin}"),
                }
            }
        }
    }
}

/// The symbols that appear in the argument of a sine, cosine or tangent: the angles.
fn angles(pool: &Pool, roots: &[ExprId]) -> HashSet<u32> {
    let mut found = HashSet::new();
    let mut seen = HashSet::new();
    let mut stack: Vec<(ExprId, bool)> = roots.iter().map(|&r| (r, false)).collect();
    while let Some((id, in_angle)) = stack.pop() {
        if !seen.insert((id, in_angle)) {
            continue;
        }
        match pool.node(id) {
            Node::Symbol(i) if in_angle => {
                found.insert(i);
            }
            Node::Apply(Function::Sin | Function::Cos | Function::Tan, a) => stack.push((a, true)),
            _ => stack.extend(pool.operands(id).into_iter().map(|o| (o, in_angle))),
        }
    }
    found
}

fn from_half_angle(t: &Rational, radicand: u64) -> SymbolValue {
    let t = Number::rational(t.clone(), radicand);
    let one = Number::integer(1, radicand);
    let square = t.mul(&t);
    let denominator = one.add(&square).inverse().expect("1 + t² > 0");
    SymbolValue::Angle {
        cos: one.sub(&square).mul(&denominator),
        sin: t.add(&t).mul(&denominator),
    }
}

/// An angle read from its double: its cosine and sine must be exact numbers of the field, with
/// cos² + sin² = 1 exactly.
/// The half-angle tangent is tried first: its exact form is the shortest (t = 4 + 2√3 where
/// cos θ = (−15 − 32√3)/73).
fn read_angle(angle: f64, recogniser: &mut Recogniser) -> Option<SymbolValue> {
    let t = (angle / 2.0).tan();
    if t.abs() < 1e3 {
        if let Some(t) = recogniser.number(t) {
            let one = Number::integer(1, t.radicand);
            let square = t.mul(&t);
            let denominator = one.add(&square).inverse()?;
            let (cos, sin) = (
                one.sub(&square).mul(&denominator),
                t.add(&t).mul(&denominator),
            );
            if (cos.to_f64() - angle.cos()).abs() < 1e-9
                && (sin.to_f64() - angle.sin()).abs() < 1e-9
            {
                return Some(SymbolValue::Angle { cos, sin });
            }
        }
    }
    let cos = recogniser.number(angle.cos())?;
    let sin = recogniser.number(angle.sin())?;
    let one = cos.mul(&cos).add(&sin.mul(&sin));
    (one == Number::integer(1, one.radicand)).then_some(SymbolValue::Angle { cos, sin })
}

/// Every coordinate of `positions`, exactly.
pub(super) fn exact_configuration(
    pool: &Pool,
    roots: &[ExprId],
    positions: &[Variable],
    given: &[Given],
    numeric: &HashMap<String, f64>,
    recogniser: &mut Recogniser,
) -> Result<Vec<ExactCoordinate>, ExactFailure> {
    for g in given {
        if !positions.iter().any(|p| p.name == g.name) {
            let names: Vec<&str> = positions.iter().map(|p| p.name.as_str()).collect();
            return Err(ExactFailure::Input(format!(
                "`--at {}`: no coordinate of that name; the coordinates are {}",
                g.name,
                names.join(", ")
            )));
        }
    }
    let angular = angles(pool, roots);
    positions
        .iter()
        .map(|p| {
            let is_angle = pool
                .symbol_index(p.symbol)
                .is_some_and(|i| angular.contains(&(i as u32)));
            let approximate = numeric.get(&p.name).copied().unwrap_or(0.0);
            let given_value = given.iter().rev().find(|g| g.name == p.name);
            let value = match (given_value, is_angle) {
                (Some(g), true) => match &g.value {
                    GivenValue::HalfAngle(t) => from_half_angle(t, recogniser.radicand),
                    GivenValue::Plain(x) if x.is_zero() => from_half_angle(x, recogniser.radicand),
                    GivenValue::Plain(x) => {
                        return Err(ExactFailure::Input(format!(
                            "`--at {}={x}`: an angle of {x} rad has no exact cosine; give `t:VALUE` (the tangent of half the angle) or `deg:VALUE`",
                            p.name
                        )))
                    }
                    GivenValue::Degrees(d) => read_angle(d.to_f64().to_radians(), recogniser)
                        .ok_or_else(|| {
                            ExactFailure::NotExact(format!(
                                "`--at {}=deg:{d}`: the cosine and sine of {d}° are not numbers of one quadratic field",
                                p.name
                            ))
                        })?,
                },
                (Some(g), false) => match &g.value {
                    GivenValue::Plain(x) => SymbolValue::Number(Number::rational(x.clone(), 1)),
                    _ => {
                        return Err(ExactFailure::Input(format!(
                            "`--at {}`: this coordinate is a length, not an angle; give its value",
                            p.name
                        )))
                    }
                },
                (None, true) => read_angle(approximate, recogniser).ok_or_else(|| {
                    ExactFailure::NotExact(format!(
                        "the assembled angle `{}` = {approximate} has no exact cosine and sine; give it with `--at {}=t:VALUE`",
                        p.name, p.name
                    ))
                })?,
                (None, false) => SymbolValue::Number(recogniser.number(approximate).ok_or_else(
                    || {
                        ExactFailure::NotExact(format!(
                            "the assembled value of `{}` = {approximate} is not an exact number; give it with `--at {}=VALUE`",
                            p.name, p.name
                        ))
                    },
                )?),
            };
            Ok(ExactCoordinate {
                name: p.name.clone(),
                value,
                given: given_value.is_some(),
                approximate,
            })
        })
        .collect()
}
