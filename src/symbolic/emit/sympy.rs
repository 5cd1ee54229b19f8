//! The equations as a Python module that needs only SymPy: the variables as `sp.Symbol`s named
//! as in the program, the unknown functions as `sp.Function`s, the temporaries, then the
//! matrices `M`, `S`, `F`, `Delta`, `Delta_bias`.

use std::fmt::Write;

use super::shared::{
    identifier_characters, nonzero_entries, Entry, Language, Listing, PowerSyntax, Precedence,
    Printer, Role, ScriptNames, Symbols,
};
use crate::symbolic::expr::{ExponentialProfile, ExprId, Function};
use crate::symbolic::lower::Variable;
use crate::symbolic::Equations;

const KEYWORDS: [&str; 35] = [
    "False", "None", "True", "and", "as", "assert", "async", "await", "break", "class", "continue",
    "def", "del", "elif", "else", "except", "finally", "for", "from", "global", "if", "import",
    "in", "is", "lambda", "nonlocal", "not", "or", "pass", "raise", "return", "try", "while",
    "with", "yield",
];

/// Names the module defines itself beside those every script defines (`ScriptNames` adds those).
const RESERVED: [&str; 8] = [
    "sp",
    "positions",
    "rates",
    "parameters",
    "given",
    "functions",
    "constraint_names",
    "source",
];

/// A Python identifier for a name: `hinge.x'` is `hinge_x_dot`.
fn sanitize(name: &str) -> String {
    let mut out = identifier_characters(name);
    if out.is_empty() || out.starts_with(|c: char| c.is_ascii_digit()) {
        out.insert(0, '_');
    }
    out
}

struct Python<'a> {
    names: &'a ScriptNames,
}

impl Language for Python<'_> {
    fn infinity(&self) -> String {
        "sp.oo".to_string()
    }
    fn not_a_number(&self) -> String {
        "sp.nan".to_string()
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
        let name = if f == Function::Abs { "Abs" } else { f.name() };
        format!("sp.{name}({argument})")
    }
    /// An undefined SymPy function: its value is a quadrature (`symbolic::exponential_profile`).
    fn exponential_profile(&self, tau: &str, profile: ExponentialProfile) -> String {
        format!(
            "sp.Function('exponential_profile')({tau}, {:?}, {:?})",
            profile.sigma(),
            profile.lambda()
        )
    }
    fn atan2(&self, y: &str, x: &str) -> String {
        format!("sp.atan2({y}, {x})")
    }
    fn select(&self, test: &str, when_nonnegative: &str, otherwise: &str) -> String {
        format!("sp.Piecewise(({when_nonnegative}, {test} >= 0), ({otherwise}, True))")
    }
    fn power_syntax(&self) -> PowerSyntax {
        PowerSyntax::Operator {
            exponent: Precedence::Unary,
        }
    }
    fn power_operator(&self, base: &str, exponent: &str) -> String {
        format!("{base}**{exponent}")
    }
}

/// The equations of `source` as a Python module.
pub fn sympy(equations: &Equations, source: &str) -> String {
    let symbols = Symbols::new(equations);
    let reserved: Vec<&str> = KEYWORDS.iter().chain(&RESERVED).copied().collect();
    let names = ScriptNames::new(equations, &reserved, sanitize);
    let entries = nonzero_entries(equations);
    let roots: Vec<ExprId> = entries.iter().map(|(_, id)| *id).collect();
    let listing = Listing::new(&symbols, &roots);
    let language = Python { names: &names };
    let printer = Printer {
        symbols: &symbols,
        listing: &listing,
        language: &language,
    };
    let mut out = header(source);
    declare_variables(&mut out, equations, &names);
    if !listing.temporaries.is_empty() {
        out.push_str("\n# Subexpressions used more than once.\n");
        for (k, &id) in listing.temporaries.iter().enumerate() {
            let _ = writeln!(
                out,
                "{} = {}",
                language.temporary(k),
                printer.definition(id)
            );
        }
    }
    let (n, m) = (equations.dimension(), equations.constraint_rows());
    let _ = writeln!(out, "\nM = sp.zeros({n}, {n})\nS = sp.zeros({n}, 1)\nF = sp.zeros({n}, 1)\nDelta = sp.zeros({m}, {n})\nDelta_bias = sp.zeros({m}, 1)");
    // For a tree, the forward dynamics q' = M⁻¹ (S + F) by the articulated-body recursion.
    let accelerations = if equations.accelerations.is_some() {
        format!("sp.zeros({n}, 1)")
    } else {
        "None".to_string()
    };
    let _ = writeln!(out, "accelerations = {accelerations}");
    for (entry, id) in entries {
        let value = printer.expression(id);
        let _ = writeln!(out, "{} = {value}", target(entry));
    }
    lists(&mut out, equations, &names, &language);
    out
}

