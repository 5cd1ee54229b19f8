//! The expression DAG itself as JSON: every node the equations reach, operands first, each
//! referring to its operands by their index in `nodes`; the matrices as node indices.

use std::collections::HashMap;

use serde_json::{json, Value};

use super::shared::{Listing, Role, Symbols};
use crate::symbolic::expr::{ExprId, Function, Node};
use crate::symbolic::lower::Variable;
use crate::symbolic::Equations;

/// The equations of `source` as a JSON document (pretty-printed).
pub fn json(equations: &Equations, source: &str) -> String {
    let symbols = Symbols::new(equations);
    let listing = Listing::new(&symbols, &equations.roots());
    let index: HashMap<ExprId, usize> = listing
        .order
        .iter()
        .enumerate()
        .map(|(k, &id)| (id, k))
        .collect();
    let at = |id: &ExprId| index[id];
    let n = equations.dimension();
    let rows = |matrix: &[ExprId]| -> Vec<Vec<usize>> {
        matrix
            .chunks(n.max(1))
            .map(|row| row.iter().map(at).collect())
            .collect()
    };
    let document = json!({
        "source": source,
        "equations": "M(p) q' = S(p, q) + F(p, q, t) + Delta^T Lambda, Delta(p) q' + Delta_bias(p, q) = 0",
        "variables": variables(equations, &index),
        "nodes": listing.order.iter().map(|&id| node(&symbols, id, &index)).collect::<Vec<_>>(),
        "mass": if n == 0 { Vec::new() } else { rows(&equations.mass) },
        "second_member": equations.second_member.iter().map(at).collect::<Vec<_>>(),
        "forces": equations.forces.iter().map(at).collect::<Vec<_>>(),
        "constraints": if n == 0 { Vec::new() } else { rows(&equations.constraints) },
        "constraint_bias": equations.constraint_bias.iter().map(at).collect::<Vec<_>>(),
        "accelerations": equations.accelerations.as_ref().map(|a| a.iter().map(at).collect::<Vec<_>>()),
        "constraint_names": equations.constraint_names,
        "size": listing.order.len(),
    });
    serde_json::to_string_pretty(&document).unwrap_or_default() + "\n"
}

/// One node: `{"op": "add", "args": [i, j]}`, `{"op": "constant", "value": 2.0}`,
/// `{"op": "symbol", "name": "hinge.x"}`, `{"op": "sin", "args": [i]}`, or for the value of an
/// unknown function `{"op": "unknown_function", "function": "cL2_x", "name": "cL2_x(…)",
/// "args": [...]}`.
fn node(symbols: &Symbols, id: ExprId, index: &HashMap<ExprId, usize>) -> Value {
    let args = |operands: &[ExprId]| operands.iter().map(|o| index[o]).collect::<Vec<_>>();
    match symbols.pool.node(id) {
        Node::Constant(bits) => json!({ "op": "constant", "value": f64::from_bits(bits) }),
        Node::Symbol(i) => match symbols.role(id) {
            Some(Role::Function(k)) => {
                let use_ = &symbols.variables.functions[k];
                json!({ "op": "unknown_function", "function": use_.name, "name": symbols.pool.symbol_name(i), "args": args(&use_.arguments) })
            }
            _ => json!({ "op": "symbol", "name": symbols.pool.symbol_name(i) }),
        },
        Node::Add(a, b) => json!({ "op": "add", "args": args(&[a, b]) }),
        Node::Mul(a, b) => json!({ "op": "mul", "args": args(&[a, b]) }),
        Node::Div(a, b) => json!({ "op": "div", "args": args(&[a, b]) }),
        Node::Pow(a, b) => json!({ "op": "pow", "args": args(&[a, b]) }),
        Node::Atan2(y, x) => json!({ "op": "atan2", "args": args(&[y, x]) }),
        Node::Neg(a) => json!({ "op": "neg", "args": args(&[a]) }),
        Node::Apply(Function::ExponentialProfile(profile), a) => json!({
            "op": "exponential_profile",
            "args": args(&[a]),
            "sigma": profile.sigma(),
            "lambda": profile.lambda()
        }),
        Node::Apply(f, a) => json!({ "op": f.name(), "args": args(&[a]) }),
        // `args[1]` where `args[0] >= 0`, else `args[2]`.
        Node::Select {
            test,
            when_nonnegative,
            otherwise,
        } => json!({ "op": "select", "args": args(&[test, when_nonnegative, otherwise]) }),
    }
}

/// The variables with their meanings and nodes (`null` for one the equations do not use).
fn variables(equations: &Equations, index: &HashMap<ExprId, usize>) -> Value {
    let v = &equations.variables;
    let list = |list: &[Variable]| -> Vec<Value> {
        list.iter().map(|x| json!({ "name": x.name, "meaning": x.meaning, "given": x.given, "node": index.get(&x.symbol) })).collect()
    };
    let functions: Vec<Value> = v
        .functions
        .iter()
        .map(|f| json!({ "name": f.name, "node": index.get(&f.symbol), "arguments": f.arguments.iter().map(|a| index.get(a)).collect::<Vec<_>>() }))
        .collect();
    json!({
        "positions": list(&v.positions),
        "rates": list(&v.rates),
        "parameters": list(&v.parameters),
        "functions": functions,
        "time": index.get(&v.time),
    })
}
