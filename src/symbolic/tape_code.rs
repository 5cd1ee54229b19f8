//! A tape's evaluation code: its steps as compact instructions that an interpreter loop
//! dispatches. An evaluation of a law's tape (a gain-scheduled law reads thousands of nodes at
//! every right-hand side) is bound by the dispatch of its instructions, one indirect jump each,
//! and by their size; so the code holds 32-bit operand positions (24 bytes an instruction
//! with its node, against 48), and a product read by one sum or difference only is computed
//! inside it (`a b + c`, `a b − c`, `c − a b`), one dispatch for two nodes. The product is
//! rounded before the sum, as the two separate steps round it (Rust never contracts them into
//! a fused multiply–add), so the values are the same to the bit; the product's own node is then
//! not written, which no reader sees: only the roots are read, and a fused product is no root.

/// A function of one argument that an instruction applies (the expressions' `Function`).
pub(super) trait Apply: Copy {
    fn apply(self, x: f64) -> f64;
}

/// One instruction: the operation on the positions of its operands in the value vector, `F`
/// the functions of one argument.
#[derive(Clone, Copy, Debug)]
pub(super) enum Code<F> {
    Constant(f64),
    Symbol(u32),
    Add(u32, u32),
    Sub(u32, u32),
    Mul(u32, u32),
    Neg(u32),
    Div(u32, u32),
    Pow(u32, u32),
    Atan2(u32, u32),
    Apply(F, u32),
    /// `b` where `a ≥ 0`, else `c`.
    Select(u32, u32, u32),
    /// `a b + c`, the product rounded first.
    MulAdd(u32, u32, u32),
    /// `a b − c`, the product rounded first.
    MulSub(u32, u32, u32),
    /// `c − a b`, the product rounded first.
    SubMul(u32, u32, u32),
}

/// The instructions in evaluation order, each with the position of the node it writes.
#[derive(Clone, Debug)]
pub(super) struct TapeCode<F> {
    code: Vec<(u32, Code<F>)>,
}

impl<F: Apply> TapeCode<F> {
    /// The code of `program` (each step's node and operation, in evaluation order), with the
    /// products that only one sum or difference reads computed inside it; `roots` are read by
    /// the caller, so a product among them keeps its own instruction.
    pub(super) fn new(program: &[(usize, Code<F>)], roots: &[usize], nodes: usize) -> Self {
        let position = |k: usize| u32::try_from(k).expect("a tape of fewer than 2^32 nodes");
        let mut uses = vec![0usize; nodes];
        for &(_, code) in program {
            for operand in operands(code).into_iter().flatten() {
                uses[operand as usize] += 1;
            }
        }
        for &root in roots {
            uses[root] += 2;
        }
        let mut product = vec![None; nodes];
        for &(k, code) in program {
            if let Code::Mul(a, b) = code {
                if uses[k] == 1 {
                    product[k] = Some((a, b));
                }
            }
        }
        let mut fused = vec![false; nodes];
        let mut code = Vec::with_capacity(program.len());
        for &(k, step) in program {
            let mut take = |x: u32| {
                let found = product[x as usize];
                if found.is_some() {
                    fused[x as usize] = true;
                }
                found
            };
            let instruction = match step {
                Code::Add(x, y) => match take(x) {
                    Some((a, b)) => Code::MulAdd(a, b, y),
                    None => match take(y) {
                        Some((a, b)) => Code::MulAdd(a, b, x),
                        None => step,
                    },
                },
                Code::Sub(x, y) => match take(x) {
                    Some((a, b)) => Code::MulSub(a, b, y),
                    None => match take(y) {
                        Some((a, b)) => Code::SubMul(a, b, x),
                        None => step,
                    },
                },
                _ => step,
            };
            code.push((position(k), instruction));
        }
        // A product fused into its reader is not computed on its own.
        code.retain(|&(k, _)| !fused[k as usize]);
        TapeCode { code }
    }

    /// Evaluates the instructions of the nodes before `count` into `value` (sized by the
    /// caller to every node), with `symbols[i]` the value of symbol i.
    pub(super) fn eval_prefix(&self, symbols: &[f64], value: &mut [f64], count: usize) {
        let end = self.code.partition_point(|&(k, _)| (k as usize) < count);
        let at = |value: &[f64], a: u32| value[a as usize];
        for &(k, code) in &self.code[..end] {
            value[k as usize] = match code {
                Code::Constant(c) => c,
                Code::Symbol(i) => symbols[i as usize],
                Code::Add(a, b) => at(value, a) + at(value, b),
                Code::Sub(a, b) => at(value, a) - at(value, b),
                Code::Mul(a, b) => at(value, a) * at(value, b),
                Code::Neg(a) => -at(value, a),
                Code::Div(a, b) => at(value, a) / at(value, b),
                Code::Pow(a, b) => at(value, a).powf(at(value, b)),
                Code::Atan2(a, b) => at(value, a).atan2(at(value, b)),
                Code::Apply(f, a) => f.apply(at(value, a)),
                Code::Select(test, high, low) => match at(value, test) >= 0.0 {
                    true => at(value, high),
                    false => at(value, low),
                },
                Code::MulAdd(a, b, c) => at(value, a) * at(value, b) + at(value, c),
                Code::MulSub(a, b, c) => at(value, a) * at(value, b) - at(value, c),
                Code::SubMul(a, b, c) => at(value, c) - at(value, a) * at(value, b),
            };
        }
    }
}

fn operands<F>(code: Code<F>) -> [Option<u32>; 3] {
    match code {
        Code::Constant(_) | Code::Symbol(_) => [None, None, None],
        Code::Neg(a) | Code::Apply(_, a) => [Some(a), None, None],
        Code::Add(a, b)
        | Code::Sub(a, b)
        | Code::Mul(a, b)
        | Code::Div(a, b)
        | Code::Pow(a, b)
        | Code::Atan2(a, b) => [Some(a), Some(b), None],
        Code::Select(a, b, c)
        | Code::MulAdd(a, b, c)
        | Code::MulSub(a, b, c)
        | Code::SubMul(a, b, c) => [Some(a), Some(b), Some(c)],
    }
}
