//! The simplifier of the expression graph: every node, operands first, is put in a normal form
//! (`polynomial`: a sum of coefficients times products of atoms and of one sine or cosine of a
//! linear form), so that like terms collect, sums and products cancel, numbers fold and the
//! trigonometric identities (sin² + cos² = 1, the angle sums) hold by construction; the roots
//! are then written back with their common factors taken out (`write`).
//!
//! Each node's work is bounded: a node whose form would pass `TERMS` terms (or whose product
//! would take more than `WORK` products of terms, refused before forming it) is not expanded but
//! kept as the operation on its operands' simplified nodes, an atom for the nodes that use it.
//! So deep chains (a 100-link pendulum's) are simplified near their leaves and shared above.
//! Below the bounds the work grows with the forms: a chain's are longer as the chain is, so on
//! the pendulums the cost per node still grows up to n = 100 (docs/equations.md, the
//! simplifier's cost).
//!
//! Expanding shares less: a sum read by several nodes, expanded in each, is written in each.
//! So the pass is run with shared sums expanded up to a few sizes (and not at all), and the
//! result with the fewest operations is kept; the simplified equations are never longer than
//! the input. The unexpanded pass runs first, and an expanded one is abandoned once its output
//! is well past the best so far (`ABANDON`), or once the roots it has finished, written, are
//! longer than the same roots of the best form (`CHECKPOINTS`): on long chains the expanded
//! forms of the mass matrix end longer, and most of their cost was in finishing them.
//!
//! Values: like computer algebra systems, the simplifier takes x − x = 0, 0 · x = 0 and
//! x / x = 1 for every x, so the result equals the input wherever the input is finite, and may
//! be finite where the input divided by zero. Coefficients are floating-point (see
//! `polynomial`): the result equals the input to round-off.

mod polynomial;
mod write;

use polynomial::{Angles, Polynomial, Wave};
use write::Writer;

use super::equations::Equations;
use super::expr::{topological_order, ExprId, Function, Node, Pool};

/// The most terms a node's normal form may have before the node is kept as an atom.
const TERMS: usize = 64;
/// The most products of terms a product of two forms may take (|A| · |B|), checked before
/// forming it. At n = 100 two thirds of the products of terms formed were thrown away with
/// their product past `TERMS`; refusing the product of two forms of more than 8 terms each
/// (or of 2 by more than 32, …) refuses them before any work, and leaves every output of the
/// pendulums (n = 1 … 100) and the satellite the same size (BENCHMARKS.md, "The simplifier's
/// cost: a budget of products, and the caps' trade-off").
const WORK: usize = 64;
/// A candidate form is abandoned once its output holds more nodes, beside the symbols, than
/// 3/2 of the operations of the best form before it plus 64. The output's nodes are its
/// operations with the numbers and any node no root reaches in the end (the 64 leave the
/// smallest groups, where these weigh most, always finished), so this is not an exact bound;
/// on the pendulums (n = 1 … 5, 10, 20, 50, 100) and the satellite no form that would have been
/// kept passes it, and at n = 100 the mass matrix's expansions to 4 and 64 terms, which end 1.7
/// and 7.4 times longer than the unexpanded form, stop there (BENCHMARKS.md, "The
/// simplifier's cost: candidates abandoned").
const ABANDON: (usize, usize, usize) = (3, 2, 64);
/// Where a candidate is also compared root by root, as fractions of the pass: the roots it has
/// finished by then are written in a copy of its output and abandoned when they take more than
/// `BEHIND` operations beyond the same roots in the best form. A mass matrix's entries finish one
/// by one along the pass, and on the pendulums its expanded forms fall further behind the
/// unexpanded one with every entry (at n = 100, the expansion to 1 term 1.05 times its
/// operations on the entries finished at an eighth, 1.13 at the end), so they are stopped early
/// instead of at the end (BENCHMARKS.md, "The simplifier's cost: candidates compared by their
/// finished roots"). The other groups' roots finish at the end: no checkpoint sees them.
const CHECKPOINTS: [(usize, usize); 5] = [(1, 16), (1, 8), (1, 4), (1, 2), (3, 4)];
/// How many operations a candidate's finished roots may take beyond the best form's at a
/// checkpoint.
const BEHIND: usize = 64;
/// The largest power of a sum expanded.
const POWER: i32 = 4;

