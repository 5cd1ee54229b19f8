//! Exact numbers a + b√d of one quadratic field ℚ(√d), d a square-free integer > 1 (or ℚ itself,
//! d = 1 with b = 0). One field per computation: the geometry of a mechanism such as the
//! antenna mesh (rotations by 120°, cos = −1/2, sin = √3/2) lives in ℚ(√3), and the half-angle
//! substitution keeps every coordinate's sine and cosine in the field of its half-angle tangent.
//! Zero is decided exactly (√d is irrational), so a rank over the field is exact.

use std::fmt;

use super::rational::Rational;

#[derive(Clone, Debug)]
pub struct Number {
    /// a
    pub rational: Rational,
    /// b
    pub surd: Rational,
    /// d, shared by every number of one computation (1 for ℚ).
    pub radicand: u64,
}

/// Equal values are equal numbers, whichever field a rational one was read in.
impl PartialEq for Number {
    fn eq(&self, other: &Number) -> bool {
        self.rational == other.rational
            && self.surd == other.surd
            && (self.surd.is_zero() || self.radicand == other.radicand)
    }
}

impl Eq for Number {}

impl Number {
    pub fn rational(value: Rational, radicand: u64) -> Number {
        Number {
            rational: value,
            surd: Rational::zero(),
            radicand,
        }
    }

    pub fn integer(value: i64, radicand: u64) -> Number {
        Number::rational(Rational::integer(value), radicand)
    }

    pub fn is_zero(&self) -> bool {
        self.rational.is_zero() && self.surd.is_zero()
    }

    pub fn is_rational(&self) -> bool {
        self.surd.is_zero()
    }

    fn check(&self, other: &Number) {
        debug_assert!(
            self.radicand == other.radicand || self.is_rational() || other.is_rational(),
            "numbers of two fields, ℚ(√{}) and ℚ(√{})",
            self.radicand,
            other.radicand
        );
    }

    fn with(&self, rational: Rational, surd: Rational) -> Number {
        Number {
            rational,
            surd,
            radicand: self.radicand,
        }
    }

    /// The result of an operation with `other`: in the field of whichever is not of ℚ alone.
    fn joined(&self, other: &Number, rational: Rational, surd: Rational) -> Number {
        Number {
            rational,
            surd,
            radicand: self.radicand.max(other.radicand),
        }
    }

    pub fn add(&self, other: &Number) -> Number {
        self.check(other);
        self.joined(
            other,
            self.rational.add(&other.rational),
            self.surd.add(&other.surd),
        )
    }

    pub fn sub(&self, other: &Number) -> Number {
        self.add(&other.neg())
    }

    pub fn neg(&self) -> Number {
        self.with(self.rational.neg(), self.surd.neg())
    }

    /// (a + b√d)(c + e√d) = ac + bed + (ae + bc)√d
    pub fn mul(&self, other: &Number) -> Number {
        self.check(other);
        let d = Rational::integer(self.radicand.max(other.radicand) as i64);
        let (a, b, c, e) = (&self.rational, &self.surd, &other.rational, &other.surd);
        self.joined(
            other,
            a.mul(c).add(&b.mul(e).mul(&d)),
            a.mul(e).add(&b.mul(c)),
        )
    }

    /// 1 / (a + b√d) = (a − b√d) / (a² − d b²); `None` for zero.
    pub fn inverse(&self) -> Option<Number> {
        if self.is_zero() {
            return None;
        }
        let d = Rational::integer(self.radicand as i64);
        let (a, b) = (&self.rational, &self.surd);
        let norm = a.mul(a).sub(&b.mul(b).mul(&d));
        Some(self.with(a.div(&norm), b.neg().div(&norm)))
    }

    pub fn div(&self, other: &Number) -> Option<Number> {
        Some(self.mul(&other.inverse()?))
    }

    pub fn to_f64(&self) -> f64 {
        self.rational.to_f64() + self.surd.to_f64() * (self.radicand as f64).sqrt()
    }
}

/// A number is written as it is displayed (`-1/2 + 3/4·√3`): JSON has no exact numbers.
impl serde::Serialize for Number {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.serialize_str(&self.to_string())
    }
}

impl fmt::Display for Number {
    /// `3/5`, `√3/2`, `-1/2 + 3/4·√3`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let root = format!("√{}", self.radicand);
        let surd = |b: &Rational| -> String {
            let magnitude = if b.signum() == std::cmp::Ordering::Less {
                b.neg()
            } else {
                b.clone()
            };
            if magnitude == Rational::one() {
                root.clone()
            } else if magnitude.numerator() == &1.into() {
                format!("{root}/{}", magnitude.denominator())
            } else {
                format!("{magnitude}·{root}")
            }
        };
        let negative = self.surd.signum() == std::cmp::Ordering::Less;
        match (self.rational.is_zero(), self.surd.is_zero()) {
            (_, true) => write!(f, "{}", self.rational),
            (true, false) => write!(f, "{}{}", if negative { "-" } else { "" }, surd(&self.surd)),
            (false, false) => write!(
                f,
                "{} {} {}",
                self.rational,
                if negative { "-" } else { "+" },
                surd(&self.surd)
            ),
        }
    }
}
