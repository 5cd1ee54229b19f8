//! Rational numbers of unbounded size, kept in lowest terms with a positive denominator.
//!
//! Written here over `num-bigint`'s integers (already built for the Parquet writer) rather than
//! taken from `num-rational`, whose big-integer feature would build a second version of
//! `num-bigint`: the few operations an elimination needs are short.

use std::cmp::Ordering;
use std::fmt;

use num_bigint::BigInt;
use num_integer::Integer;
use num_traits::{One, Signed, ToPrimitive, Zero};

#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct Rational {
    numerator: BigInt,
    denominator: BigInt,
}

impl Rational {
    pub fn new(numerator: BigInt, denominator: BigInt) -> Rational {
        assert!(!denominator.is_zero(), "a rational with denominator 0");
        let divisor = numerator.gcd(&denominator);
        let (mut n, mut d) = (numerator / &divisor, denominator / &divisor);
        if d.is_negative() {
            (n, d) = (-n, -d);
        }
        Rational {
            numerator: n,
            denominator: d,
        }
    }

    pub fn integer(value: i64) -> Rational {
        Rational::new(BigInt::from(value), BigInt::one())
    }

    #[cfg_attr(not(lsdc_internals), allow(dead_code))]
    pub fn fraction(numerator: i64, denominator: i64) -> Rational {
        Rational::new(BigInt::from(numerator), BigInt::from(denominator))
    }

    pub fn zero() -> Rational {
        Rational::integer(0)
    }

    pub fn one() -> Rational {
        Rational::integer(1)
    }

    pub fn numerator(&self) -> &BigInt {
        &self.numerator
    }

    pub fn denominator(&self) -> &BigInt {
        &self.denominator
    }

    pub fn is_zero(&self) -> bool {
        self.numerator.is_zero()
    }

    pub fn is_integer(&self) -> bool {
        self.denominator.is_one()
    }

    pub fn signum(&self) -> Ordering {
        self.numerator.sign().cmp(&num_bigint::Sign::NoSign)
    }

    /// Reads `3`, `-2/7`, `0.125` or `1e-7` exactly: a decimal number is the rational it
    /// writes, not the binary number nearest to it.
    pub fn parse(text: &str) -> Option<Rational> {
        let text = text.trim();
        if let Some((n, d)) = text.split_once('/') {
            let (n, d) = (Rational::parse(n)?, Rational::parse(d)?);
            return (!d.is_zero()).then(|| n.div(&d));
        }
        let (mantissa, exponent) = match text.split_once(['e', 'E']) {
            Some((m, e)) => (m, e.parse::<i32>().ok()?),
            None => (text, 0),
        };
        let (negative, digits) = match mantissa.strip_prefix('-') {
            Some(rest) => (true, rest),
            None => (false, mantissa.strip_prefix('+').unwrap_or(mantissa)),
        };
        let (whole, fraction) = digits.split_once('.').unwrap_or((digits, ""));
        if whole.is_empty() && fraction.is_empty()
            || !(whole.chars().chain(fraction.chars())).all(|c| c.is_ascii_digit())
        {
            return None;
        }
        let all: BigInt = format!("0{whole}{fraction}").parse().ok()?;
        let scale = exponent - fraction.len() as i32;
        let ten = BigInt::from(10);
        let value = if scale >= 0 {
            Rational::new(all * ten.pow(scale as u32), BigInt::one())
        } else {
            Rational::new(all, ten.pow((-scale) as u32))
        };
        Some(if negative { value.neg() } else { value })
    }

    pub fn add(&self, other: &Rational) -> Rational {
        Rational::new(
            &self.numerator * &other.denominator + &other.numerator * &self.denominator,
            &self.denominator * &other.denominator,
        )
    }

    pub fn sub(&self, other: &Rational) -> Rational {
        self.add(&other.neg())
    }

    pub fn mul(&self, other: &Rational) -> Rational {
        Rational::new(
            &self.numerator * &other.numerator,
            &self.denominator * &other.denominator,
        )
    }

    /// `self / other`; `other` must not be zero.
    pub fn div(&self, other: &Rational) -> Rational {
        Rational::new(
            &self.numerator * &other.denominator,
            &self.denominator * &other.numerator,
        )
    }

    pub fn neg(&self) -> Rational {
        Rational {
            numerator: -&self.numerator,
            denominator: self.denominator.clone(),
        }
    }

    pub fn to_f64(&self) -> f64 {
        match (self.numerator.to_f64(), self.denominator.to_f64()) {
            (Some(n), Some(d)) if n.is_finite() && d.is_finite() => n / d,
            // Too large for a double on either side: scale both down first.
            _ => {
                let shift = self.numerator.bits().max(self.denominator.bits()) - 1000;
                let n = (&self.numerator >> shift).to_f64().unwrap_or(0.0);
                let d = (&self.denominator >> shift)
                    .to_f64()
                    .unwrap_or(f64::INFINITY);
                n / d
            }
        }
    }
}

impl fmt::Display for Rational {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.is_integer() {
            write!(f, "{}", self.numerator)
        } else {
            write!(f, "{}/{}", self.numerator, self.denominator)
        }
    }
}
