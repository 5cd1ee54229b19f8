//! A tape evaluated in dual numbers (`num_dual::Dual64`, x + ε ẋ with ε² = 0), the oracle of
//! the tangent mode (`tangents`) in the tests: each operation is num-dual's own (its sum,
//! product, quotient, powers and elementary functions carry the derivative by their own
//! rules), so that it shares none of the tangent sweep's slopes and the two agree to round-off
//! only where both are right. One direction per evaluation.

use num_dual::{Dual64, DualNum};

use super::{Function, Step, Tape};

impl Tape {
    /// Every node's value and derivative along one direction, in the order's positions (as
    /// `Tangents::values`), symbol i being `symbols[i]`: the first `count` nodes, the others
    /// (and a negation that only subtractions read, which the program does not compute) zero.
    pub fn eval_dual_prefix(&self, symbols: &[Dual64], count: usize) -> Vec<Dual64> {
        let mut values = vec![Dual64::from_re(0.0); self.order.len()];
        for &(k, step) in self.program.iter().filter(|(k, _)| *k < count) {
            values[k] = match step {
                Step::Constant(c) => Dual64::from_re(c),
                Step::Symbol(i) => symbols[i],
                Step::Add(a, b) => values[a] + values[b],
                Step::Sub(a, b) => values[a] - values[b],
                Step::Mul(a, b) => values[a] * values[b],
                Step::Neg(a) => -values[a],
                Step::Div(a, b) => values[a] / values[b],
                // A constant exponent: a negative base has a power but no logarithm.
                Step::Pow(a, b) if values[b].eps == 0.0 => values[a].powf(values[b].re),
                Step::Pow(a, b) => values[a].powd(values[b]),
                Step::Atan2(y, x) => values[y].atan2(values[x]),
                Step::Apply(f, a) => apply(f, values[a]),
                Step::Select(test, when_nonnegative, otherwise) => match values[test].re >= 0.0 {
                    true => values[when_nonnegative],
                    false => values[otherwise],
                },
            };
        }
        values
    }
}

/// f(x) in dual numbers.
fn apply(f: Function, x: Dual64) -> Dual64 {
    match f {
        Function::Sin => x.sin(),
        Function::Cos => x.cos(),
        Function::Tan => x.tan(),
        Function::Asin => x.asin(),
        Function::Acos => x.acos(),
        Function::Atan => x.atan(),
        Function::Sqrt => x.sqrt(),
        Function::Exp => x.exp(),
        Function::Log => x.ln(),
        Function::Abs => match x.re >= 0.0 {
            true => x,
            false => -x,
        },
        Function::Floor => Dual64::from_re(x.re.floor()),
        // The position is a quadrature of the rate r over R: its derivative is the integrand
        // at the upper limit (the fundamental theorem), r(τ) = exp(−σ (1 − g)/g^λ) with
        // g = 4τ(1 − τ), here in dual numbers; 0 outside (0, 1).
        Function::ExponentialProfile(profile) => {
            let g = x * (-x + 1.0) * 4.0;
            let rate = match g.re > 0.0 {
                true => ((-g + 1.0) * (-profile.sigma()) / g.powf(profile.lambda())).exp(),
                false => Dual64::from_re(0.0),
            };
            Dual64::new(profile.value(x.re), rate.re * x.eps / profile.total())
        }
    }
}
