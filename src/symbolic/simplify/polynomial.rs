//! The normal form the simplifier computes per node: a polynomial whose terms are a real
//! coefficient times a product of atoms (nodes it does not look into, with integer exponents,
//! negative for divisors) times at most one sine or cosine of a linear form in atoms.
//!
//! Products of sines and cosines are turned into sums (sin X sin Y = ½ cos(X − Y) − ½ cos(X + Y),
//! …), so a term holds one wave and trigonometric polynomials in the coordinates have a single
//! form, their Fourier series: sin² + cos² = 1, the angle sums and their differences, and every
//! cancellation between them come out of collecting like terms. The angles are put with a
//! positive leading coefficient (cos(−X) = cos X, sin(−X) = −sin X) so that each wave has one
//! name.
//!
//! The angles are interned (`Angles`): a term's key holds an angle's number, not its linear
//! form, so that comparing and hashing keys costs the same whatever the angle's length (a
//! chain's angles are sums of up to n coordinates), and the sums and differences of two angles
//! the product-to-sum formulas take are formed once per pair.
//!
//! Coefficients are floating-point: products by ½ are exact; sums of coefficients that cancel
//! to within a few units in the last place of the terms are taken as 0 (a change of the
//! value at round-off, the same as evaluating the terms in another order).

use std::cmp::Ordering;
use std::collections::BTreeMap;

use rustc_hash::FxHashMap;

use crate::symbolic::expr::ExprId;

/// A real number as a key of ordered maps: its bits, with −0 stored as +0.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Real(u64);

impl Real {
    pub fn new(x: f64) -> Real {
        Real(if x == 0.0 { 0.0f64 } else { x }.to_bits())
    }

    pub fn get(self) -> f64 {
        f64::from_bits(self.0)
    }
}

/// A linear form Σ cₖ aₖ + c₀ over atoms aₖ: the argument of a sine or cosine.
#[derive(Clone, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Angle {
    /// By atom, increasing, without zero coefficients.
    pub terms: Vec<(ExprId, Real)>,
    pub offset: Real,
}

impl Angle {
    /// The terms of `self + sign · other` into `terms` (cleared first), merging the two sorted
    /// lists; the offset is returned.
    fn combined_into(&self, other: &Angle, sign: f64, terms: &mut Vec<(ExprId, Real)>) -> Real {
        terms.clear();
        let (mut left, mut right) = (self.terms.iter().peekable(), other.terms.iter().peekable());
        loop {
            let (atom, c) = match (left.peek(), right.peek()) {
                (None, None) => break,
                (Some(&&(a, x)), Some(&&(b, y))) => match a.cmp(&b) {
                    Ordering::Less => {
                        left.next();
                        (a, x.get())
                    }
                    Ordering::Greater => {
                        right.next();
                        (b, sign * y.get())
                    }
                    Ordering::Equal => {
                        left.next();
                        right.next();
                        (a, x.get() + sign * y.get())
                    }
                },
                (Some(&&(a, x)), None) => {
                    left.next();
                    (a, x.get())
                }
                (None, Some(&&(b, y))) => {
                    right.next();
                    (b, sign * y.get())
                }
            };
            if c != 0.0 {
                terms.push((atom, Real::new(c)));
            }
        }
        Real::new(self.offset.get() + sign * other.offset.get())
    }
}

/// The hash of a linear form (its terms and offset): the key angles are found by, and the
/// writer's order of them.
fn form_hash(terms: &[(ExprId, Real)], offset: Real) -> u64 {
    use std::hash::BuildHasher;
    rustc_hash::FxBuildHasher.hash_one((terms, offset))
}

/// An angle's number in its `Angles`: equal angles have one number.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct AngleId(u32);

/// An angle as a wave reads it: a number (the wave is evaluated), or a named angle, itself or
/// its opposite.
#[derive(Clone, Copy, Debug)]
pub enum Named {
    Constant(f64),
    Angle { id: AngleId, negated: bool },
}

/// The angles of one pass, each named once with a positive leading coefficient, and the sums
/// and differences of pairs already formed.
#[derive(Default)]
pub struct Angles {
    forms: Vec<Angle>,
    /// By angle, the hash of its linear form (`form_hash`).
    hashes: Vec<u64>,
    /// Each angle's number, found by its form's hash and compared by its form in `forms`.
    ids: hashbrown::HashTable<AngleId>,
    /// `x + y` and `x − y` by `(x, y, difference)`.
    combinations: FxHashMap<(AngleId, AngleId, bool), Named>,
    /// The terms of the sum or difference being formed: one buffer for all, so that an angle
    /// already named costs no allocation.
    scratch: Vec<(ExprId, Real)>,
}

