//! The simplifier of the expression graph: every node, operands first, is put in a normal form
//! (`polynomial`: a sum of coefficients times products of atoms and of one sine or cosine of a
//! linear form), so that like terms collect, sums and products cancel, numbers fold and the
//! trigonometric identities (sin² + cos² = 1, the angle sums) hold by construction; the roots
//! are then written back with their common factors taken out (`write`).
//!
//! The cost stays linear in the graph: a node whose form would pass `TERMS` terms (or take more
//! than `WORK` products of terms) is not expanded but kept as the operation on its operands'
//! simplified nodes, an atom for the nodes that use it. So each node costs a bounded amount and
//! deep chains (a 100-link pendulum's) are simplified near their leaves and shared above.
//!
//! Values: like computer algebra systems, the simplifier takes x − x = 0, 0 · x = 0 and
//! x / x = 1 for every x, so the result equals the input wherever the input is finite, and may
//! be finite where the input divided by zero. Coefficients are floating-point (see
//! `polynomial`): the result equals the input to round-off.

mod polynomial;
mod write;

use std::collections::HashMap;

use polynomial::{Polynomial, Wave};
use write::Writer;

use super::equations::Equations;
use super::expr::{topological_order, ExprId, Function, Node, Pool};

/// The most terms a node's normal form may have before the node is kept as an atom.
const TERMS: usize = 64;
/// The most products of terms forming one product may take.
const WORK: usize = 4096;
/// The largest power of a sum expanded.
const POWER: i32 = 4;

/// The roots of `pool` simplified, in a new pool with the same symbols in the same order (so
/// that values of the symbols are given alike to both).
pub fn simplify(pool: &Pool, roots: &[ExprId]) -> (Pool, Vec<ExprId>) {
    let mut pass = Pass::new(pool);
    let order = topological_order(roots, |id| pool.operands(id));
    // How many nodes still to simplify read each node: a form is dropped after its last reader.
    let kept: std::collections::HashSet<ExprId> = roots.iter().copied().collect();
    let mut readers: HashMap<ExprId, usize> = HashMap::new();
    for &id in &order {
        for operand in pool.operands(id) {
            *readers.entry(operand).or_insert(0) += 1;
        }
    }
    for &id in &order {
        let form = pass.form_of(id);
        pass.forms.insert(id, form);
        for operand in pool.operands(id) {
            let left = readers.get_mut(&operand).expect("counted");
            *left -= 1;
            if *left == 0 && !kept.contains(&operand) {
                pass.forms.remove(&operand);
            }
        }
    }
    let simplified = roots.iter().map(|&root| pass.written(root)).collect();
    (pass.out, simplified)
}

/// The equations with every expression simplified, in a new pool.
pub fn simplify_equations(equations: &Equations) -> Equations {
    let roots = equations.roots();
    let (pool, simplified) = simplify(&equations.pool, &roots);
    let mut rest = simplified.as_slice();
    let mut take = |count: usize| {
        let (head, tail) = rest.split_at(count);
        rest = tail;
        head.to_vec()
    };
    Equations {
        variables: equations.variables.clone(),
        mass: take(equations.mass.len()),
        second_member: take(equations.second_member.len()),
        forces: take(equations.forces.len()),
        constraints: take(equations.constraints.len()),
        constraint_bias: take(equations.constraint_bias.len()),
        constraint_names: equations.constraint_names.clone(),
        accelerations: equations.accelerations.as_ref().map(|a| take(a.len())),
        pool,
    }
}

struct Pass<'a> {
    input: &'a Pool,
    out: Pool,
    /// The normal form of each input node simplified and still to be read.
    forms: HashMap<ExprId, Polynomial>,
    /// Each input node written in `out`.
    nodes: HashMap<ExprId, ExprId>,
    writer: Writer,
}

