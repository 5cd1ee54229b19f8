//! A hash-consed expression DAG. Every node is interned in a `Pool`: building the same
//! expression twice gives the same `ExprId`, so common subexpressions are shared by construction
//! (no separate elimination pass) and the size of a set of equations is the number of distinct
//! nodes they reach. Constructors simplify locally: constants fold, 0 and 1 vanish where they
//! are neutral or absorbing, a double negation cancels, and the operands of sums and products are
//! put in a canonical order so that `a + b` and `b + a` are one node.

use std::collections::HashMap;

use super::tape_code::{Apply, Code, TapeCode};

pub use super::exponential_profile::ExponentialProfile;

pub mod dual_evaluation;
pub mod tangents;

/// An expression: an index into its `Pool`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct ExprId(u32);

impl ExprId {
    /// The node's position in its pool: a stable name for emitted temporaries.
    pub fn index(self) -> usize {
        self.0 as usize
    }
}

/// One node. Constants are stored by their bits so that nodes can be hashed; -0.0 is stored as
/// 0.0 so that the two zeros are one node.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Node {
    Constant(u64),
    /// A symbol: an unknown of the program, a coordinate or a rate, by its index in the pool.
    Symbol(u32),
    Add(ExprId, ExprId),
    Mul(ExprId, ExprId),
    Neg(ExprId),
    Div(ExprId, ExprId),
    /// `a ^ b`; integer exponents are emitted as products.
    Pow(ExprId, ExprId),
    /// `atan2(y, x)`.
    Atan2(ExprId, ExprId),
    Apply(Function, ExprId),
    /// `when_nonnegative` where `test ≥ 0`, else `otherwise` (a NaN test takes `otherwise`): the
    /// one piecewise node, behind saturation, dead zones and the piecewise reference laws. Each
    /// piece is differentiated on its own, so the derivative is exact inside every piece and the
    /// right-hand one where a rising test crosses 0.
    Select {
        test: ExprId,
        when_nonnegative: ExprId,
        otherwise: ExprId,
    },
}

/// The functions of one argument LSD programs may call.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Function {
    Sin,
    Cos,
    Tan,
    Asin,
    Acos,
    Atan,
    Sqrt,
    Exp,
    Log,
    Abs,
    /// The largest integer not above the argument; its derivative is 0 wherever it exists.
    Floor,
    /// The normalised profile of the exponential law of motion, a quadrature (see
    /// `exponential_profile`); its derivative is its rate, as ordinary nodes.
    ExponentialProfile(ExponentialProfile),
}

impl Function {
    pub fn from_name(name: &str) -> Option<Function> {
        Some(match name {
            "sin" => Function::Sin,
            "cos" => Function::Cos,
            "tan" => Function::Tan,
            "asin" => Function::Asin,
            "acos" => Function::Acos,
            "atan" => Function::Atan,
            "sqrt" => Function::Sqrt,
            "exp" => Function::Exp,
            "log" => Function::Log,
            "abs" => Function::Abs,
            "floor" => Function::Floor,
            _ => return None,
        })
    }

    /// The name in LSD, C, Rust (as a method) and SymPy alike.
    pub fn name(self) -> &'static str {
        match self {
            Function::Sin => "sin",
            Function::Cos => "cos",
            Function::Tan => "tan",
            Function::Asin => "asin",
            Function::Acos => "acos",
            Function::Atan => "atan",
            Function::Sqrt => "sqrt",
            Function::Exp => "exp",
            Function::Log => "log",
            Function::Abs => "abs",
            Function::Floor => "floor",
            Function::ExponentialProfile(_) => "exponential_profile",
        }
    }

    pub fn eval(self, x: f64) -> f64 {
        match self {
            Function::Sin => x.sin(),
            Function::Cos => x.cos(),
            Function::Tan => x.tan(),
            Function::Asin => x.asin(),
            Function::Acos => x.acos(),
            Function::Atan => x.atan(),
            Function::Sqrt => x.sqrt(),
            Function::Exp => x.exp(),
            Function::Log => x.ln(),
            Function::Abs => x.abs(),
            Function::Floor => x.floor(),
            Function::ExponentialProfile(profile) => profile.value(x),
        }
    }
}

/// A node's hash in its pool's table of ids: the Fx hash folded to 32 bits, kept in the table
/// beside the id (`Pool::index`).
fn node_hash(node: &Node) -> u32 {
    use std::hash::BuildHasher;
    let hash = rustc_hash::FxBuildHasher.hash_one(node);
    (hash ^ (hash >> 32)) as u32
}