impl Angles {
    /// The linear form of angle `id`.
    pub fn get(&self, id: AngleId) -> &Angle {
        &self.forms[id.0 as usize]
    }

    /// An order of the angles that depends on their linear forms alone, not on the order the
    /// pass named them (the writer sorts a form's waves by it, so that the written form does
    /// not depend on the interning): by the forms' hashes, and by the forms themselves on the
    /// rare equal hashes. Constant time: the forms' own order costs their common prefix, and a
    /// chain's angles share long ones (q₁ + … + qₖ against q₁ + … + qⱼ; at n = 100, 31
    /// coordinates per comparison). Ordered by hash, an angle needs no place among the others
    /// when it is named: no ordered map of the angles (BENCHMARKS.md, "The simplifier beyond
    /// 100 links").
    pub fn rank(&self, x: AngleId, y: AngleId) -> Ordering {
        let (i, j) = (x.0 as usize, y.0 as usize);
        (self.hashes[i].cmp(&self.hashes[j])).then_with(|| self.forms[i].cmp(&self.forms[j]))
    }

    /// `angle`'s name: a number when it has no atom, else its number or its opposite's.
    pub fn name(&mut self, mut angle: Angle) -> Named {
        self.named(&mut angle.terms, angle.offset)
    }

    /// The name of the linear form of `terms` and `offset`; `terms` is turned to the positive
    /// form in place, and copied only when the angle is new.
    fn named(&mut self, terms: &mut [(ExprId, Real)], offset: Real) -> Named {
        let Some(&(_, leading)) = terms.first() else {
            return Named::Constant(offset.get());
        };
        let negated = leading.get() < 0.0;
        let offset = if negated {
            for (_, c) in terms.iter_mut() {
                *c = Real::new(-c.get());
            }
            Real::new(-offset.get())
        } else {
            offset
        };
        let hash = form_hash(terms, offset);
        let forms = &self.forms;
        let same = |id: &AngleId| {
            let form = &forms[id.0 as usize];
            form.offset == offset && form.terms == terms
        };
        let id = match self.ids.find(hash, same) {
            Some(&id) => id,
            None => {
                let id = AngleId(self.forms.len() as u32);
                self.forms.push(Angle {
                    terms: terms.to_vec(),
                    offset,
                });
                self.hashes.push(hash);
                let hashes = &self.hashes;
                (self.ids).insert_unique(hash, id, |id| hashes[id.0 as usize]);
                id
            }
        };
        Named::Angle { id, negated }
    }

    /// `x + y`, or `x − y` when `difference`, named.
    fn combined(&mut self, x: AngleId, y: AngleId, difference: bool) -> Named {
        if let Some(&named) = self.combinations.get(&(x, y, difference)) {
            return named;
        }
        let sign = if difference { -1.0 } else { 1.0 };
        let mut terms = std::mem::take(&mut self.scratch);
        let offset = self.get(x).combined_into(self.get(y), sign, &mut terms);
        let named = self.named(&mut terms, offset);
        self.scratch = terms;
        self.combinations.insert((x, y, difference), named);
        named
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Wave {
    Sin,
    Cos,
}

impl Wave {
    fn eval(self, x: f64) -> f64 {
        match self {
            Wave::Sin => x.sin(),
            Wave::Cos => x.cos(),
        }
    }
}

/// A product of atoms to integer powers and at most one wave.
#[derive(Clone, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Monomial {
    /// By atom, increasing, without zero exponents.
    pub factors: Vec<(ExprId, i32)>,
    pub wave: Option<(Wave, AngleId)>,
}

impl Monomial {
    const ONE: Monomial = Monomial {
        factors: Vec::new(),
        wave: None,
    };

