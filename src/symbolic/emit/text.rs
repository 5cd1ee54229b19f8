//! The equations for people: the variables, the temporaries, then every nonzero entry.

use std::fmt::Write;

use super::shared::{
    described, nonzero_entries, temporary_prefix, Entry, Language, Listing, PowerSyntax,
    Precedence, Printer, Role, Symbols,
};
use crate::symbolic::expr::{ExprId, Function};
use crate::symbolic::lower::Variable;
use crate::symbolic::Equations;

struct Text {
    prefix: String,
}

impl Language for Text {
    fn infinity(&self) -> String {
        "inf".to_string()
    }
    fn not_a_number(&self) -> String {
        "NaN".to_string()
    }
    fn symbol(&self, _role: Role, name: &str) -> String {
        name.to_string()
    }
    fn temporary(&self, k: usize) -> String {
        format!("{}{k}", self.prefix)
    }
    fn unknown_function(&self, _index: usize, name: &str, arguments: &[String]) -> String {
        format!("{name}({})", arguments.join(", "))
    }
    fn function(&self, f: Function, argument: &str) -> String {
        format!("{}({argument})", f.name())
    }
    fn atan2(&self, y: &str, x: &str) -> String {
        format!("atan2({y}, {x})")
    }
    fn select(&self, test: &str, when_nonnegative: &str, otherwise: &str) -> String {
        format!("select({test} >= 0, {when_nonnegative}, {otherwise})")
    }
    fn power_syntax(&self) -> PowerSyntax {
        PowerSyntax::Operator {
            exponent: Precedence::Unary,
        }
    }
}

/// The equations of `source` as plain text.
pub fn text(equations: &Equations, source: &str) -> String {
    let symbols = Symbols::new(equations);
    let entries = nonzero_entries(equations);
    let roots: Vec<ExprId> = entries.iter().map(|(_, id)| *id).collect();
    let listing = Listing::new(&symbols, &roots);
    let language = Text {
        prefix: temporary_prefix(&symbols.all_names()),
    };
    let printer = Printer {
        symbols: &symbols,
        listing: &listing,
        language: &language,
    };
    let mut out = header(source);
    if equations.form != crate::symbolic::Form::Lagrange {
        let _ = writeln!(out, "# Derived by {}.", equations.form.description());
    }
    variables(&mut out, equations);
    if !listing.temporaries.is_empty() {
        out.push_str("\ntemporaries\n");
        for (k, &id) in listing.temporaries.iter().enumerate() {
            let _ = writeln!(
                out,
                "  {} = {}",
                language.temporary(k),
                printer.definition(id)
            );
        }
    }
    out.push('\n');
    for (entry, id) in entries {
        let _ = writeln!(
            out,
            "{} = {}",
            label(entry, equations),
            printer.expression(id)
        );
    }
    let _ = writeln!(out, "\nsize: {} distinct nodes", listing.order.len());
    out
}

fn header(source: &str) -> String {
    format!(
        "# Equations of motion of `{source}`:\n\
         #   M(p) q' = S(p, q) + F(p, q, t) + Δᵀ Λ,   Δ(p) q' + Δ̇q = 0\n\
         # p the positions, q their rates, q' the rates' derivatives, Λ the constraints' multipliers.\n\
         # Indices count from 1 in the order of the positions; constraint rows go by name.\n\
         # M is symmetric: only M[i,j] with i ≤ j is listed. Entries equal to zero are left out.\n\
         # For a tree, q'[i] is the forward dynamics, by the articulated-body recursion.\n"
    )
}

fn variables(out: &mut String, equations: &Equations) {
    let v = &equations.variables;
    let numbered = |out: &mut String, title: &str, list: &[Variable]| {
        let _ = writeln!(out, "\n{title}");
        for (i, variable) in list.iter().enumerate() {
            let _ = writeln!(
                out,
                "  {:>3}  {:<24} {}",
                i + 1,
                variable.name,
                variable.meaning
            );
        }
    };
    numbered(out, "positions", &v.positions);
    numbered(out, "rates", &v.rates);
    if !v.parameters.is_empty() {
        out.push_str("\nparameters\n");
        for p in &v.parameters {
            let _ = writeln!(out, "  {:<29} {}", p.name, described(&p.meaning, p.given));
        }
    }
    if !v.functions.is_empty() {
        out.push_str("\nunknown functions applied\n");
        for f in &v.functions {
            let _ = writeln!(
                out,
                "  {}",
                equations.pool.name_of(f.symbol).unwrap_or_default()
            );
        }
    }
    out.push_str("\ntime\n  t\n");
}

fn label(entry: Entry, equations: &Equations) -> String {
    let names = &equations.constraint_names;
    match entry {
        Entry::Mass(i, j) => format!("M[{},{}]", i + 1, j + 1),
        Entry::SecondMember(i) => format!("S[{}]", i + 1),
        Entry::Force(i) => format!("F[{}]", i + 1),
        Entry::Constraint(r, c) => format!("Δ[{},{}]", names[r], c + 1),
        Entry::Bias(r) => format!("Δ̇q[{}]", names[r]),
        Entry::Acceleration(i) => format!("q'[{}]", i + 1),
    }
}
