//! The equations as a Maple worksheet, the thesis's target language (Papegay 1992, §3.1: the
//! compiler's products are read by Maple, as GEMMES's were): the variables as Maple names, the
//! temporaries, then the matrices `M`, `S`, `F`, `Delta`, `Delta_bias` (indices from 1), each
//! assignment ending in `;`. The names are the program's with `.` written `_` and a rate's `'`
//! written `_dot` (`hinge.x'` is `hinge_x_dot`); a name Maple protects (`D`, `I`, `Pi`, …) takes
//! a trailing `_`.

use std::fmt::Write;

use super::shared::{
    identifier_characters, nonzero_entries, Entry, Language, Listing, PowerSyntax, Precedence,
    Printer, Role, ScriptNames, Symbols,
};
use crate::symbolic::expr::{ExprId, Function};
use crate::symbolic::lower::Variable;
use crate::symbolic::Equations;

/// Names Maple protects or gives a meaning that would change the equations' (the names every
/// script assigns itself are added by `ScriptNames`).
const RESERVED: [&str; 29] = [
    "D",
    "I",
    "O",
    "Pi",
    "E",
    "gamma",
    "Catalan",
    "infinity",
    "undefined",
    "true",
    "false",
    "FAIL",
    "and",
    "or",
    "not",
    "xor",
    "implies",
    "in",
    "to",
    "by",
    "do",
    "od",
    "if",
    "fi",
    "then",
    "else",
    "end",
    "local",
    "global",
];

/// A Maple name for a program's name: letters, digits and `_`, not starting with a digit or `_`
/// (Maple reserves names starting with `_` for itself).
fn maple_name(name: &str) -> String {
    let mut out = identifier_characters(name);
    if out.is_empty() || out.starts_with(|c: char| c.is_ascii_digit() || c == '_') {
        out.insert(0, 'v');
    }
    out
}

struct Maple<'a> {
    names: &'a ScriptNames,
}

impl Language for Maple<'_> {
    fn infinity(&self) -> String {
        "infinity".to_string()
    }
    fn not_a_number(&self) -> String {
        "undefined".to_string()
    }
    fn symbol(&self, role: Role, name: &str) -> String {
        self.names.symbol(role, name)
    }
    fn temporary(&self, k: usize) -> String {
        self.names.temporary(k)
    }
    fn unknown_function(&self, _index: usize, name: &str, arguments: &[String]) -> String {
        self.names.unknown_function(name, arguments)
    }
    fn function(&self, f: Function, argument: &str) -> String {
        let name = match f {
            Function::Asin => "arcsin",
            Function::Acos => "arccos",
            Function::Atan => "arctan",
            Function::Log => "ln",
            other => other.name(),
        };
        format!("{name}({argument})")
    }
    /// Maple's two-argument `arctan(y, x)` is atan2.
    fn atan2(&self, y: &str, x: &str) -> String {
        format!("arctan({y}, {x})")
    }
    fn select(&self, test: &str, when_nonnegative: &str, otherwise: &str) -> String {
        format!("piecewise({test} >= 0, {when_nonnegative}, {otherwise})")
    }
    /// Maple's `^` does not associate and takes no sign after it: base and exponent are atoms.
    fn power_syntax(&self) -> PowerSyntax {
        PowerSyntax::Operator {
            exponent: Precedence::Atom,
        }
    }
    fn power_operator(&self, base: &str, exponent: &str) -> String {
        format!("{base}^{exponent}")
    }
    /// No sign after `*` or `/` either: `a * (-b)`.
    fn product_operand(&self) -> Precedence {
        Precedence::Power
    }
}

/// The equations of `source` as a Maple worksheet.
pub fn maple(equations: &Equations, source: &str) -> String {
    let symbols = Symbols::new(equations);
    let names = ScriptNames::new(equations, &RESERVED, maple_name);
    let entries = nonzero_entries(equations);
    let roots: Vec<ExprId> = entries.iter().map(|(_, id)| *id).collect();
    let listing = Listing::new(&symbols, &roots);
    let language = Maple { names: &names };
    let printer = Printer {
        symbols: &symbols,
        listing: &listing,
        language: &language,
    };
    let mut out = header(source, equations);
    declare_variables(&mut out, equations, &names);
    if !listing.temporaries.is_empty() {
        out.push_str("\n# Subexpressions used more than once.\n");
        for (k, &id) in listing.temporaries.iter().enumerate() {
            let _ = writeln!(
                out,
                "{} := {};",
                language.temporary(k),
                printer.definition(id)
            );
        }
    }
    let (n, m) = (equations.dimension(), equations.constraint_rows());
    let _ = writeln!(
        out,
        "\nM := Matrix({n}, {n}, shape = symmetric);\nS := Vector({n});\nF := Vector({n});\n\
         Delta := Matrix({m}, {n});\nDelta_bias := Vector({m});"
    );
    if equations.accelerations.is_some() {
        let _ = writeln!(out, "accelerations := Vector({n});");
    }
    for (entry, id) in entries {
        let _ = writeln!(out, "{} := {};", target(entry), printer.expression(id));
    }
    out
}

fn header(source: &str, equations: &Equations) -> String {
    format!(
        "# Equations of motion of `{source}`, written by lsdc for Maple:\n\
         #   M(p) . q' = S(p, q) + F(p, q, t) + Delta^T . Lambda,   Delta(p) . q' + Delta_bias(p, q) = 0\n\
         # p the positions, q their rates, q' the rates' derivatives, Lambda the constraints' multipliers.\n\
         # Derived by {}.\n",
        equations.form.description()
    )
}

fn declare_variables(out: &mut String, equations: &Equations, names: &ScriptNames) {
    let v = &equations.variables;
    let mut list = |title: &str, list: &[Variable], maple: &[String]| {
        if list.is_empty() {
            return;
        }
        let _ = writeln!(out, "\n# {title}");
        for (variable, name) in list.iter().zip(maple) {
            let given = variable
                .given
                .map(|g| format!(" (given {g:?})"))
                .unwrap_or_default();
            let _ = writeln!(out, "#   {name}: {}{given}", variable.meaning);
        }
    };
    list("Positions.", &v.positions, &names.positions);
    list("Rates.", &v.rates, &names.rates);
    list("Parameters.", &v.parameters, &names.parameters);
    if !names.functions.is_empty() {
        let _ = writeln!(
            out,
            "\n# Unknown functions of the program (left unassigned)."
        );
        for (name, maple) in &names.functions {
            let _ = writeln!(out, "#   {maple}: `{name}`");
        }
    }
    let _ = writeln!(out, "\n# Time.\n#   t");
}

/// The Maple assignment target of an entry (indices from 1); M is declared symmetric, so its
/// upper triangle defines it.
fn target(entry: Entry) -> String {
    match entry {
        Entry::Mass(i, j) => format!("M[{}, {}]", i + 1, j + 1),
        Entry::SecondMember(i) => format!("S[{}]", i + 1),
        Entry::Force(i) => format!("F[{}]", i + 1),
        Entry::Constraint(r, c) => format!("Delta[{}, {}]", r + 1, c + 1),
        Entry::Bias(r) => format!("Delta_bias[{}]", r + 1),
        Entry::Acceleration(i) => format!("accelerations[{}]", i + 1),
    }
}