/// The roots of `pool` simplified, in a new pool with the same symbols in the same order (so
/// that values of the symbols are given alike to both). Of the forms tried (`Expansion`), the
/// one with the fewest operations is kept: never more than the input rebuilt.
#[cfg(lsdc_internals)]
pub fn simplify(pool: &Pool, roots: &[ExprId]) -> (Pool, Vec<ExprId>) {
    let (pool, mut groups) = simplify_groups(pool, &[roots]);
    (pool, groups.pop().expect("one group"))
}

/// Each group of roots simplified on its own (its form chosen by its own operations: the mass
/// matrix's closed form is not traded for a shorter right-hand side), the results gathered in
/// one pool, where equal nodes of different groups are one node again.
pub fn simplify_groups(pool: &Pool, groups: &[&[ExprId]]) -> (Pool, Vec<Vec<ExprId>>) {
    let mut gathered = Pool::new();
    for i in 0..pool.symbol_count() as u32 {
        gathered.symbol(pool.symbol_name(i));
    }
    let mut simplified = Vec::new();
    for roots in groups {
        if roots.is_empty() {
            // A tree's constraints: no pass over the pool for nothing.
            simplified.push(Vec::new());
            continue;
        }
        // Every candidate reads the same nodes in the same order.
        let order = topological_order(roots, |id| pool.operand_ids(id));
        // The unexpanded form first (linear in the group), then the expansions from the least
        // to the most: each stops once its output holds more nodes than `ABANDON` allows beside
        // the operations of the best form found before it, which it can then hardly beat. On ties
        // the more expanded form is kept, as when the candidates were compared all at once.
        let candidates = [
            Expansion::None,
            Expansion::Shared(1),
            Expansion::Shared(4),
            Expansion::Shared(TERMS),
        ];
        let finishing = finishing_order(roots, &order);
        let mut best: Option<Best> = None;
        for expansion in candidates {
            let yardstick = best.as_ref().map(|best| Yardstick {
                best,
                finishing: &finishing,
            });
            let candidate = match expansion {
                Expansion::None => Some(rebuilt(pool, roots, &order, Pool::new())),
                Expansion::Shared(terms) => {
                    simplify_with(pool, roots, &order, terms, Pool::new(), yardstick)
                }
            };
            if let Some((pool, roots)) = candidate {
                let operations = pool.operation_count(&roots);
                if best
                    .as_ref()
                    .is_none_or(|best| operations <= best.operations)
                {
                    best = Some(Best {
                        pool,
                        roots,
                        operations,
                    });
                }
            }
        }
        let Best {
            pool: best,
            roots: best_roots,
            ..
        } = best.expect("the unexpanded form is never abandoned");
        let order = topological_order(&best_roots, |id| best.operand_ids(id));
        let copied;
        (gathered, copied) = rebuilt(&best, &best_roots, &order, gathered);
        simplified.push(copied);
    }
    (gathered, simplified)
}

/// The best form of a group found so far.
struct Best {
    pool: Pool,
    roots: Vec<ExprId>,
    operations: usize,
}

/// What a candidate is measured against as it goes: the best form before it, and the group's
/// roots by the place in the pass's order where each is finished (`finishing_order`).
#[derive(Clone, Copy)]
struct Yardstick<'a> {
    best: &'a Best,
    finishing: &'a [(usize, usize)],
}

impl Yardstick<'_> {
    /// The whole output's limit: `ABANDON` over the best form's operations.
    fn limit(&self) -> usize {
        let operations = self.best.operations;
        operations.saturating_mul(ABANDON.0) / ABANDON.1 + ABANDON.2
    }

    /// The roots finished once the pass has formed the node at `place` of its order, by their
    /// index among the group's roots, increasing.
    fn finished(&self, place: usize) -> Vec<usize> {
        let count = self.finishing.partition_point(|&(at, _)| at <= place);
        let mut finished: Vec<usize> = self.finishing[..count].iter().map(|&(_, i)| i).collect();
        finished.sort_unstable();
        finished
    }
}