/// The table's hash of a node's 32-bit one: hashbrown takes a bucket from the low bits and a
/// 7-bit tag from the top ones, so both halves carry the 32 bits.
fn table_hash(hash: u32) -> u64 {
    u64::from(hash) << 32 | u64::from(hash)
}

#[derive(Clone, Default)]
pub struct Pool {
    nodes: Vec<Node>,
    /// Per node, whether it is surely finite (`finite_when_interned`).
    finite: Vec<bool>,
    /// Each node's id (hash-consing), by the node's Fx hash (rather than SipHash: the keys are
    /// our own nodes, and the lookup is in every constructor). The table holds the ids and
    /// their nodes' hashes, not the nodes: a slot of 8 bytes instead of a copy of the node (40
    /// bytes, the profile's parameters within `Function`) and its id, so that the table of a
    /// simplifier's pass of several hundred thousand nodes stays small, where its lookups were
    /// the profile's first item (BENCHMARKS.md, "The simplifier's cost: what each node costs as
    /// n grows, counted"). A candidate is compared by its hash first and by reading `nodes`
    /// only when the hashes agree, and growing the table rehashes from the stored hashes: a
    /// read of the pool (a random one, in a pool of millions of nodes) only for a node found.
    index: hashbrown::HashTable<(ExprId, u32)>,
    symbols: Vec<String>,
    symbol_ids: HashMap<String, ExprId>,
}

impl Pool {
    pub fn new() -> Pool {
        Pool::default()
    }

    pub fn node(&self, id: ExprId) -> Node {
        self.nodes[id.0 as usize]
    }

    /// Whether a node is the exponential law's profile (code emitters then define it).
    pub fn uses_exponential_profile(&self) -> bool {
        (self.nodes.iter()).any(|n| matches!(n, Node::Apply(Function::ExponentialProfile(_), _)))
    }

    /// The operations evaluating `roots` computes, as `Tape::operation_count` counts them, without
    /// building the tape: the nodes the roots reach that are neither numbers nor symbols, less
    /// the negations only subtractions read. One mark per node of the pool instead of the tape's
    /// hashed positions: the simplifier counts each of its candidate forms.
    pub fn operation_count(&self, roots: &[ExprId]) -> usize {
        const REACHED: u8 = 1;
        const USED: u8 = 2;
        let mut marks = vec![0u8; self.nodes.len()];
        let mut stack: Vec<ExprId> = roots.to_vec();
        let mut reached = Vec::new();
        while let Some(id) = stack.pop() {
            if marks[id.index()] & REACHED != 0 {
                continue;
            }
            marks[id.index()] |= REACHED;
            reached.push(id);
            stack.extend(self.operand_ids(id));
        }
        for &root in roots {
            marks[root.index()] |= USED;
        }
        let negated = |id: ExprId| match self.node(id) {
            Node::Neg(inner) => Some(inner),
            _ => None,
        };
        for &id in &reached {
            // The operands a tape's step reads: a sum with a negated operand is a subtraction
            // of the negation's operand.
            let read: Vec<ExprId> = match self.node(id) {
                Node::Add(a, b) => match (negated(a), negated(b)) {
                    (_, Some(b)) => vec![a, b],
                    (Some(a), None) => vec![b, a],
                    (None, None) => vec![a, b],
                },
                _ => self.operands(id),
            };
            for operand in read {
                marks[operand.index()] |= USED;
            }
        }
        (reached.iter())
            .filter(|&&id| match self.node(id) {
                Node::Constant(_) | Node::Symbol(_) => false,
                Node::Neg(_) => marks[id.index()] & USED != 0,
                _ => true,
            })
            .count()
    }

    /// Number of distinct nodes in the pool.
    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    pub fn symbol_name(&self, index: u32) -> &str {
        &self.symbols[index as usize]
    }

    pub fn symbol_count(&self) -> usize {
        self.symbols.len()
    }

    /// Room for `additional` more nodes, so that a pool whose size is foreseen (a simplifier's
    /// output, by its input's) is not grown, and its table of ids not rehashed, on the way.
    pub fn reserve(&mut self, additional: usize) {
        self.nodes.reserve(additional);
        self.finite.reserve(additional);
        (self.index).reserve(additional, |&(_, hash)| table_hash(hash));
    }