    /// The product of the two monomials' atoms, exponents added (a merge of the two sorted
    /// lists).
    fn factors_times(&self, other: &Monomial) -> Vec<(ExprId, i32)> {
        let (a, b) = (&self.factors, &other.factors);
        let mut merged = Vec::with_capacity(a.len() + b.len());
        let (mut i, mut j) = (0, 0);
        while i < a.len() && j < b.len() {
            match a[i].0.cmp(&b[j].0) {
                Ordering::Less => {
                    merged.push(a[i]);
                    i += 1;
                }
                Ordering::Greater => {
                    merged.push(b[j]);
                    j += 1;
                }
                Ordering::Equal => {
                    let exponent = a[i].1 + b[j].1;
                    if exponent != 0 {
                        merged.push((a[i].0, exponent));
                    }
                    i += 1;
                    j += 1;
                }
            }
        }
        merged.extend_from_slice(&a[i..]);
        merged.extend_from_slice(&b[j..]);
        merged
    }
}

/// `coefficient · wave(angle)` in its one name: a constant angle evaluated, a negative one
/// turned positive.
fn named_wave(wave: Wave, angle: Named, coefficient: f64) -> (f64, Option<(Wave, AngleId)>) {
    match (angle, wave) {
        (Named::Constant(x), _) => (coefficient * wave.eval(x), None),
        (Named::Angle { id, negated: false }, _) | (Named::Angle { id, .. }, Wave::Cos) => {
            (coefficient, Some((wave, id)))
        }
        (Named::Angle { id, negated: true }, Wave::Sin) => (-coefficient, Some((Wave::Sin, id))),
    }
}

/// The product of two waves as a sum of two (product-to-sum formulas).
fn wave_product(
    (left, x): (Wave, AngleId),
    (right, y): (Wave, AngleId),
    angles: &mut Angles,
) -> [(f64, Wave, Named); 2] {
    let (sum, difference) = (angles.combined(x, y, false), angles.combined(x, y, true));
    match (left, right) {
        (Wave::Sin, Wave::Sin) => [(0.5, Wave::Cos, difference), (-0.5, Wave::Cos, sum)],
        (Wave::Cos, Wave::Cos) => [(0.5, Wave::Cos, difference), (0.5, Wave::Cos, sum)],
        (Wave::Sin, Wave::Cos) => [(0.5, Wave::Sin, sum), (0.5, Wave::Sin, difference)],
        (Wave::Cos, Wave::Sin) => [(0.5, Wave::Sin, sum), (-0.5, Wave::Sin, difference)],
    }
}

/// Σ coefficient · monomial, without zero coefficients.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Polynomial {
    pub terms: BTreeMap<Monomial, f64>,
}

/// How close to 0, relative to the terms added, a sum of coefficients is taken as 0: a few
/// units in the last place.
const CANCELLATION: f64 = 8.0 * f64::EPSILON;

impl Polynomial {
    pub fn constant(c: f64) -> Polynomial {
        let mut p = Polynomial::default();
        p.add_term(Monomial::ONE, c);
        p
    }

    /// `atom ^ exponent`.
    pub fn atom(atom: ExprId, exponent: i32) -> Polynomial {
        let mut p = Polynomial::default();
        let monomial = Monomial {
            factors: vec![(atom, exponent)],
            wave: None,
        };
        p.add_term(monomial, 1.0);
        p
    }

    /// `wave(angle)`.
    pub fn wave(wave: Wave, angle: Angle, angles: &mut Angles) -> Polynomial {
        let mut p = Polynomial::default();
        let (c, wave) = named_wave(wave, angles.name(angle), 1.0);
        p.add_term(
            Monomial {
                factors: Vec::new(),
                wave,
            },
            c,
        );
        p
    }

    pub fn len(&self) -> usize {
        self.terms.len()
    }

    fn add_term(&mut self, monomial: Monomial, c: f64) {
        if c == 0.0 {
            return;
        }
        match self.terms.entry(monomial) {
            std::collections::btree_map::Entry::Vacant(entry) => {
                entry.insert(c);
            }
            std::collections::btree_map::Entry::Occupied(mut entry) => {
                let old = *entry.get();
                let sum = old + c;
                if sum.abs() <= CANCELLATION * old.abs().max(c.abs()) {
                    entry.remove();
                } else {
                    *entry.get_mut() = sum;
                }
            }
        }
    }

    /// `self + scale · other`.
    pub fn add_scaled(&mut self, other: &Polynomial, scale: f64) {
        for (monomial, &c) in &other.terms {
            self.add_term(monomial.clone(), scale * c);
        }
    }

    pub fn scaled(mut self, scale: f64) -> Polynomial {
        if scale == 0.0 {
            return Polynomial::default();
        }
        for c in self.terms.values_mut() {
            *c *= scale;
        }
        self
    }

    /// The product, or `None` when forming it would take more than `work` products of terms
    /// or give more than `limit` terms: the caller then keeps the operation as it is.
    pub fn times(
        &self,
        other: &Polynomial,
        work: usize,
        limit: usize,
        angles: &mut Angles,
    ) -> Option<Polynomial> {
        if self.len() * other.len() > work {
            return None;
        }
        let mut product = Polynomial::default();
        for (a, &ca) in &self.terms {
            for (b, &cb) in &other.terms {
                let factors = a.factors_times(b);
                let c = ca * cb;
                match (a.wave, b.wave) {
                    (None, None) => product.add_term(
                        Monomial {
                            factors,
                            wave: None,
                        },
                        c,
                    ),
                    (Some(w), None) | (None, Some(w)) => product.add_term(
                        Monomial {
                            factors,
                            wave: Some(w),
                        },
                        c,
                    ),
                    (Some(x), Some(y)) => {
                        for (half, wave, angle) in wave_product(x, y, angles) {
                            let (c, wave) = named_wave(wave, angle, c * half);
                            let factors = factors.clone();
                            product.add_term(Monomial { factors, wave }, c);
                        }
                    }
                }
            }
            if product.len() > 2 * limit {
                return None;
            }
        }
        (product.len() <= limit).then_some(product)
    }