impl Pass<'_> {
    fn new(input: &Pool) -> Pass<'_> {
        let mut out = Pool::new();
        for i in 0..input.symbol_count() as u32 {
            out.symbol(input.symbol_name(i));
        }
        Pass {
            input,
            out,
            forms: HashMap::new(),
            nodes: HashMap::new(),
            writer: Writer::new(),
        }
    }

    fn form(&self, id: ExprId) -> &Polynomial {
        &self.forms[&id]
    }

    /// The input node `id` written in `out` from its normal form (once).
    fn written(&mut self, id: ExprId) -> ExprId {
        if let Some(&node) = self.nodes.get(&id) {
            return node;
        }
        let form = self.forms.get(&id).expect("formed before it is written");
        let node = self.writer.write(&mut self.out, form);
        self.nodes.insert(id, node);
        node
    }

    /// A node of `out` as a form: a number, or an atom.
    fn atom(&self, node: ExprId) -> Polynomial {
        match self.out.as_constant(node) {
            Some(c) if c.is_finite() => Polynomial::constant(c),
            _ => Polynomial::atom(node, 1),
        }
    }

    /// The normal form of input node `id`, whose operands have theirs.
    fn form_of(&mut self, id: ExprId) -> Polynomial {
        let expanded = match self.input.node(id) {
            Node::Constant(bits) => {
                let c = f64::from_bits(bits);
                let node = self.out.constant(c);
                Some(self.atom(node))
            }
            Node::Symbol(i) => {
                let node = self.out.symbol(self.input.symbol_name(i));
                Some(Polynomial::atom(node, 1))
            }
            Node::Add(a, b) => {
                let mut sum = self.form(a).clone();
                sum.add_scaled(self.form(b), 1.0);
                (sum.len() <= TERMS).then_some(sum)
            }
            Node::Neg(a) => Some(self.form(a).clone().scaled(-1.0)),
            Node::Mul(a, b) => self.form(a).times(self.form(b), WORK, TERMS),
            Node::Div(a, b) => self.quotient(a, b),
            Node::Pow(a, b) => self.power(a, b),
            Node::Apply(f @ (Function::Sin | Function::Cos), a) => {
                self.form(a).as_angle().map(|angle| {
                    let wave = if f == Function::Sin {
                        Wave::Sin
                    } else {
                        Wave::Cos
                    };
                    Polynomial::wave(wave, angle)
                })
            }
            Node::Apply(..) | Node::Atan2(..) | Node::Select { .. } => None,
        };
        match expanded {
            Some(form) => form,
            None => {
                let node = self.kept(id);
                self.atom(node)
            }
        }
    }

    /// `a / b`: a product by the inverse of a number or of a monomial; otherwise by the
    /// divisor written as an atom.
    fn quotient(&mut self, a: ExprId, b: ExprId) -> Option<Polynomial> {
        let divisor = self.form(b);
        if let Some(c) = divisor.as_constant() {
            return (c != 0.0 && (1.0 / c).is_finite()).then(|| self.form(a).clone().scaled(1.0 / c));
        }
        let inverse = match divisor.as_monomial() {
            Some((factors, c)) => {
                let mut inverse = Polynomial::constant(1.0 / c);
                for &(atom, exponent) in factors {
                    inverse = inverse.times(&Polynomial::atom(atom, -exponent), WORK, TERMS)?;
                }
                inverse
            }
            None => {
                let node = self.written(b);
                Polynomial::atom(node, -1)
            }
        };
        self.form(a).times(&inverse, WORK, TERMS)
    }

    /// `a ^ b` expanded for a small integer exponent.
    fn power(&mut self, a: ExprId, b: ExprId) -> Option<Polynomial> {
        let exponent = self.form(b).as_constant()?;
        if exponent.fract() != 0.0 || exponent.abs() > f64::from(POWER) {
            return None;
        }
        let exponent = exponent as i32;
        let base = if exponent >= 0 {
            self.form(a).clone()
        } else {
            let node = self.written(a);
            Polynomial::atom(node, -1)
        };
        let mut product = Polynomial::constant(1.0);
        for _ in 0..exponent.abs() {
            product = product.times(&base, WORK, TERMS)?;
        }
        Some(product)
    }

    /// Input node `id` kept as its operation on its operands' simplified nodes.
    fn kept(&mut self, id: ExprId) -> ExprId {
        let input = self.input;
        match input.node(id) {
            Node::Constant(bits) => self.out.constant(f64::from_bits(bits)),
            Node::Symbol(i) => self.out.symbol(input.symbol_name(i)),
            Node::Add(a, b) => {
                let (a, b) = (self.written(a), self.written(b));
                self.out.add(a, b)
            }
            Node::Mul(a, b) => {
                let (a, b) = (self.written(a), self.written(b));
                self.out.mul(a, b)
            }
            Node::Neg(a) => {
                let a = self.written(a);
                self.out.neg(a)
            }
            Node::Div(a, b) => {
                let (a, b) = (self.written(a), self.written(b));
                self.out.div(a, b)
            }
            Node::Pow(a, b) => {
                let (a, b) = (self.written(a), self.written(b));
                self.out.pow(a, b)
            }
            Node::Atan2(a, b) => {
                let (a, b) = (self.written(a), self.written(b));
                self.out.atan2(a, b)
            }
            Node::Apply(f, a) => {
                let a = self.written(a);
                self.out.apply(f, a)
            }
            Node::Select {
                test,
                when_nonnegative,
                otherwise,
            } => {
                let test = self.written(test);
                let (high, low) = (self.written(when_nonnegative), self.written(otherwise));
                self.out.select(test, high, low)
            }
        }
    }
}
