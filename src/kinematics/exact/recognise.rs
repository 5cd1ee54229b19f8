//! Reading a double as the exact number it stands for: the program's constants (1.0, 0.5,
//! cos(2π/3) = −0.4999999999999998, 1/sin(π/3) = 1.1547005383792517) and the coordinates of an
//! assembled configuration, as elements of one quadratic field ℚ(√d).
//!
//! A double is read as the rational with the smallest denominator (continued fractions) within
//! 1e-12 of it (relative above 1), a denominator of at most 10⁴; else as ±√r with r such a
//! rational; else as (A + B√d)/q with q ≤ 48 and |B| ≤ 4q for the field's d, or, while no field
//! is chosen, for d in 2, 3, 5, 6, 7. The bounds keep a chance match unlikely (a double that is
//! not such a number falls within 1e-12 of one of them with probability below 1e-4), and every
//! exact result is checked afterwards where it can be: a configuration is accepted only if its
//! loops close exactly and each angle's cos² + sin² is exactly 1.

use std::collections::HashMap;

use num_bigint::BigInt;
use num_traits::ToPrimitive;

use super::field::Number;
use super::rational::Rational;

const TOLERANCE: f64 = 1e-12;
const LARGEST_DENOMINATOR: i64 = 10_000;
const LARGEST_MIXED_DENOMINATOR: i64 = 48;
const FIRST_FIELDS: [u64; 5] = [2, 3, 5, 6, 7];

/// The quadratic field of a computation, chosen by the first irrational number read.
#[derive(Default)]
pub struct Recogniser {
    /// d, 1 while every number read was rational.
    pub radicand: u64,
    memo: HashMap<u64, Option<Number>>,
}

impl Recogniser {
    pub fn new() -> Recogniser {
        Recogniser {
            radicand: 1,
            memo: HashMap::new(),
        }
    }

    /// The exact number `x` stands for, in ℚ or in the computation's field; `None` when it is
    /// none of the numbers this reads (or lies in a second field).
    pub fn number(&mut self, x: f64) -> Option<Number> {
        if let Some(known) = self.memo.get(&x.to_bits()) {
            return known.clone();
        }
        let found = self.read(x);
        self.memo.insert(x.to_bits(), found.clone());
        found
    }

    fn read(&mut self, x: f64) -> Option<Number> {
        if !x.is_finite() {
            return None;
        }
        if let Some(r) = rational(x, LARGEST_DENOMINATOR) {
            return Some(Number::rational(r, self.radicand));
        }
        if let Some((coefficient, d)) = surd(x) {
            return self.in_field(d).then(|| Number {
                rational: Rational::zero(),
                surd: coefficient,
                radicand: d,
            });
        }
        let fields: Vec<u64> = if self.radicand == 1 {
            FIRST_FIELDS.to_vec()
        } else {
            vec![self.radicand]
        };
        for d in fields {
            if let Some((a, b)) = mixed(x, d) {
                self.in_field(d);
                return Some(Number {
                    rational: a,
                    surd: b,
                    radicand: d,
                });
            }
        }
        None
    }

    /// Takes ℚ(√d) as the computation's field if none was chosen; false for a second field.
    fn in_field(&mut self, d: u64) -> bool {
        if self.radicand == 1 {
            self.radicand = d;
        }
        self.radicand == d
    }
}

fn close(x: f64, y: f64) -> bool {
    (x - y).abs() <= TOLERANCE * x.abs().max(1.0)
}

/// The rational of smallest denominator (at most `largest`) within the tolerance of `x`.
pub fn rational(x: f64, largest: i64) -> Option<Rational> {
    // Convergents h/k of the continued fraction of x.
    let (mut h0, mut h1) = (0i128, 1i128);
    let (mut k0, mut k1) = (1i128, 0i128);
    let mut rest = x;
    for _ in 0..64 {
        let a = rest.floor();
        if a.abs() > 1e15 {
            return None;
        }
        let a = a as i128;
        (h0, h1) = (h1, a * h1 + h0);
        (k0, k1) = (k1, a * k1 + k0);
        if k1 > largest as i128 {
            return None;
        }
        if close(x, h1 as f64 / k1 as f64) {
            return Some(Rational::new(BigInt::from(h1), BigInt::from(k1)));
        }
        let fraction = rest - a as f64;
        if fraction == 0.0 {
            return None;
        }
        rest = 1.0 / fraction;
    }
    None
}

/// `x = c √d` with c rational and d > 1 square-free, read from x² = P/Q:
/// √(P/Q) = √(P Q) / Q = s √d / Q with P Q = s² d.
fn surd(x: f64) -> Option<(Rational, u64)> {
    let square = rational(x * x, LARGEST_DENOMINATOR)?;
    let product = (square.numerator() * square.denominator()).to_u64()?;
    if product == 0 {
        return None;
    }
    let (s, d) = square_free(product);
    if d == 1 {
        return None;
    }
    let coefficient = Rational::new(BigInt::from(s), square.denominator().clone());
    let coefficient = if x < 0.0 {
        coefficient.neg()
    } else {
        coefficient
    };
    close(x, coefficient.to_f64() * (d as f64).sqrt()).then_some((coefficient, d))
}

/// n = s² d with d square-free.
fn square_free(mut n: u64) -> (u64, u64) {
    let (mut s, mut d) = (1u64, 1u64);
    let mut p = 2u64;
    while p * p <= n {
        while n.is_multiple_of(p * p) {
            n /= p * p;
            s *= p;
        }
        if n.is_multiple_of(p) {
            n /= p;
            d *= p;
        }
        p += 1;
    }
    (s, d * n)
}

/// `x = (A + B √d) / q` with small q and B.
fn mixed(x: f64, d: u64) -> Option<(Rational, Rational)> {
    let root = (d as f64).sqrt();
    for q in 1..=LARGEST_MIXED_DENOMINATOR {
        let scaled = x * q as f64;
        for magnitude in 1..=4 * q {
            for b in [magnitude, -magnitude] {
                let a = (scaled - b as f64 * root).round();
                if (scaled - a - b as f64 * root).abs() <= TOLERANCE * q as f64 * x.abs().max(1.0) {
                    let q = BigInt::from(q);
                    return Some((
                        Rational::new(BigInt::from(a as i64), q.clone()),
                        Rational::new(BigInt::from(b), q),
                    ));
                }
            }
        }
    }
    None
}
