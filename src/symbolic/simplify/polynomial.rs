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
    /// `self + sign · other`, merging the two sorted lists of terms.
    fn combined(&self, other: &Angle, sign: f64) -> Angle {
        let mut terms = Vec::with_capacity(self.terms.len() + other.terms.len());
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
        Angle {
            terms,
            offset: Real::new(self.offset.get() + sign * other.offset.get()),
        }
    }

    fn negated(&self) -> Angle {
        Angle {
            terms: self.terms.iter().map(|&(a, c)| (a, Real::new(-c.get()))).collect(),
            offset: Real::new(-self.offset.get()),
        }
    }

    /// Whether the first coefficient (or the offset, when there is no atom) is negative.
    fn is_negative(&self) -> bool {
        match self.terms.first() {
            Some(&(_, c)) => c.get() < 0.0,
            None => self.offset.get() < 0.0,
        }
    }
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
    ids: FxHashMap<Angle, AngleId>,
    /// `x + y` and `x − y` by `(x, y, difference)`.
    combinations: FxHashMap<(AngleId, AngleId, bool), Named>,
    /// The angles in the order of their linear forms, and by angle a label increasing in that
    /// order (`rank`).
    order: BTreeMap<Angle, AngleId>,
    labels: Vec<u64>,
}

impl Angles {
    /// The linear form of angle `id`.
    pub fn get(&self, id: AngleId) -> &Angle {
        &self.forms[id.0 as usize]
    }

    /// The order of two angles' linear forms, in constant time: the writer sorts a form's waves
    /// by it. Comparing the forms themselves costs their common prefix, and a chain's angles
    /// share long ones (q₁ + … + qₖ against q₁ + … + qⱼ): at n = 100, 31 coordinates per
    /// comparison and 250 per input node, against 2 at n = 5.
    pub fn rank(&self, x: AngleId, y: AngleId) -> Ordering {
        self.labels[x.0 as usize].cmp(&self.labels[y.0 as usize])
    }

    /// A label for the new angle `angle`, numbered `id`, between those of the angles before
    /// and after it in the order of linear forms (list labelling: a label is found once per
    /// angle, in the middle of its neighbours' or a fixed step past the last or before the
    /// first, and all are spread evenly again when two neighbours leave no label between
    /// them; Dietz and Sleator, "Two algorithms for maintaining order in a list", STOC 1987,
    /// give the bounds of its refinements).
    fn label(&mut self, angle: &Angle, id: AngleId) {
        use std::ops::Bound::{Excluded, Unbounded};
        /// The step past the last label or before the first: angles met in increasing order
        /// (a chain's, often) take 2³² labels each before the labels are spread again.
        const STEP: u64 = 1 << 32;
        let labels = &self.labels;
        let below = (self.order.range::<Angle, _>((Unbounded, Excluded(angle))).next_back())
            .map(|(_, &id)| labels[id.0 as usize]);
        let above = (self.order.range::<Angle, _>((Excluded(angle), Unbounded)).next())
            .map(|(_, &id)| labels[id.0 as usize]);
        let label = match (below, above) {
            (None, None) => u64::MAX / 2,
            (Some(b), None) => b + STEP.min((u64::MAX - b) / 2),
            (None, Some(a)) => a - STEP.min(a / 2),
            (Some(b), Some(a)) => b + (a - b) / 2,
        };
        self.order.insert(angle.clone(), id);
        self.labels.push(label);
        let fits = below.is_none_or(|b| b < label) && above.is_none_or(|a| label < a);
        if !fits {
            let spacing = u64::MAX / (self.order.len() as u64 + 1);
            for (k, &id) in self.order.values().enumerate() {
                self.labels[id.0 as usize] = (k as u64 + 1) * spacing;
            }
        }
    }

    /// `angle`'s name: a number when it has no atom, else its number or its opposite's.
    pub fn name(&mut self, angle: Angle) -> Named {
        if angle.terms.is_empty() {
            return Named::Constant(angle.offset.get());
        }
        let negated = angle.is_negative();
        let angle = if negated { angle.negated() } else { angle };
        let id = match self.ids.get(&angle) {
            Some(&id) => id,
            None => {
                let id = AngleId(self.forms.len() as u32);
                self.label(&angle, id);
                self.forms.push(angle.clone());
                self.ids.insert(angle, id);
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
        let angle = self.get(x).combined(self.get(y), sign);
        let named = self.name(angle);
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
                    (None, None) => product.add_term(Monomial { factors, wave: None }, c),
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