    fn intern(&mut self, node: Node) -> ExprId {
        let hash = node_hash(&node);
        let nodes = &self.nodes;
        let same = |&(id, h): &(ExprId, u32)| h == hash && nodes[id.index()] == node;
        if let Some(&(id, _)) = self.index.find(table_hash(hash), same) {
            return id;
        }
        let id = ExprId(self.nodes.len() as u32);
        self.finite.push(self.finite_when_interned(node));
        self.nodes.push(node);
        (self.index).insert_unique(table_hash(hash), (id, hash), |&(_, h)| table_hash(h));
        id
    }

    pub fn constant(&mut self, value: f64) -> ExprId {
        let value = if value == 0.0 { 0.0 } else { value };
        self.intern(Node::Constant(value.to_bits()))
    }

    /// The symbol called `name`, created on first use; its index orders the values of `eval`.
    pub fn symbol(&mut self, name: &str) -> ExprId {
        if let Some(&id) = self.symbol_ids.get(name) {
            return id;
        }
        let id = self.intern(Node::Symbol(self.symbols.len() as u32));
        self.symbols.push(name.to_string());
        self.symbol_ids.insert(name.to_string(), id);
        id
    }

    /// The name of a symbol node (`None` for any other node).
    pub fn name_of(&self, id: ExprId) -> Option<&str> {
        match self.node(id) {
            Node::Symbol(i) => Some(self.symbol_name(i)),
            _ => None,
        }
    }

    /// The index of a symbol node among the symbols (`None` for any other node).
    pub fn symbol_index(&self, id: ExprId) -> Option<usize> {
        match self.node(id) {
            Node::Symbol(i) => Some(i as usize),
            _ => None,
        }
    }

    /// The value of a constant node.
    pub fn as_constant(&self, id: ExprId) -> Option<f64> {
        match self.node(id) {
            Node::Constant(bits) => Some(f64::from_bits(bits)),
            _ => None,
        }
    }

    /// Whether a node is finite at every instant and state (see `finite_when_interned`).
    pub fn surely_finite(&self, id: ExprId) -> bool {
        self.finite[id.0 as usize]
    }

    /// Whether a new node is finite at every instant and state: finite constants, symbols (the
    /// values of coordinates, rates, time and unknowns are finite numbers), and sums, products,
    /// negations, arctangents, sines, cosines and absolute values of finite nodes. Overflow of a
    /// sum or product is not considered; quotients, roots, powers, logarithms and exponentials
    /// may be infinite or NaN. Decided once per node from its operands', which exist before it.
    fn finite_when_interned(&self, node: Node) -> bool {
        match node {
            Node::Constant(bits) => f64::from_bits(bits).is_finite(),
            Node::Symbol(_) => true,
            Node::Add(a, b) | Node::Mul(a, b) | Node::Atan2(a, b) => {
                self.surely_finite(a) && self.surely_finite(b)
            }
            Node::Neg(a)
            | Node::Apply(
                Function::Sin | Function::Cos | Function::Atan | Function::Abs | Function::Floor,
                a,
            ) => self.surely_finite(a),
            // Only the value taken matters, whatever the test.
            Node::Select {
                when_nonnegative,
                otherwise,
                ..
            } => self.surely_finite(when_nonnegative) && self.surely_finite(otherwise),
            Node::Div(..) | Node::Pow(..) | Node::Apply(..) => false,
        }
    }

    fn is(&self, id: ExprId, value: f64) -> bool {
        self.as_constant(id) == Some(value)
    }

    pub fn add(&mut self, a: ExprId, b: ExprId) -> ExprId {
        match (self.as_constant(a), self.as_constant(b)) {
            (Some(x), Some(y)) => return self.constant(x + y),
            (Some(0.0), _) => return b,
            (_, Some(0.0)) => return a,
            _ => {}
        }
        // a + (−a) = 0 for a finite a (∞ − ∞ and NaN − NaN are NaN).
        if (self.node(b) == Node::Neg(a) || self.node(a) == Node::Neg(b)) && self.surely_finite(a) {
            return self.constant(0.0);
        }
        self.intern(Node::Add(a.min(b), a.max(b)))
    }

    pub fn sub(&mut self, a: ExprId, b: ExprId) -> ExprId {
        let minus_b = self.neg(b);
        self.add(a, minus_b)
    }

