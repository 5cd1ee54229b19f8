//! Forward-mode differentiation of a tape (Griewank & Walther, *Evaluating Derivatives*, 2nd ed.,
//! ch. 3, the tangent mode): each node's value and its derivatives along several directions
//! at once, every instruction's tangent by the chain rule from its operands' tangents. The
//! derivatives are exact (no increment, no truncation): the rounding of the operations only.
//!
//! The values are recomputed here by the same operations as the tape's program rather than
//! read from its interpreter (`tape_code`), which does not write a product that only one sum
//! reads. A `Select` takes the tangent of the branch its test chooses, as `Pool::derivative`
//! differentiates each piece on its own.

use super::{Function, Step, Tape};

/// The values of a tape's nodes and their derivatives along `directions` directions, node k's
/// at `tangents[k * directions..(k + 1) * directions]`.
#[derive(Clone, Debug, Default)]
pub struct Tangents {
    pub directions: usize,
    pub values: Vec<f64>,
    pub tangents: Vec<f64>,
}

impl Tangents {
    /// The derivatives of node `k` (a position in the tape's order) along every direction.
    pub fn of(&self, k: usize) -> &[f64] {
        &self.tangents[k * self.directions..(k + 1) * self.directions]
    }
}

/// f'(x), for the tangent of `Apply(f, x)` whose value is `value` = f(x).
fn slope(f: Function, x: f64, value: f64) -> f64 {
    match f {
        Function::Sin => x.cos(),
        Function::Cos => -x.sin(),
        Function::Tan => 1.0 + value * value,
        Function::Asin => 1.0 / (1.0 - x * x).sqrt(),
        Function::Acos => -1.0 / (1.0 - x * x).sqrt(),
        Function::Atan => 1.0 / (1.0 + x * x),
        Function::Sqrt => 0.5 / value,
        Function::Exp => value,
        Function::Log => 1.0 / x,
        // As `Pool::derivative`'s a / |a|.
        Function::Abs => x / value,
        // A step function: flat between its jumps.
        Function::Floor => 0.0,
        Function::ExponentialProfile(profile) => profile.unnormalised_rate(x) / profile.total(),
    }
}

impl Tape {
    /// Evaluates the first `count` nodes of the order (as `eval_prefix_into`) with their
    /// derivatives: `symbols[i]` the value of symbol i, `symbol_tangents[i * d..(i + 1) * d]`
    /// its derivatives along the `d` = `out.directions` directions.
    pub fn tangents_prefix_into(
        &self,
        symbols: &[f64],
        symbol_tangents: &[f64],
        count: usize,
        out: &mut Tangents,
    ) {
        let d = out.directions;
        debug_assert_eq!(symbol_tangents.len(), symbols.len() * d);
        let nodes = self.order.len();
        out.values.clear();
        out.values.resize(nodes, 0.0);
        out.tangents.clear();
        out.tangents.resize(nodes * d, 0.0);
        let (values, tangents) = (&mut out.values, &mut out.tangents);
        for &(k, step) in self.program.iter().filter(|(k, _)| *k < count) {
            // The node's tangent is written after its operands' (the order is topological), so
            // it is split off the rest.
            let (before, rest) = tangents.split_at_mut(k * d);
            let own = &mut rest[..d];
            let t = |a: usize| &before[a * d..(a + 1) * d];
            // own = α t(a) + β t(b).
            let combine = |own: &mut [f64], (alpha, a): (f64, usize), (beta, b): (f64, usize)| {
                for ((o, x), y) in own.iter_mut().zip(t(a)).zip(t(b)) {
                    *o = alpha * x + beta * y;
                }
            };
            let scale = |own: &mut [f64], alpha: f64, a: usize| {
                for (o, x) in own.iter_mut().zip(t(a)) {
                    *o = alpha * x;
                }
            };
            values[k] = match step {
                Step::Constant(c) => c,
                Step::Symbol(i) => {
                    own.copy_from_slice(&symbol_tangents[i * d..(i + 1) * d]);
                    symbols[i]
                }
                Step::Add(a, b) => {
                    combine(own, (1.0, a), (1.0, b));
                    values[a] + values[b]
                }
                Step::Sub(a, b) => {
                    combine(own, (1.0, a), (-1.0, b));
                    values[a] - values[b]
                }
                Step::Mul(a, b) => {
                    combine(own, (values[b], a), (values[a], b));
                    values[a] * values[b]
                }
                Step::Neg(a) => {
                    scale(own, -1.0, a);
                    -values[a]
                }
                Step::Div(a, b) => {
                    let quotient = values[a] / values[b];
                    combine(own, (1.0 / values[b], a), (-quotient / values[b], b));
                    quotient
                }
                Step::Pow(a, b) => {
                    let (base, exponent) = (values[a], values[b]);
                    let power = base.powf(exponent);
                    // d(a^b) = b a^(b−1) da + a^b ln a db; the second term only where b varies
                    // (a constant exponent of a negative base has no logarithm to take).
                    let along_base = exponent * base.powf(exponent - 1.0);
                    if t(b).iter().all(|&x| x == 0.0) {
                        scale(own, along_base, a);
                    } else {
                        combine(own, (along_base, a), (power * base.ln(), b));
                    }
                    power
                }
                Step::Atan2(y, x) => {
                    let (vy, vx) = (values[y], values[x]);
                    let r2 = vy * vy + vx * vx;
                    combine(own, (vx / r2, y), (-vy / r2, x));
                    vy.atan2(vx)
                }
                Step::Apply(f, a) => {
                    let value = f.eval(values[a]);
                    scale(own, slope(f, values[a], value), a);
                    value
                }
                Step::Select(test, when_nonnegative, otherwise) => {
                    // A NaN test takes `otherwise`, as the evaluation does.
                    let chosen = match values[test] >= 0.0 {
                        true => when_nonnegative,
                        false => otherwise,
                    };
                    own.copy_from_slice(t(chosen));
                    values[chosen]
                }
            };
        }
    }
}