/// Each root's index among `roots` with the place in `order` where the pass forms it, by place:
/// the roots a pass has finished at a place are a prefix.
fn finishing_order(roots: &[ExprId], order: &[ExprId]) -> Vec<(usize, usize)> {
    let mut place: rustc_hash::FxHashMap<ExprId, usize> =
        roots.iter().map(|&root| (root, 0)).collect();
    for (k, id) in order.iter().enumerate() {
        if let Some(at) = place.get_mut(id) {
            *at = k;
        }
    }
    let mut finishing: Vec<(usize, usize)> = (roots.iter().enumerate())
        .map(|(i, root)| (place[root], i))
        .collect();
    finishing.sort_unstable();
    finishing
}

/// How far the forms of shared nodes are carried into the nodes that read them.
#[derive(Clone, Copy, Debug)]
enum Expansion {
    /// A node read more than once is expanded in its readers up to this many terms, and is an
    /// atom for them beyond: a larger shared sum is written once rather than in every reader.
    Shared(usize),
    /// No expansion: the input rebuilt as it is (the constructors' local folding only).
    None,
}

/// The roots rebuilt in `out` node by node by its constructors (their local folding only): the
/// form without expansion (`Expansion::None`), and the copy of a group's best form into the
/// gathered pool. Each node is made from its operands' nodes, in `order` (the nodes the roots
/// reach, operands first, `topological_order`), as the expanding pass makes a node it keeps
/// (`Pass::kept`) but without a normal form per node: that pass would form each node as a
/// one-term polynomial and write it back for its readers, which makes the node itself, the
/// number 1 (the written coefficient) the first time, and nothing else. So the same nodes are
/// made in the same order (operands are ordered by their ids in sums and products), with no
/// allocation per node (BENCHMARKS.md, "The simplifier's cost: the unexpanded form without
/// forms").
fn rebuilt(pool: &Pool, roots: &[ExprId], order: &[ExprId], mut out: Pool) -> (Pool, Vec<ExprId>) {
    out.reserve(order.len());
    for i in 0..pool.symbol_count() as u32 {
        out.symbol(pool.symbol_name(i));
    }
    let mut nodes: Vec<Option<ExprId>> = vec![None; pool.len()];
    let made =
        |nodes: &[Option<ExprId>], id: ExprId| nodes[id.index()].expect("made before it is read");
    // Where the expanding pass would write its first one-term form: before the first
    // operation's node, or at the roots.
    let mut one_written = false;
    for &id in order {
        let node = match pool.node(id) {
            Node::Symbol(i) => out.symbol(pool.symbol_name(i)),
            shape @ Node::Constant(_) => out.rebuild(shape, &[]),
            shape => {
                if !one_written {
                    out.constant(1.0);
                    one_written = true;
                }
                let mut operands = [id; 3];
                for (k, operand) in pool.operand_ids(id).into_iter().enumerate() {
                    operands[k] = made(&nodes, operand);
                }
                out.rebuild(shape, &operands)
            }
        };
        nodes[id.index()] = Some(node);
    }
    if !one_written && !roots.is_empty() {
        out.constant(1.0);
    }
    let roots = roots.iter().map(|&root| made(&nodes, root)).collect();
    (out, roots)
}

