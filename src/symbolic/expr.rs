//! A hash-consed expression DAG. Every node is interned in a `Pool`: building the same
//! expression twice gives the same `ExprId`, so common subexpressions are shared by construction
//! (no separate elimination pass) and the size of a set of equations is the number of distinct
//! nodes they reach. Constructors simplify locally: constants fold, 0 and 1 vanish where they
//! are neutral or absorbing, a double negation cancels, and the operands of sums and products are
//! put in a canonical order so that `a + b` and `b + a` are one node.

use std::collections::HashMap;

/// An expression: an index into its `Pool`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct ExprId(u32);

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
    Sin(ExprId),
    Cos(ExprId),
    Sqrt(ExprId),
}

#[derive(Default)]
pub struct Pool {
    nodes: Vec<Node>,
    index: HashMap<Node, ExprId>,
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

    fn intern(&mut self, node: Node) -> ExprId {
        if let Some(&id) = self.index.get(&node) {
            return id;
        }
        let id = ExprId(self.nodes.len() as u32);
        self.nodes.push(node);
        self.index.insert(node, id);
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

    /// The value of a constant node.
    pub fn as_constant(&self, id: ExprId) -> Option<f64> {
        match self.node(id) {
            Node::Constant(bits) => Some(f64::from_bits(bits)),
            _ => None,
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
        // a + (−a) = 0.
        if self.node(b) == Node::Neg(a) || self.node(a) == Node::Neg(b) {
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
            (Some(x), _) | (_, Some(x)) if x == 0.0 => return self.constant(0.0),
            (Some(1.0), _) => return b,
            (_, Some(1.0)) => return a,
            (Some(-1.0), _) => return self.neg(b),
            (_, Some(-1.0)) => return self.neg(a),
            _ => {}
        }
        self.intern(Node::Mul(a.min(b), a.max(b)))
    }

    pub fn neg(&mut self, a: ExprId) -> ExprId {
        match self.node(a) {
            Node::Constant(bits) => self.constant(-f64::from_bits(bits)),
            Node::Neg(inner) => inner,
            _ => self.intern(Node::Neg(a)),
        }
    }

    pub fn div(&mut self, a: ExprId, b: ExprId) -> ExprId {
        match (self.as_constant(a), self.as_constant(b)) {
            (Some(x), Some(y)) if y != 0.0 => self.constant(x / y),
            (Some(0.0), _) => self.constant(0.0),
            (_, Some(1.0)) => a,
            _ if a == b => self.constant(1.0),
            _ => self.intern(Node::Div(a, b)),
        }
    }

    pub fn sin(&mut self, a: ExprId) -> ExprId {
        match self.as_constant(a) {
            Some(x) => self.constant(x.sin()),
            None => self.intern(Node::Sin(a)),
        }
    }

    pub fn cos(&mut self, a: ExprId) -> ExprId {
        match self.as_constant(a) {
            Some(x) => self.constant(x.cos()),
            None => self.intern(Node::Cos(a)),
        }
    }

    pub fn sqrt(&mut self, a: ExprId) -> ExprId {
        match self.as_constant(a) {
            Some(x) if x >= 0.0 => self.constant(x.sqrt()),
            _ => self.intern(Node::Sqrt(a)),
        }
    }

    /// The operands of a node.
    pub fn operands(&self, id: ExprId) -> Vec<ExprId> {
        match self.node(id) {
            Node::Constant(_) | Node::Symbol(_) => Vec::new(),
            Node::Add(a, b) | Node::Mul(a, b) | Node::Div(a, b) => vec![a, b],
            Node::Neg(a) | Node::Sin(a) | Node::Cos(a) | Node::Sqrt(a) => vec![a],
        }
    }

    /// Whether `id` is the constant 0.
    pub fn is_zero(&self, id: ExprId) -> bool {
        self.is(id, 0.0)
    }
}

/// The nodes that `roots` reach, operands before the nodes that use them: the order in which to
/// evaluate them, or to emit one assignment each.
pub struct Tape {
    pub order: Vec<ExprId>,
    /// For each root, its position in `order`.
    pub roots: Vec<usize>,
}

impl Tape {
    pub fn new(pool: &Pool, roots: &[ExprId]) -> Tape {
        let mut position: HashMap<ExprId, usize> = HashMap::new();
        let mut order = Vec::new();
        for &root in roots {
            // Depth-first with an explicit stack: expression DAGs can be deep.
            let mut stack = vec![(root, false)];
            while let Some((id, expanded)) = stack.pop() {
                if position.contains_key(&id) {
                    continue;
                }
                if expanded {
                    position.insert(id, order.len());
                    order.push(id);
                } else {
                    stack.push((id, true));
                    stack.extend(pool.operands(id).into_iter().filter(|o| !position.contains_key(o)).map(|o| (o, false)));
                }
            }
        }
        let roots = roots.iter().map(|r| position[r]).collect();
        Tape { order, roots }
    }

    /// Number of distinct nodes the roots reach.
    pub fn size(&self) -> usize {
        self.order.len()
    }

    /// Evaluates every node with `symbols[i]` the value of symbol i; returns the roots' values.
    pub fn eval(&self, pool: &Pool, symbols: &[f64]) -> Vec<f64> {
        let mut value: HashMap<ExprId, f64> = HashMap::with_capacity(self.order.len());
        for &id in &self.order {
            let v = |o: ExprId| value[&o];
            let x = match pool.node(id) {
                Node::Constant(bits) => f64::from_bits(bits),
                Node::Symbol(i) => symbols[i as usize],
                Node::Add(a, b) => v(a) + v(b),
                Node::Mul(a, b) => v(a) * v(b),
                Node::Neg(a) => -v(a),
                Node::Div(a, b) => v(a) / v(b),
                Node::Sin(a) => v(a).sin(),
                Node::Cos(a) => v(a).cos(),
                Node::Sqrt(a) => v(a).sqrt(),
            };
            value.insert(id, x);
        }
        self.roots.iter().map(|&r| value[&self.order[r]]).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn equal_expressions_are_one_node() {
        let mut p = Pool::new();
        let (x, y) = (p.symbol("x"), p.symbol("y"));
        let a = p.add(x, y);
        let b = p.add(y, x);
        assert_eq!(a, b);
        let (s1, s2) = (p.sin(a), p.sin(b));
        assert_eq!(s1, s2);
        assert_eq!(p.symbol("x"), x);
    }

    #[test]
    fn neutral_and_absorbing_constants_vanish() {
        let mut p = Pool::new();
        let x = p.symbol("x");
        let (zero, one, minus_one) = (p.constant(0.0), p.constant(1.0), p.constant(-1.0));
        assert_eq!(p.add(x, zero), x);
        assert_eq!(p.mul(one, x), x);
        let absorbed = p.mul(x, zero);
        assert!(p.is_zero(absorbed));
        let minus_x = p.mul(minus_one, x);
        assert_eq!(p.neg(minus_x), x);
        let cancelled = p.sub(x, x);
        assert!(p.is_zero(cancelled));
        let two = p.constant(2.0);
        let three = p.constant(3.0);
        let five = p.add(two, three);
        assert_eq!(p.as_constant(five), Some(5.0));
        assert_eq!(p.constant(-0.0), zero);
    }

    #[test]
    fn shared_subexpressions_are_counted_once() {
        let mut p = Pool::new();
        let q = p.symbol("q");
        let (s, c) = (p.sin(q), p.cos(q));
        let sc = p.mul(s, c);
        let e1 = p.add(sc, s);
        let e2 = p.sub(sc, c);
        let tape = Tape::new(&p, &[e1, e2]);
        // q, sin q, cos q, sin q cos q, e1, −cos q, e2.
        assert_eq!(tape.size(), 7);
        let values = tape.eval(&p, &[0.3]);
        let (sv, cv) = (0.3f64.sin(), 0.3f64.cos());
        assert!((values[0] - (sv * cv + sv)).abs() < 1e-15);
        assert!((values[1] - (sv * cv - cv)).abs() < 1e-15);
    }
}