    pub fn mul(&mut self, a: ExprId, b: ExprId) -> ExprId {
        match (self.as_constant(a), self.as_constant(b)) {
            (Some(x), Some(y)) => return self.constant(x * y),
            // 0 · x = 0 for a finite x (0 · ∞ and 0 · NaN are NaN).
            (Some(x), _) if x == 0.0 && self.surely_finite(b) => return self.constant(0.0),
            (_, Some(x)) if x == 0.0 && self.surely_finite(a) => return self.constant(0.0),
            (Some(1.0), _) => return b,
            (_, Some(1.0)) => return a,
            (Some(-1.0), _) => return self.neg(b),
            (_, Some(-1.0)) => return self.neg(a),
            _ => {}
        }
        // Signs move onto constants or cancel; negation is exact, so the value is unchanged.
        match (self.node(a), self.node(b)) {
            (Node::Neg(x), Node::Neg(y)) => return self.mul(x, y),
            (Node::Constant(c), Node::Neg(x)) | (Node::Neg(x), Node::Constant(c)) => {
                let minus = self.constant(-f64::from_bits(c));
                return self.mul(minus, x);
            }
            _ => {}
        }
        self.intern(Node::Mul(a.min(b), a.max(b)))
    }

    pub fn neg(&mut self, a: ExprId) -> ExprId {
        match self.node(a) {
            Node::Constant(bits) => self.constant(-f64::from_bits(bits)),
            Node::Neg(inner) => inner,
            // −(c x) = (−c) x, exactly.
            Node::Mul(x, y) if self.as_constant(x).is_some() || self.as_constant(y).is_some() => {
                let (c, other) = if self.as_constant(x).is_some() {
                    (x, y)
                } else {
                    (y, x)
                };
                let minus = self.neg(c);
                self.mul(minus, other)
            }
            _ => self.intern(Node::Neg(a)),
        }
    }

    pub fn div(&mut self, a: ExprId, b: ExprId) -> ExprId {
        match (self.as_constant(a), self.as_constant(b)) {
            // Not 0 / b = 0 nor a / a = 1: either is NaN where the divisor vanishes.
            (Some(x), Some(y)) if (x / y).is_finite() => self.constant(x / y),
            (_, Some(1.0)) => a,
            _ => self.intern(Node::Div(a, b)),
        }
    }

    pub fn apply(&mut self, f: Function, a: ExprId) -> ExprId {
        match self.as_constant(a) {
            Some(x) if f.eval(x).is_finite() => self.constant(f.eval(x)),
            _ => self.intern(Node::Apply(f, a)),
        }
    }

    pub fn sin(&mut self, a: ExprId) -> ExprId {
        self.apply(Function::Sin, a)
    }

    pub fn cos(&mut self, a: ExprId) -> ExprId {
        self.apply(Function::Cos, a)
    }

    pub fn sqrt(&mut self, a: ExprId) -> ExprId {
        self.apply(Function::Sqrt, a)
    }

    /// `a ^ b`: folded for constants, `a` for b = 1, 1 for b = 0.
    pub fn pow(&mut self, a: ExprId, b: ExprId) -> ExprId {
        match (self.as_constant(a), self.as_constant(b)) {
            (Some(x), Some(y)) if x.powf(y).is_finite() => self.constant(x.powf(y)),
            (_, Some(1.0)) => a,
            (_, Some(0.0)) => self.constant(1.0),
            _ => self.intern(Node::Pow(a, b)),
        }
    }

    pub fn atan2(&mut self, y: ExprId, x: ExprId) -> ExprId {
        match (self.as_constant(y), self.as_constant(x)) {
            (Some(a), Some(b)) => self.constant(a.atan2(b)),
            _ => self.intern(Node::Atan2(y, x)),
        }
    }

    /// `when_nonnegative` where `test ≥ 0`, else `otherwise`: decided now for a constant test,
    /// and one branch when both are the same node.
    pub fn select(&mut self, test: ExprId, when_nonnegative: ExprId, otherwise: ExprId) -> ExprId {
        if when_nonnegative == otherwise {
            return otherwise;
        }
        match self.as_constant(test) {
            Some(c) if c >= 0.0 => when_nonnegative,
            Some(_) => otherwise,
            None => self.intern(Node::Select {
                test,
                when_nonnegative,
                otherwise,
            }),
        }
    }

    /// The sum of `terms` (0 when empty).
    pub fn sum(&mut self, terms: impl IntoIterator<Item = ExprId>) -> ExprId {
        let zero = self.constant(0.0);
        terms.into_iter().fold(zero, |sum, t| self.add(sum, t))
    }