    /// The value when the polynomial is a number.
    pub fn as_constant(&self) -> Option<f64> {
        match self.terms.len() {
            0 => Some(0.0),
            1 => self.terms.get(&Monomial::ONE).copied(),
            _ => None,
        }
    }

    /// The polynomial as a linear form in atoms, when it is one: an angle.
    pub fn as_angle(&self) -> Option<Angle> {
        let mut terms = Vec::new();
        let mut offset = 0.0;
        for (monomial, &c) in &self.terms {
            match (monomial.factors.as_slice(), &monomial.wave) {
                ([], None) => offset = c,
                (&[(atom, 1)], None) => terms.push((atom, Real::new(c))),
                _ => return None,
            }
        }
        Some(Angle {
            terms,
            offset: Real::new(offset),
        })
    }

    /// The single monomial without a wave and its coefficient, when the polynomial is one.
    pub fn as_monomial(&self) -> Option<(&[(ExprId, i32)], f64)> {
        match self.terms.iter().next() {
            Some((monomial, &c)) if self.terms.len() == 1 && monomial.wave.is_none() => {
                Some((&monomial.factors, c))
            }
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::symbolic::expr::Pool;

    fn angle(terms: &[(ExprId, f64)], offset: f64) -> Angle {
        Angle {
            terms: terms.iter().map(|&(a, c)| (a, Real::new(c))).collect(),
            offset: Real::new(offset),
        }
    }

    fn id(named: Named) -> (AngleId, bool) {
        match named {
            Named::Angle { id, negated } => (id, negated),
            Named::Constant(c) => panic!("a constant angle {c}"),
        }
    }

    #[test]
    fn an_angle_has_one_name_whatever_its_road() {
        let mut pool = Pool::new();
        let (x, y, z) = (pool.symbol("x"), pool.symbol("y"), pool.symbol("z"));
        let mut angles = Angles::default();
        let (xy, _) = id(angles.name(angle(&[(x, 1.0), (y, 1.0)], 0.0)));
        let (yz, _) = id(angles.name(angle(&[(y, 1.0), (z, 1.0)], 0.5)));
        // (x + y) − (y + z + ½) formed from the two, then named directly, then its opposite.
        let formed = id(angles.combined(xy, yz, true));
        let direct = id(angles.name(angle(&[(x, 1.0), (z, -1.0)], -0.5)));
        let opposite = id(angles.name(angle(&[(x, -1.0), (z, 1.0)], 0.5)));
        assert_eq!(formed, direct);
        assert_eq!(opposite, (direct.0, true));
        assert_eq!(angles.get(direct.0), &angle(&[(x, 1.0), (z, -1.0)], -0.5));
        // (y + z + ½) − (y + z + ½) has no atom: a number.
        assert!(matches!(
            angles.combined(yz, yz, true),
            Named::Constant(0.0)
        ));
    }

    #[test]
    fn the_angles_order_does_not_depend_on_the_naming_order() {
        let mut pool = Pool::new();
        let q: Vec<ExprId> = (0..6).map(|i| pool.symbol(&format!("q{i}"))).collect();
        // A chain's angles, q₀ + … + qₖ, and some differences.
        let mut forms: Vec<Angle> = (1..=6)
            .map(|k| angle(&q[..k].iter().map(|&a| (a, 1.0)).collect::<Vec<_>>(), 0.0))
            .collect();
        forms.push(angle(&[(q[1], 1.0), (q[4], -2.0)], 0.0));
        forms.push(angle(&[(q[2], 3.0)], 1.0));
        let ranks = |order: &mut dyn Iterator<Item = usize>| {
            let mut angles = Angles::default();
            let mut ids = vec![None; forms.len()];
            for k in order {
                ids[k] = Some(id(angles.name(forms[k].clone())).0);
            }
            let ids: Vec<AngleId> = ids.into_iter().map(|i| i.expect("named")).collect();
            let pairs = (0..forms.len()).flat_map(|i| (0..forms.len()).map(move |j| (i, j)));
            pairs
                .map(|(i, j)| angles.rank(ids[i], ids[j]))
                .collect::<Vec<_>>()
        };
        let forward = ranks(&mut (0..forms.len()));
        let backward = ranks(&mut (0..forms.len()).rev());
        assert_eq!(forward, backward);
    }
}