/// The roots simplified with shared nodes expanded in their readers up to `terms` terms
/// (`Expansion::Shared`), written into `out`. With a `yardstick`, `None` (abandoned) as soon as
/// `out` holds more than its `limit` of nodes beyond those it had and the symbols, or when the
/// roots finished at one of the `CHECKPOINTS` take more than `BEHIND` operations beyond the
/// best form's. `order` is the nodes the roots reach, operands first (`topological_order`).
fn simplify_with(
    pool: &Pool,
    roots: &[ExprId],
    order: &[ExprId],
    terms: usize,
    mut out: Pool,
    yardstick: Option<Yardstick>,
) -> Option<(Pool, Vec<ExprId>)> {
    let limit = yardstick.map_or(usize::MAX, |yardstick| yardstick.limit());
    let checkpoints = CHECKPOINTS.map(|(numerator, denominator)| {
        yardstick.map_or(usize::MAX, |_| order.len() * numerator / denominator)
    });
    // The output's size foreseen by the input's: a pool grown by doubling copies its nodes and
    // rehashes its table at each step, a pass over memory that grows with the pool.
    out.reserve(order.len());
    let mut pass = Pass::new(pool, out);
    let limit = limit.saturating_add(pass.out.len());
    for &root in roots {
        pass.roots[root.index()] = true;
    }
    for &id in order {
        for operand in pool.operand_ids(id) {
            pass.readers[operand.index()] += 1;
        }
    }
    for (place, &id) in order.iter().enumerate() {
        let mut form = pass.form_of(id);
        let shared = pass.readers[id.index()] > 1;
        if shared && form.len() > terms {
            let node = pass.writer.write(&mut pass.out, &form, &pass.angles);
            pass.nodes[id.index()] = Some(node);
            form = pass.atom(node);
        }
        if pass.out.len() > limit {
            return None;
        }
        pass.forms[id.index()] = Some(form);
        for operand in pool.operand_ids(id) {
            let left = &mut pass.readers[operand.index()];
            *left -= 1;
            if *left == 0 && !pass.roots[operand.index()] {
                pass.forms[operand.index()] = None;
            }
        }
        if let Some(yardstick) = yardstick.filter(|_| checkpoints.contains(&place)) {
            let finished = yardstick.finished(place);
            if !finished.is_empty() {
                let written = pass.operations_if_written(finished.iter().map(|&i| roots[i]));
                let best = &yardstick.best;
                let theirs: Vec<ExprId> = finished.iter().map(|&i| best.roots[i]).collect();
                if written > best.pool.operation_count(&theirs) + BEHIND {
                    return None;
                }
            }
        }
    }
    let mut simplified = Vec::with_capacity(roots.len());
    for &root in roots {
        simplified.push(pass.written(root));
        if pass.out.len() > limit {
            return None;
        }
    }
    Some((pass.out, simplified))
}

/// The equations with every expression simplified, in a new pool.
pub fn simplify_equations(equations: &Equations) -> Equations {
    let none = Vec::new();
    let groups: [&[ExprId]; 6] = [
        &equations.mass,
        &equations.second_member,
        &equations.forces,
        &equations.constraints,
        &equations.constraint_bias,
        equations.accelerations.as_ref().unwrap_or(&none),
    ];
    let (pool, mut simplified) = simplify_groups(&equations.pool, &groups);
    let accelerations = simplified.pop().expect("six groups");
    let mut groups = simplified.into_iter();
    let mut next = || groups.next().expect("six groups");
    Equations {
        variables: equations.variables.clone(),
        mass: next(),
        second_member: next(),
        forces: next(),
        constraints: next(),
        constraint_bias: next(),
        constraint_names: equations.constraint_names.clone(),
        accelerations: equations.accelerations.as_ref().map(|_| accelerations),
        form: equations.form,
        pool,
    }
}

/// The form of input node `id` in a pass's table of forms (a function of the table, not of the
/// pass, so that the pass's angles may be borrowed beside it).
fn formed(forms: &[Option<Polynomial>], id: ExprId) -> &Polynomial {
    forms[id.index()]
        .as_ref()
        .expect("formed before it is read")
}

struct Pass<'a> {
    input: &'a Pool,
    out: Pool,
    /// The normal form of each input node simplified and still to be read.
    forms: Vec<Option<Polynomial>>,
    /// Each input node written in `out`.
    nodes: Vec<Option<ExprId>>,
    /// By input node: how many nodes still to simplify read it (its form is dropped, or taken
    /// by its last reader, when none is left), and whether it is a root (its form is kept).
    readers: Vec<u32>,
    roots: Vec<bool>,
    /// The angles of the forms' waves.
    angles: Angles,
    writer: Writer,
}