    /// ∂e/∂x for a symbol x. `memo` keeps the derivatives already taken with respect to x, so
    /// that shared subexpressions are differentiated once: pass the same map for the same x.
    pub fn derivative(
        &mut self,
        e: ExprId,
        x: ExprId,
        memo: &mut HashMap<ExprId, ExprId>,
    ) -> ExprId {
        if let Some(&d) = memo.get(&e) {
            return d;
        }
        let d = match self.node(e) {
            Node::Constant(_) => self.constant(0.0),
            Node::Symbol(_) => self.constant(if e == x { 1.0 } else { 0.0 }),
            Node::Add(a, b) => {
                let (da, db) = (self.derivative(a, x, memo), self.derivative(b, x, memo));
                self.add(da, db)
            }
            Node::Mul(a, b) => {
                let (da, db) = (self.derivative(a, x, memo), self.derivative(b, x, memo));
                let (l, r) = (self.mul(da, b), self.mul(a, db));
                self.add(l, r)
            }
            Node::Neg(a) => {
                let da = self.derivative(a, x, memo);
                self.neg(da)
            }
            Node::Div(a, b) => {
                // (a/b)' = a'/b − (a/b)·b'/b
                let (da, db) = (self.derivative(a, x, memo), self.derivative(b, x, memo));
                let first = self.div(da, b);
                let ratio = self.div(db, b);
                let second = self.mul(e, ratio);
                self.sub(first, second)
            }
            Node::Pow(a, b) => self.pow_derivative(e, a, b, x, memo),
            Node::Atan2(y, w) => {
                // (w y' − y w') / (w² + y²)
                let (dy, dw) = (self.derivative(y, x, memo), self.derivative(w, x, memo));
                let (l, r) = (self.mul(w, dy), self.mul(y, dw));
                let numerator = self.sub(l, r);
                let (ww, yy) = (self.mul(w, w), self.mul(y, y));
                let denominator = self.add(ww, yy);
                self.div(numerator, denominator)
            }
            Node::Select {
                test,
                when_nonnegative,
                otherwise,
            } => {
                // Piece by piece: exact inside each piece; the test's own derivative plays no
                // part (the pieces' values meet where the laws are continuous, and the jump of
                // a discontinuous one is not differentiated).
                let high = self.derivative(when_nonnegative, x, memo);
                let low = self.derivative(otherwise, x, memo);
                self.select(test, high, low)
            }
            Node::Apply(f, a) => {
                let da = self.derivative(a, x, memo);
                if self.is_zero(da) {
                    da
                } else {
                    let outer = self.outer_derivative(f, e, a);
                    self.mul(outer, da)
                }
            }
        };
        memo.insert(e, d);
        d
    }

    fn pow_derivative(
        &mut self,
        e: ExprId,
        a: ExprId,
        b: ExprId,
        x: ExprId,
        memo: &mut HashMap<ExprId, ExprId>,
    ) -> ExprId {
        let (da, db) = (self.derivative(a, x, memo), self.derivative(b, x, memo));
        if self.is_zero(db) {
            // b a^(b−1) a'
            let one = self.constant(1.0);
            let exponent = self.sub(b, one);
            let power = self.pow(a, exponent);
            let scaled = self.mul(b, power);
            return self.mul(scaled, da);
        }
        // a^b (b' log a + b a'/a)
        let log = self.apply(Function::Log, a);
        let first = self.mul(db, log);
        let ratio = self.div(da, a);
        let second = self.mul(b, ratio);
        let rate = self.add(first, second);
        self.mul(e, rate)
    }

    /// f'(a), given e = f(a).
    fn outer_derivative(&mut self, f: Function, e: ExprId, a: ExprId) -> ExprId {
        let one = self.constant(1.0);
        match f {
            Function::Sin => self.cos(a),
            Function::Cos => {
                let s = self.sin(a);
                self.neg(s)
            }
            Function::Tan => {
                let ee = self.mul(e, e);
                self.add(one, ee)
            }
            Function::Asin | Function::Acos => {
                let aa = self.mul(a, a);
                let rest = self.sub(one, aa);
                let root = self.sqrt(rest);
                let inverse = self.div(one, root);
                if f == Function::Asin {
                    inverse
                } else {
                    self.neg(inverse)
                }
            }
            Function::Atan => {
                let aa = self.mul(a, a);
                let d = self.add(one, aa);
                self.div(one, d)
            }
            Function::Sqrt => {
                let two = self.constant(2.0);
                let twice = self.mul(two, e);
                self.div(one, twice)
            }
            Function::Exp => e,
            Function::Log => self.div(one, a),
            Function::Abs => self.div(a, e),
            // A step function: flat between its jumps.
            Function::Floor => self.constant(0.0),
            Function::ExponentialProfile(profile) => self.exponential_rate(profile, a),
        }
    }

