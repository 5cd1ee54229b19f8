//! What the Rust and C emitters share: the functions that evaluate parts of the equations, each
//! computing only the nodes its own outputs reach.

use std::fmt::Write;

use super::shared::{upper_triangle, Language, Listing, Printer, Role, Symbols};
use crate::symbolic::expr::ExprId;
use crate::symbolic::Equations;

/// One generated function: `array[target] = sum of terms` for each output.
pub struct Routine {
    pub listing: Listing,
    /// Target index in the output array, and the terms summed there.
    pub outputs: Vec<(usize, Vec<ExprId>)>,
    /// `array[target] = array[source]` after the outputs: M's lower triangle.
    pub mirrors: Vec<(usize, usize)>,
    /// Length of the output array.
    pub length: usize,
    /// Values the function checks are finite with its outputs (`zero_products`).
    pub guards: Vec<ExprId>,
    pub uses_time: bool,
    pub uses_functions: bool,
}

impl Routine {
    fn new(symbols: &Symbols, length: usize, outputs: Vec<(usize, Vec<ExprId>)>) -> Routine {
        Routine::guarded(symbols, length, outputs, Vec::new())
    }

    /// A routine that also computes `guards`, to check them.
    fn guarded(
        symbols: &Symbols,
        length: usize,
        outputs: Vec<(usize, Vec<ExprId>)>,
        guards: Vec<ExprId>,
    ) -> Routine {
        let outputs: Vec<(usize, Vec<ExprId>)> = outputs
            .into_iter()
            .map(|(target, terms)| {
                (
                    target,
                    terms
                        .into_iter()
                        .filter(|&t| !symbols.pool.is_zero(t))
                        .collect::<Vec<_>>(),
                )
            })
            .filter(|(_, terms)| !terms.is_empty())
            .collect();
        let roots: Vec<ExprId> = outputs
            .iter()
            .flat_map(|(_, terms)| terms.iter().copied())
            .chain(guards.iter().copied())
            .collect();
        let listing = Listing::new(symbols, &roots);
        let uses_time = listing.uses(symbols, |r| r == Role::Time);
        let uses_functions = listing.uses(symbols, |r| matches!(r, Role::Function(_)));
        Routine {
            listing,
            outputs,
            mirrors: Vec::new(),
            length,
            guards,
            uses_time,
            uses_functions,
        }
    }

    /// The statements of the function's body: the output zeroed (only nonzero entries are
    /// assigned), one declaration per temporary, one assignment per output.
    pub fn body<L: Language>(
        &self,
        symbols: &Symbols,
        language: &L,
        syntax: &dyn Statements,
        array: &str,
    ) -> String {
        let printer = Printer {
            symbols,
            listing: &self.listing,
            language,
        };
        let mut out = String::new();
        let _ = writeln!(out, "    {}", syntax.zero(array, self.length));
        for (k, &id) in self.listing.temporaries.iter().enumerate() {
            let _ = writeln!(
                out,
                "    {}",
                syntax.declare(&language.temporary(k), &printer.definition(id))
            );
        }
        for (target, terms) in &self.outputs {
            let _ = writeln!(
                out,
                "    {array}[{target}] = {};",
                printer.sum(terms, "0.0")
            );
        }
        for (target, source) in &self.mirrors {
            let _ = writeln!(out, "    {array}[{target}] = {array}[{source}];");
        }
        out
    }

    /// The guards as expressions of the function's temporaries and inputs.
    pub fn guard_expressions<L: Language>(&self, symbols: &Symbols, language: &L) -> Vec<String> {
        let printer = Printer {
            symbols,
            listing: &self.listing,
            language,
        };
        self.guards
            .iter()
            .map(|&id| printer.expression(id))
            .collect()
    }
}

/// The statements that differ between the languages.
pub trait Statements {
    fn declare(&self, name: &str, value: &str) -> String;
    /// Sets `array[0..length]` to zero.
    fn zero(&self, array: &str, length: usize) -> String;
}

/// The functions of the generated code.
pub struct Routines {
    /// M's upper triangle, mirrored.
    pub mass: Routine,
    /// S + F.
    pub right_hand_side: Routine,
    /// Δ and Δ̇q, for a mechanism with loops.
    pub loops: Option<(Routine, Routine)>,
    /// q' by the articulated-body recursion, for a tree.
    pub accelerations: Option<Routine>,
}

impl Routines {
    /// The functions of `equations`, the forward dynamics checking `guards` (`zero_products`).
    pub fn new(symbols: &Symbols, equations: &Equations, guards: &[ExprId]) -> Routines {
        let n = equations.dimension();
        let upper = upper_triangle(equations);
        let mut mass = Routine::new(
            symbols,
            n * n,
            upper
                .iter()
                .map(|&(i, j, id)| (i * n + j, vec![id]))
                .collect(),
        );
        let assigned: std::collections::HashSet<usize> =
            mass.outputs.iter().map(|(target, _)| *target).collect();
        mass.mirrors = upper
            .iter()
            .filter(|&&(i, j, _)| i < j && assigned.contains(&(i * n + j)))
            .map(|&(i, j, _)| (j * n + i, i * n + j))
            .collect();
        let sums = (0..n)
            .map(|i| (i, vec![equations.second_member[i], equations.forces[i]]))
            .collect();
        let right_hand_side = Routine::new(symbols, n, sums);
        let loops = (equations.constraint_rows() > 0).then(|| {
            let delta = Routine::new(
                symbols,
                equations.constraints.len(),
                equations
                    .constraints
                    .iter()
                    .enumerate()
                    .map(|(k, &id)| (k, vec![id]))
                    .collect(),
            );
            let bias = Routine::new(
                symbols,
                equations.constraint_rows(),
                equations
                    .constraint_bias
                    .iter()
                    .enumerate()
                    .map(|(r, &id)| (r, vec![id]))
                    .collect(),
            );
            (delta, bias)
        });
        let accelerations = equations
            .accelerations
            .as_ref()
            .filter(|_| loops.is_none())
            .map(|a| {
                Routine::guarded(
                    symbols,
                    n,
                    a.iter().enumerate().map(|(i, &id)| (i, vec![id])).collect(),
                    guards.to_vec(),
                )
            });
        Routines {
            mass,
            right_hand_side,
            loops,
            accelerations,
        }
    }

    /// Whether any function needs the unknown functions' values: then forward dynamics does.
    pub fn uses_functions(&self) -> bool {
        let loops = self
            .loops
            .as_ref()
            .is_some_and(|(d, b)| d.uses_functions || b.uses_functions);
        let accelerations = self
            .accelerations
            .as_ref()
            .is_some_and(|a| a.uses_functions);
        self.mass.uses_functions || self.right_hand_side.uses_functions || loops || accelerations
    }
}

/// A variable in the generated functions: an element of the argument arrays `p` (positions),
/// `q` (rates) and `k` (parameters), the time `t`, or an unknown function's value by its name.
pub fn array_symbol(role: Role, name: &str) -> String {
    match role {
        Role::Position(i) => format!("p[{i}]"),
        Role::Rate(i) => format!("q[{i}]"),
        Role::Parameter(i) => format!("k[{i}]"),
        Role::Time => "t".to_string(),
        Role::Function(_) => name.to_string(),
    }
}

/// Text safe inside a comment of either language.
pub fn comment(text: &str) -> String {
    text.replace("*/", "* /").replace('\n', " ")
}