impl Pass<'_> {
    /// A pass from `input` into `out`, where the symbols are created first in `input`'s order.
    fn new(input: &Pool, mut out: Pool) -> Pass<'_> {
        for i in 0..input.symbol_count() as u32 {
            out.symbol(input.symbol_name(i));
        }
        Pass {
            input,
            out,
            forms: vec![None; input.len()],
            nodes: vec![None; input.len()],
            readers: vec![0; input.len()],
            roots: vec![false; input.len()],
            angles: Angles::default(),
            writer: Writer::new(),
        }
    }

    fn form(&self, id: ExprId) -> &Polynomial {
        formed(&self.forms, id)
    }

    /// The form of `id` to build on: taken when the node being simplified is its last reader
    /// (it is dropped after it anyway), a copy otherwise. Taking it saves a copy per link of a
    /// chain of sums, whose copies would cost the square of the chain's length. Only for a form
    /// the node is sure to be built from: a node kept as an operation writes its operands'
    /// forms.
    fn taken(&mut self, id: ExprId) -> Polynomial {
        if self.readers[id.index()] == 1 && !self.roots[id.index()] {
            self.forms[id.index()]
                .take()
                .expect("formed before it is read")
        } else {
            self.form(id).clone()
        }
    }

    /// The input node `id` written in `out` from its normal form (once).
    fn written(&mut self, id: ExprId) -> ExprId {
        if let Some(node) = self.nodes[id.index()] {
            return node;
        }
        let form = self.forms[id.index()]
            .as_ref()
            .expect("formed before it is written");
        let node = self.writer.write(&mut self.out, form, &self.angles);
        self.nodes[id.index()] = Some(node);
        node
    }

    /// The operations of `roots` (formed, and kept as roots are) if they were written now, as
    /// the pass writes its roots at its end; written in a copy of `out`, which stays as it was.
    fn operations_if_written(&self, roots: impl Iterator<Item = ExprId>) -> usize {
        let mut out = self.out.clone();
        let mut writer = self.writer.clone();
        let written: Vec<ExprId> = roots
            .map(|root| match self.nodes[root.index()] {
                Some(node) => node,
                None => writer.write(&mut out, formed(&self.forms, root), &self.angles),
            })
            .collect();
        out.operation_count(&written)
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
            Node::Add(a, b) if a != b && self.form(a).len() + self.form(b).len() <= TERMS => {
                // The sum cannot pass `TERMS`: the larger form is added to in place (taken
                // when this is its last reader). Adding is commutative term by term, so the
                // sum is the same whichever operand it starts from.
                let (large, small) = if self.form(a).len() >= self.form(b).len() {
                    (a, b)
                } else {
                    (b, a)
                };
                let mut sum = self.taken(large);
                sum.add_scaled(self.form(small), 1.0);
                Some(sum)
            }
            Node::Add(a, b) => {
                let mut sum = self.form(a).clone();
                sum.add_scaled(self.form(b), 1.0);
                (sum.len() <= TERMS).then_some(sum)
            }
            Node::Neg(a) => Some(self.taken(a).scaled(-1.0)),
            Node::Mul(a, b) => {
                formed(&self.forms, a).times(formed(&self.forms, b), WORK, TERMS, &mut self.angles)
            }
            Node::Div(a, b) => self.quotient(a, b),
            Node::Pow(a, b) => self.power(a, b),
            Node::Apply(f @ (Function::Sin | Function::Cos), a) => {
                formed(&self.forms, a).as_angle().map(|angle| {
                    let wave = if f == Function::Sin {
                        Wave::Sin
                    } else {
                        Wave::Cos
                    };
                    Polynomial::wave(wave, angle, &mut self.angles)
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
        if let Some(c) = self.form(b).as_constant() {
            return (c != 0.0 && (1.0 / c).is_finite()).then(|| self.taken(a).scaled(1.0 / c));
        }
        let divisor = formed(&self.forms, b);
        let inverse = match divisor.as_monomial() {
            Some((factors, c)) => {
                let mut inverse = Polynomial::constant(1.0 / c);
                for &(atom, exponent) in factors {
                    let factor = Polynomial::atom(atom, -exponent);
                    inverse = inverse.times(&factor, WORK, TERMS, &mut self.angles)?;
                }
                inverse
            }
            None => {
                let node = self.written(b);
                Polynomial::atom(node, -1)
            }
        };
        formed(&self.forms, a).times(&inverse, WORK, TERMS, &mut self.angles)
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
            product = product.times(&base, WORK, TERMS, &mut self.angles)?;
        }
        Some(product)
    }

    /// Input node `id` kept as its operation on its operands' simplified nodes.
    fn kept(&mut self, id: ExprId) -> ExprId {
        let input = self.input;
        match input.node(id) {
            Node::Symbol(i) => self.out.symbol(input.symbol_name(i)),
            shape => {
                let mut operands = [id; 3];
                for (k, operand) in input.operand_ids(id).into_iter().enumerate() {
                    operands[k] = self.written(operand);
                }
                self.out.rebuild(shape, &operands)
            }
        }
    }
}