    /// The exponential law's rate s'(τ) = r(τ)/R at the node `tau`, r = exp(−σ (1 − g)/g^λ),
    /// g = 4τ(1 − τ) (`exponential_profile`); 0 where g ≤ 0, as are its derivatives there.
    fn exponential_rate(&mut self, profile: ExponentialProfile, tau: ExprId) -> ExprId {
        let (one, four) = (self.constant(1.0), self.constant(4.0));
        let rest = self.sub(one, tau);
        let product = self.mul(tau, rest);
        let g = self.mul(four, product);
        let minus_lambda = self.constant(-profile.lambda());
        let inverse_power = self.pow(g, minus_lambda);
        let complement = self.sub(one, g);
        let f = self.mul(complement, inverse_power);
        let minus_sigma = self.constant(-profile.sigma());
        let exponent = self.mul(minus_sigma, f);
        let rate = self.apply(Function::Exp, exponent);
        let total = self.constant(profile.total());
        let normalised = self.div(rate, total);
        let outside = self.neg(g);
        let zero = self.constant(0.0);
        self.select(outside, zero, normalised)
    }

    /// The operands of a node.
    pub fn operands(&self, id: ExprId) -> Vec<ExprId> {
        self.operand_ids(id).to_vec()
    }

    /// The operands of a node, without allocating: for passes that read every node's. The
    /// places past the operands hold any id; they are never read.
    pub fn operand_ids(&self, id: ExprId) -> Operands {
        let (ids, len) = match self.node(id) {
            Node::Constant(_) | Node::Symbol(_) => ([id; 3], 0),
            Node::Add(a, b)
            | Node::Mul(a, b)
            | Node::Div(a, b)
            | Node::Pow(a, b)
            | Node::Atan2(a, b) => ([a, b, b], 2),
            Node::Neg(a) | Node::Apply(_, a) => ([a; 3], 1),
            Node::Select {
                test,
                when_nonnegative,
                otherwise,
            } => ([test, when_nonnegative, otherwise], 3),
        };
        Operands { ids, len }
    }

    /// The node `id` of another pool rebuilt in this one (symbols matched by name), so that
    /// expressions of two derivations can be subtracted. `memo` keeps the nodes already rebuilt:
    /// pass the same map for the same `from`.
    pub fn transplant(
        &mut self,
        from: &Pool,
        id: ExprId,
        memo: &mut HashMap<ExprId, ExprId>,
    ) -> ExprId {
        // Operands first, without recursion: a deep graph would overflow the stack.
        let mut stack = vec![(id, false)];
        while let Some((node, expanded)) = stack.pop() {
            if memo.contains_key(&node) {
                continue;
            }
            let operands = from.operands(node);
            if !expanded {
                stack.push((node, true));
                stack.extend(operands.iter().map(|&o| (o, false)));
                continue;
            }
            let o: Vec<ExprId> = operands.iter().map(|x| memo[x]).collect();
            let rebuilt = match from.node(node) {
                // A symbol's index is its pool's own: matched by name.
                Node::Symbol(i) => self.symbol(from.symbol_name(i)),
                shape => self.rebuild(shape, &o),
            };
            memo.insert(node, rebuilt);
        }
        memo[&id]
    }

    /// The operation of `shape` (a node of this pool; its own operands ignored) over
    /// `operands`, folded as the constructors fold: how a node is made again once its operands
    /// have been made again, in this pool or, by `transplant`, in another.
    pub fn rebuild(&mut self, shape: Node, operands: &[ExprId]) -> ExprId {
        let o = operands;
        match shape {
            Node::Constant(bits) => self.constant(f64::from_bits(bits)),
            Node::Symbol(_) => self.intern(shape),
            Node::Add(..) => self.add(o[0], o[1]),
            Node::Mul(..) => self.mul(o[0], o[1]),
            Node::Div(..) => self.div(o[0], o[1]),
            Node::Pow(..) => self.pow(o[0], o[1]),
            Node::Atan2(..) => self.atan2(o[0], o[1]),
            Node::Neg(_) => self.neg(o[0]),
            Node::Apply(f, _) => self.apply(f, o[0]),
            Node::Select { .. } => self.select(o[0], o[1], o[2]),
        }
    }

    /// Whether `id` is the constant 0.
    pub fn is_zero(&self, id: ExprId) -> bool {
        self.is(id, 0.0)
    }
}

impl Apply for Function {
    fn apply(self, x: f64) -> f64 {
        self.eval(x)
    }
}

