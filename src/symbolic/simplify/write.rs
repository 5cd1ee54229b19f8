//! A polynomial written back as expressions, its common factors taken out: the atom (or wave)
//! that most terms share is factored out of them, then again inside and among the others (a
//! greedy multivariate Horner scheme), and a coefficient every term of a sum shares up to its
//! sign multiplies the sum once.

use rustc_hash::FxHashMap;

use super::polynomial::{AngleId, Angles, Polynomial, Wave};
use crate::symbolic::expr::{ExprId, Function, Pool};

/// One term being written: its coefficient and its factors (the wave among them as a node).
#[derive(Clone)]
struct Term {
    coefficient: f64,
    /// By node, increasing, without zero exponents.
    factors: Vec<(ExprId, i32)>,
}

/// Writes polynomials into `pool`, each wave built once.
#[derive(Clone)]
pub struct Writer {
    waves: FxHashMap<(Wave, AngleId), ExprId>,
}

impl Writer {
    pub fn new() -> Writer {
        Writer {
            waves: FxHashMap::default(),
        }
    }

    /// The polynomial written in `pool`. Its terms are taken in the order of their monomials
    /// with the angles in an order of their linear forms (`Angles::rank`), not of their
    /// numbers (which depend on the order the pass met them): the greedy factoring breaks ties
    /// by this order, so the written form does not depend on the interning.
    pub fn write(&mut self, pool: &mut Pool, polynomial: &Polynomial, angles: &Angles) -> ExprId {
        let mut monomials: Vec<_> = polynomial.terms.iter().collect();
        monomials.sort_by(|(a, _), (b, _)| {
            a.factors
                .cmp(&b.factors)
                .then_with(|| match (a.wave, b.wave) {
                    (Some((x, i)), Some((y, j))) => x.cmp(&y).then_with(|| angles.rank(i, j)),
                    (x, y) => x.cmp(&y),
                })
        });
        let terms: Vec<Term> = monomials
            .into_iter()
            .map(|(monomial, &coefficient)| {
                let mut factors = monomial.factors.clone();
                if let Some((wave, angle)) = monomial.wave {
                    let node = self.wave(pool, wave, angle, angles);
                    factors.push((node, 1));
                    factors.sort_unstable();
                }
                Term {
                    coefficient,
                    factors,
                }
            })
            .collect();
        write_terms(pool, terms)
    }

    fn wave(&mut self, pool: &mut Pool, wave: Wave, id: AngleId, angles: &Angles) -> ExprId {
        if let Some(&node) = self.waves.get(&(wave, id)) {
            return node;
        }
        let angle = angles.get(id);
        let terms = angle.terms.iter().map(|&(atom, c)| Term {
            coefficient: c.get(),
            factors: vec![(atom, 1)],
        });
        let offset = (angle.offset.get() != 0.0).then(|| Term {
            coefficient: angle.offset.get(),
            factors: Vec::new(),
        });
        let argument = write_sum(pool, terms.chain(offset).collect());
        let function = match wave {
            Wave::Sin => Function::Sin,
            Wave::Cos => Function::Cos,
        };
        let node = pool.apply(function, argument);
        self.waves.insert((wave, id), node);
        node
    }
}

/// The terms' sum with common factors taken out.
fn write_terms(pool: &mut Pool, terms: Vec<Term>) -> ExprId {
    if terms.len() < 2 {
        return write_sum(pool, terms);
    }
    // The factor (a node, on the numerator's or the divisor's side) most terms share.
    let mut shared: FxHashMap<(ExprId, bool), usize> = FxHashMap::default();
    for term in &terms {
        for &(node, exponent) in &term.factors {
            *shared.entry((node, exponent > 0)).or_insert(0) += 1;
        }
    }
    let best = shared
        .into_iter()
        .filter(|&(_, count)| count >= 2)
        .max_by(|(a, x), (b, y)| x.cmp(y).then(b.cmp(a)));
    let Some(((factor, numerator), _)) = best else {
        return write_sum(pool, terms);
    };
    let (mut with, without): (Vec<Term>, Vec<Term>) = terms
        .into_iter()
        .partition(|t| (t.factors.iter()).any(|&(node, e)| node == factor && (e > 0) == numerator));
    for term in &mut with {
        for (node, exponent) in &mut term.factors {
            if *node == factor {
                *exponent += if numerator { -1 } else { 1 };
            }
        }
        term.factors.retain(|&(_, e)| e != 0);
    }
    let inner = write_terms(pool, with);
    let factored = if numerator {
        pool.mul(factor, inner)
    } else {
        pool.div(inner, factor)
    };
    if without.is_empty() {
        return factored;
    }
    let rest = write_terms(pool, without);
    pool.add(factored, rest)
}

/// The sum of the terms as they are; a magnitude of coefficient every term shares multiplies
/// the sum once.
fn write_sum(pool: &mut Pool, mut terms: Vec<Term>) -> ExprId {
    let common = terms.first().map(|t| t.coefficient.abs()).unwrap_or(1.0);
    let scale = if terms.len() > 1 && terms.iter().all(|t| t.coefficient.abs() == common) {
        for term in &mut terms {
            term.coefficient = term.coefficient.signum();
        }
        common
    } else {
        1.0
    };
    // Positive terms first, so that the negative ones are subtractions.
    terms.sort_by_key(|t| t.coefficient < 0.0);
    let mut sum: Option<ExprId> = None;
    for term in terms {
        sum = Some(match sum {
            None => write_monomial(pool, &term),
            Some(sum) if term.coefficient < 0.0 => {
                let positive = Term {
                    coefficient: -term.coefficient,
                    ..term
                };
                let magnitude = write_monomial(pool, &positive);
                pool.sub(sum, magnitude)
            }
            Some(sum) => {
                let next = write_monomial(pool, &term);
                pool.add(sum, next)
            }
        });
    }
    let sum = sum.unwrap_or_else(|| pool.constant(0.0));
    let scale = pool.constant(scale);
    pool.mul(scale, sum)
}

/// coefficient · Π numerator factors / Π divisor factors.
fn write_monomial(pool: &mut Pool, term: &Term) -> ExprId {
    let power = |pool: &mut Pool, node: ExprId, exponent: i32| {
        if exponent == 1 {
            node
        } else {
            let e = pool.constant(f64::from(exponent));
            pool.pow(node, e)
        }
    };
    let mut numerator: Option<ExprId> = None;
    let mut divisor: Option<ExprId> = None;
    for &(node, exponent) in &term.factors {
        let (side, exponent) = if exponent > 0 {
            (&mut numerator, exponent)
        } else {
            (&mut divisor, -exponent)
        };
        let factor = power(pool, node, exponent);
        *side = Some(match *side {
            None => factor,
            Some(product) => pool.mul(product, factor),
        });
    }
    let coefficient = pool.constant(term.coefficient);
    let numerator = match numerator {
        Some(product) => pool.mul(coefficient, product),
        None => coefficient,
    };
    match divisor {
        Some(divisor) => pool.div(numerator, divisor),
        None => numerator,
    }
}