#[cfg(test)]
mod tests {
    use std::collections::HashMap;

    use num_dual::Dual64;

    use super::super::{ExponentialProfile, ExprId, Function, Pool, Tape};
    use super::Tangents;

    /// A root per instruction and function of the tape, of the symbols x and y.
    fn every_operation(pool: &mut Pool) -> (ExprId, ExprId, Vec<ExprId>) {
        let (x, y) = (pool.symbol("x"), pool.symbol("y"));
        let mut roots = vec![];
        let xy = pool.mul(x, y);
        roots.push(pool.add(xy, x));
        roots.push(pool.sub(x, y));
        roots.push(pool.div(x, y));
        let negated = pool.neg(xy);
        roots.push(pool.add(negated, y));
        roots.push(pool.pow(y, x));
        let three = pool.constant(3.0);
        roots.push(pool.pow(x, three));
        roots.push(pool.atan2(y, x));
        for f in [
            Function::Sin,
            Function::Cos,
            Function::Tan,
            Function::Asin,
            Function::Acos,
            Function::Atan,
            Function::Sqrt,
            Function::Exp,
            Function::Log,
            Function::Abs,
            Function::Floor,
            Function::ExponentialProfile(ExponentialProfile::new(2.0, 1.0)),
        ] {
            let half = pool.constant(0.5);
            let scaled = pool.mul(half, xy);
            roots.push(pool.apply(f, scaled));
        }
        let test = pool.sub(x, y);
        let square = pool.mul(x, x);
        roots.push(pool.select(test, square, xy));
        (x, y, roots)
    }

    /// Along x, along y, along x + 2y.
    const DIRECTIONS: [[f64; 2]; 3] = [[1.0, 0.0], [0.0, 1.0], [1.0, 2.0]];

    /// The tangents of `tape` at (vx, vy) along [`DIRECTIONS`].
    fn tangents_at(tape: &Tape, (vx, vy): (f64, f64)) -> Tangents {
        let symbol_tangents: Vec<f64> = (0..2)
            .flat_map(|s| DIRECTIONS.iter().map(move |d| d[s]))
            .collect();
        let mut out = Tangents {
            directions: DIRECTIONS.len(),
            ..Tangents::default()
        };
        tape.tangents_prefix_into(&[vx, vy], &symbol_tangents, tape.size(), &mut out);
        out
    }

    /// Every instruction's tangent against the symbolic derivative of the same DAG
    /// (`Pool::derivative`, a different algorithm: a new expression per derivative, evaluated
    /// by the tape's interpreter), along two directions (x, y) and a mixed one.
    #[test]
    fn tangents_agree_with_symbolic_derivatives() {
        let mut pool = Pool::new();
        let (x, y, roots) = every_operation(&mut pool);
        let (vx, vy) = (0.7, 0.45);
        let tape = Tape::new(&pool, &roots);
        let out = tangents_at(&tape, (vx, vy));
        let values = tape.eval(&[vx, vy]);
        for (r, &root) in roots.iter().enumerate() {
            let slot = tape.roots[r];
            assert!((out.values[slot] - values[r]).abs() <= 1e-15 * values[r].abs().max(1.0));
            let by_x = pool.derivative(root, x, &mut HashMap::new());
            let by_y = pool.derivative(root, y, &mut HashMap::new());
            let exact = Tape::new(&pool, &[by_x, by_y]).eval(&[vx, vy]);
            for (k, d) in DIRECTIONS.iter().enumerate() {
                let expected = d[0] * exact[0] + d[1] * exact[1];
                let found = out.of(slot)[k];
                assert!(
                    (found - expected).abs() <= 1e-14 * expected.abs().max(1.0),
                    "root {r} direction {k}: {found} against {expected}"
                );
            }
        }
    }

    /// Every instruction's tangent against the tape evaluated in dual numbers
    /// (`dual_evaluation`: num-dual's own rule for each operation), at two points (the second
    /// takes the other branch of the `Select` and of `Abs`), to 1e-12 of the derivative's size
    /// (absolute below 1).
    #[test]
    fn tangents_agree_with_dual_numbers() {
        let mut pool = Pool::new();
        let (_, _, roots) = every_operation(&mut pool);
        let tape = Tape::new(&pool, &roots);
        for (vx, vy) in [(0.7, 0.45), (-0.35, 0.6)] {
            let out = tangents_at(&tape, (vx, vy));
            for (k, d) in DIRECTIONS.iter().enumerate() {
                let symbols = [Dual64::new(vx, d[0]), Dual64::new(vy, d[1])];
                let duals = tape.eval_dual_prefix(&symbols, tape.size());
                for (r, &slot) in tape.roots.iter().enumerate() {
                    let (value, dual) = (out.values[slot], duals[slot]);
                    let (found, expected) = (out.of(slot)[k], dual.eps);
                    // Outside a function's domain (a root or logarithm of a negative number at
                    // the second point) both values are NaN, and the derivatives mean nothing.
                    assert_eq!(value.is_nan(), dual.re.is_nan(), "root {r}");
                    if value.is_nan() {
                        continue;
                    }
                    assert!(
                        (found - expected).abs() <= 1e-12 * expected.abs().max(1.0),
                        "root {r} at ({vx}, {vy}) direction {k}: {found} against {expected}"
                    );
                    assert!((value - dual.re).abs() <= 1e-14 * value.abs().max(1.0));
                }
            }
        }
    }
}