/// The nodes that `roots` reach, operands before the nodes that use them: the order in which to
/// evaluate them, or to emit one assignment each.
#[derive(Clone, Debug)]
pub struct Tape {
    pub order: Vec<ExprId>,
    /// For each root, its position in `order`.
    pub roots: Vec<usize>,
    /// What evaluating computes, in order: each node's position in `order` and its operation on
    /// the positions of its operands. A sum with a negated operand is one subtraction, so a
    /// negation that only such sums use is not computed at all.
    program: Vec<(usize, Step)>,
    /// The program as the interpreter runs it (`tape_code`).
    code: TapeCode<Function>,
}

#[derive(Clone, Copy, Debug)]
enum Step {
    Constant(f64),
    Symbol(usize),
    Add(usize, usize),
    /// `a − b`: a sum of `a` and the negation of `b`, exactly.
    Sub(usize, usize),
    Mul(usize, usize),
    Neg(usize),
    Div(usize, usize),
    Pow(usize, usize),
    Atan2(usize, usize),
    Apply(Function, usize),
    /// `b` where `a ≥ 0`, else `c`.
    Select(usize, usize, usize),
}

impl Step {
    /// The step as an instruction of the tape's code.
    fn code(self) -> Code<Function> {
        let p = |k: usize| u32::try_from(k).expect("a tape of fewer than 2^32 nodes");
        match self {
            Step::Constant(c) => Code::Constant(c),
            Step::Symbol(i) => Code::Symbol(p(i)),
            Step::Add(a, b) => Code::Add(p(a), p(b)),
            Step::Sub(a, b) => Code::Sub(p(a), p(b)),
            Step::Mul(a, b) => Code::Mul(p(a), p(b)),
            Step::Neg(a) => Code::Neg(p(a)),
            Step::Div(a, b) => Code::Div(p(a), p(b)),
            Step::Pow(a, b) => Code::Pow(p(a), p(b)),
            Step::Atan2(a, b) => Code::Atan2(p(a), p(b)),
            Step::Apply(f, a) => Code::Apply(f, p(a)),
            Step::Select(a, b, c) => Code::Select(p(a), p(b), p(c)),
        }
    }

    fn operands(self) -> [Option<usize>; 3] {
        match self {
            Step::Constant(_) | Step::Symbol(_) => [None, None, None],
            Step::Neg(a) | Step::Apply(_, a) => [Some(a), None, None],
            Step::Add(a, b)
            | Step::Sub(a, b)
            | Step::Mul(a, b)
            | Step::Div(a, b)
            | Step::Pow(a, b)
            | Step::Atan2(a, b) => [Some(a), Some(b), None],
            Step::Select(a, b, c) => [Some(a), Some(b), Some(c)],
        }
    }
}

/// A node's operands (at most three) held in place: `Pool::operand_ids`.
#[derive(Clone, Copy, Debug)]
pub struct Operands {
    ids: [ExprId; 3],
    len: u8,
}

impl std::ops::Deref for Operands {
    type Target = [ExprId];

    fn deref(&self) -> &[ExprId] {
        &self.ids[..usize::from(self.len)]
    }
}

impl IntoIterator for Operands {
    type Item = ExprId;
    type IntoIter = std::iter::Take<std::array::IntoIter<ExprId, 3>>;

    fn into_iter(self) -> Self::IntoIter {
        self.ids.into_iter().take(usize::from(self.len))
    }
}

/// The nodes `roots` reach through `operands`, operands before the nodes that use them, each
/// once; depth-first with an explicit stack, since expression DAGs can be deep.
pub fn topological_order<I: IntoIterator<Item = ExprId>>(
    roots: &[ExprId],
    operands: impl Fn(ExprId) -> I,
) -> Vec<ExprId> {
    // The Fx hash: the nodes' numbers are small integers, hashed once per visit of a large DAG.
    let mut placed: rustc_hash::FxHashSet<ExprId> = rustc_hash::FxHashSet::default();
    let mut order = Vec::new();
    for &root in roots {
        let mut stack = vec![(root, false)];
        while let Some((id, expanded)) = stack.pop() {
            if placed.contains(&id) {
                continue;
            }
            if expanded {
                placed.insert(id);
                order.push(id);
            } else {
                stack.push((id, true));
                stack.extend(
                    operands(id)
                        .into_iter()
                        .filter(|o| !placed.contains(o))
                        .map(|o| (o, false)),
                );
            }
        }
    }
    order
}