fn header(source: &str) -> String {
    format!(
        "\"\"\"Equations of motion of `{}`, written by lsdc:\n\n    \
         M(p) q' = S(p, q) + F(p, q, t) + Delta^T Lambda,   Delta(p) q' + Delta_bias(p, q) = 0\n\n\
         with p the positions, q their rates, q' the rates' derivatives and Lambda the constraints'\n\
         multipliers. M is symmetric. Needs only SymPy.\n\"\"\"\n\nimport sympy as sp\n\nsource = {}\n",
        source.replace('\\', "\\\\").replace('"', "\\\""),
        python_string(source)
    )
}

fn python_string(text: &str) -> String {
    format!("'{}'", text.replace('\\', "\\\\").replace('\'', "\\'"))
}

fn declare_variables(out: &mut String, equations: &Equations, names: &ScriptNames) {
    let v = &equations.variables;
    let mut declare = |title: &str, list: &[Variable], python: &[String]| {
        if list.is_empty() {
            return;
        }
        let _ = writeln!(out, "\n# {title}");
        for (variable, name) in list.iter().zip(python) {
            let _ = writeln!(
                out,
                "{name} = sp.Symbol({})  # {}",
                python_string(&variable.name),
                variable.meaning
            );
        }
    };
    declare("Positions.", &v.positions, &names.positions);
    declare("Rates.", &v.rates, &names.rates);
    declare("Parameters.", &v.parameters, &names.parameters);
    let _ = writeln!(out, "\n# Time.\nt = sp.Symbol('t')");
    if !names.functions.is_empty() {
        let _ = writeln!(out, "\n# Unknown functions of the program.");
        for (name, python) in &names.functions {
            let _ = writeln!(out, "{python} = sp.Function({})", python_string(name));
        }
    }
}

/// The Python assignment target of an entry; M's mirror entry is assigned too.
fn target(entry: Entry) -> String {
    match entry {
        Entry::Mass(i, j) if i == j => format!("M[{i}, {j}]"),
        Entry::Mass(i, j) => format!("M[{i}, {j}] = M[{j}, {i}]"),
        Entry::SecondMember(i) => format!("S[{i}]"),
        Entry::Force(i) => format!("F[{i}]"),
        Entry::Constraint(r, c) => format!("Delta[{r}, {c}]"),
        Entry::Bias(r) => format!("Delta_bias[{r}]"),
        Entry::Acceleration(i) => format!("accelerations[{i}]"),
    }
}

fn lists(out: &mut String, equations: &Equations, names: &ScriptNames, language: &Python) {
    let v = &equations.variables;
    let list = |items: &[String]| format!("[{}]", items.join(", "));
    let _ = writeln!(out, "\npositions = {}", list(&names.positions));
    let _ = writeln!(out, "rates = {}", list(&names.rates));
    let _ = writeln!(out, "parameters = {}", list(&names.parameters));
    let given: Vec<String> = v
        .parameters
        .iter()
        .zip(&names.parameters)
        .filter_map(|(p, name)| p.given.map(|g| format!("{name}: {g:?}")))
        .collect();
    let _ = writeln!(
        out,
        "# The parameters' values given by the program.\ngiven = {{{}}}",
        given.join(", ")
    );
    let symbols = Symbols::new(equations);
    let whole = Listing::inline(
        &symbols,
        &v.functions.iter().map(|f| f.symbol).collect::<Vec<_>>(),
    );
    let printer = Printer {
        symbols: &symbols,
        listing: &whole,
        language,
    };
    let applications: Vec<String> = v
        .functions
        .iter()
        .map(|f| printer.definition(f.symbol))
        .collect();
    let _ = writeln!(
        out,
        "# The unknown functions as applied in the equations.\nfunctions = {}",
        list(&applications)
    );
    let rows: Vec<String> = equations
        .constraint_names
        .iter()
        .map(|n| python_string(n))
        .collect();
    let _ = writeln!(out, "constraint_names = {}", list(&rows));
}