impl Tape {
    pub fn new(pool: &Pool, roots: &[ExprId]) -> Tape {
        let order = topological_order(roots, |id| pool.operand_ids(id));
        let position: HashMap<ExprId, usize> =
            order.iter().enumerate().map(|(k, &id)| (id, k)).collect();
        let at = |id: ExprId| position[&id];
        let negated = |id: ExprId| match pool.node(id) {
            Node::Neg(inner) => Some(inner),
            _ => None,
        };
        let steps: Vec<Step> = order
            .iter()
            .map(|&id| match pool.node(id) {
                Node::Constant(bits) => Step::Constant(f64::from_bits(bits)),
                Node::Symbol(i) => Step::Symbol(i as usize),
                Node::Add(a, b) => match (negated(a), negated(b)) {
                    (_, Some(b)) => Step::Sub(at(a), at(b)),
                    (Some(a), None) => Step::Sub(at(b), at(a)),
                    (None, None) => Step::Add(at(a), at(b)),
                },
                Node::Mul(a, b) => Step::Mul(at(a), at(b)),
                Node::Neg(a) => Step::Neg(at(a)),
                Node::Div(a, b) => Step::Div(at(a), at(b)),
                Node::Pow(a, b) => Step::Pow(at(a), at(b)),
                Node::Atan2(a, b) => Step::Atan2(at(a), at(b)),
                Node::Apply(f, a) => Step::Apply(f, at(a)),
                Node::Select {
                    test,
                    when_nonnegative,
                    otherwise,
                } => Step::Select(at(test), at(when_nonnegative), at(otherwise)),
            })
            .collect();
        let roots: Vec<usize> = roots.iter().map(|r| position[r]).collect();
        // Every node is used except negations that only subtractions read.
        let mut used = vec![false; steps.len()];
        for &r in &roots {
            used[r] = true;
        }
        for step in &steps {
            for operand in step.operands().into_iter().flatten() {
                used[operand] = true;
            }
        }
        let program: Vec<(usize, Step)> = steps
            .into_iter()
            .enumerate()
            .filter(|&(k, step)| used[k] || !matches!(step, Step::Neg(_)))
            .collect();
        let steps: Vec<(usize, Code<Function>)> =
            program.iter().map(|&(k, s)| (k, s.code())).collect();
        let code = TapeCode::new(&steps, &roots, order.len());
        Tape {
            order,
            roots,
            program,
            code,
        }
    }

    /// Number of distinct nodes the roots reach.
    pub fn size(&self) -> usize {
        self.order.len()
    }

    /// Number of operations evaluating computes: the nodes that are neither numbers nor
    /// symbols, a sum with a negated operand one subtraction (the measure SymPy's `count_ops`
    /// takes of an expression, here with common subexpressions counted once).
    pub fn operation_count(&self) -> usize {
        (self.program.iter())
            .filter(|(_, step)| !matches!(step, Step::Constant(_) | Step::Symbol(_)))
            .count()
    }

    /// Number of nodes the roots would have written as trees, without sharing (as f64: it grows
    /// exponentially with depth): what common subexpressions save.
    pub fn expanded_size(&self) -> f64 {
        let mut size = vec![0.0; self.order.len()];
        for &(k, step) in &self.program {
            let operands: f64 = step.operands().into_iter().flatten().map(|a| size[a]).sum();
            // A subtraction stands for a sum and a negation.
            let negation = if matches!(step, Step::Sub(..)) {
                1.0
            } else {
                0.0
            };
            size[k] = 1.0 + negation + operands;
        }
        self.roots.iter().map(|&r| size[r]).sum()
    }

    /// Evaluates every node with `symbols[i]` the value of symbol i; returns the roots' values.
    pub fn eval(&self, symbols: &[f64]) -> Vec<f64> {
        let mut value = Vec::new();
        self.eval_into(symbols, &mut value);
        self.roots.iter().map(|&r| value[r]).collect()
    }

    /// Evaluates every node into `value` (node k of `order` at index k, a product that only one
    /// sum reads computed inside it and not written: read the roots), reusing its storage.
    pub fn eval_into(&self, symbols: &[f64], value: &mut Vec<f64>) {
        self.eval_prefix_into(symbols, value, self.order.len());
    }

    /// Evaluates the first `count` nodes of `order` into `value` (the nodes the first roots
    /// reach come first: they need no other), reusing its storage.
    pub fn eval_prefix_into(&self, symbols: &[f64], value: &mut Vec<f64>, count: usize) {
        value.resize(self.order.len(), 0.0);
        self.code.eval_prefix(symbols, value, count);
    }
}
