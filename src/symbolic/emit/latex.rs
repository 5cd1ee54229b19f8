//! The equations as a LaTeX document (amsmath's `align*`), with readable symbols:
//! `hinge.x` is x_hinge, its rate has a dot, `mu_1` is μ₁, `z34` is z₃₄.

use std::fmt::Write;

use super::shared::{
    described, nonzero_entries, temporary_prefix, Entry, Language, Listing, PowerSyntax,
    Precedence, Printer, Role, Symbols,
};
use crate::symbolic::expr::{ExponentialProfile, ExprId, Function};
use crate::symbolic::Equations;

const GREEK: [&str; 35] = [
    "alpha", "beta", "gamma", "delta", "epsilon", "zeta", "eta", "theta", "iota", "kappa",
    "lambda", "mu", "nu", "xi", "pi", "rho", "sigma", "tau", "upsilon", "phi", "chi", "psi",
    "omega", "Gamma", "Delta", "Theta", "Lambda", "Xi", "Pi", "Sigma", "Upsilon", "Phi", "Psi",
    "Omega", "varphi",
];

struct Latex<'a> {
    prefix: String,
    equations: &'a Equations,
}

impl Language for Latex<'_> {
    fn number(&self, value: f64) -> String {
        let text = format!("{value:?}");
        match text.split_once('e') {
            Some((mantissa, exponent)) => format!("{{{mantissa} \\times 10^{{{exponent}}}}}"),
            None => text,
        }
    }
    fn infinity(&self) -> String {
        "\\infty".to_string()
    }
    fn not_a_number(&self) -> String {
        "\\mathrm{NaN}".to_string()
    }
    fn symbol(&self, role: Role, name: &str) -> String {
        match role {
            Role::Position(i) => coordinate(&self.equations.variables.positions[i].name, false),
            Role::Rate(i) => coordinate(&self.equations.variables.positions[i].name, true),
            _ => identifier(name),
        }
    }
    fn temporary(&self, k: usize) -> String {
        identifier(&format!("{}{k}", self.prefix))
    }
    fn unknown_function(&self, _index: usize, name: &str, arguments: &[String]) -> String {
        format!(
            "\\operatorname{{{}}}\\left({}\\right)",
            escape(name),
            arguments.join(", ")
        )
    }
    fn function(&self, f: Function, argument: &str) -> String {
        let command = match f {
            Function::Sqrt => return format!("\\sqrt{{{argument}}}"),
            Function::Abs => return format!("\\left|{argument}\\right|"),
            Function::Floor => return format!("\\left\\lfloor {argument}\\right\\rfloor"),
            Function::ExponentialProfile(profile) => {
                return self.exponential_profile(argument, profile)
            }
            Function::Asin => "\\arcsin",
            Function::Acos => "\\arccos",
            Function::Atan => "\\arctan",
            Function::Sin => "\\sin",
            Function::Cos => "\\cos",
            Function::Tan => "\\tan",
            Function::Exp => "\\exp",
            Function::Log => "\\log",
        };
        format!("{command}\\left({argument}\\right)")
    }
    fn exponential_profile(&self, tau: &str, profile: ExponentialProfile) -> String {
        format!(
            "\\operatorname{{exponential\\_profile}}\\left({tau}, {}, {}\\right)",
            profile.sigma(),
            profile.lambda()
        )
    }
    fn atan2(&self, y: &str, x: &str) -> String {
        format!("\\operatorname{{atan2}}\\left({y}, {x}\\right)")
    }
    fn select(&self, test: &str, when_nonnegative: &str, otherwise: &str) -> String {
        format!("\\begin{{cases}} {when_nonnegative} & \\text{{if }} {test} \\geq 0 \\\\ {otherwise} & \\text{{otherwise}} \\end{{cases}}")
    }
    fn power_syntax(&self) -> PowerSyntax {
        PowerSyntax::Operator {
            exponent: Precedence::Lowest,
        }
    }
    fn power_operator(&self, base: &str, exponent: &str) -> String {
        // A fraction is an atom for the printer but needs parentheses as a base to be read right.
        let base = if base.starts_with("\\frac") {
            self.parenthesize(base)
        } else {
            base.to_string()
        };
        format!("{base}^{{{exponent}}}")
    }
    fn times(&self) -> &'static str {
        " \\cdot "
    }
    fn fraction(&self, numerator: &str, denominator: &str) -> Option<String> {
        Some(format!("\\frac{{{numerator}}}{{{denominator}}}"))
    }
    fn product_operand(&self) -> Precedence {
        Precedence::Power
    }
    fn parenthesize(&self, text: &str) -> String {
        format!("\\left({text}\\right)")
    }
}

/// The equations of `source` as a standalone LaTeX document.
pub fn latex(equations: &Equations, source: &str) -> String {
    let symbols = Symbols::new(equations);
    let entries = nonzero_entries(equations);
    let roots: Vec<ExprId> = entries.iter().map(|(_, id)| *id).collect();
    let listing = Listing::new(&symbols, &roots);
    let language = Latex {
        prefix: temporary_prefix(&symbols.all_names()),
        equations,
    };
    let printer = Printer {
        symbols: &symbols,
        listing: &listing,
        language: &language,
    };
    let mut out = preamble(source);
    variables(&mut out, equations, &language);
    let mut lines: Vec<String> = listing
        .temporaries
        .iter()
        .enumerate()
        .map(|(k, &id)| format!("{} &= {}", language.temporary(k), printer.definition(id)))
        .collect();
    lines.extend(
        entries.iter().map(|&(entry, id)| {
            format!("{} &= {}", label(entry, equations), printer.expression(id))
        }),
    );
    if !lines.is_empty() {
        let _ = writeln!(
            out,
            "\\begin{{align*}}\n{}\n\\end{{align*}}",
            lines.join(" \\\\\n")
        );
    }
    let _ = writeln!(
        out,
        "Size: {} distinct nodes.\n\\end{{document}}",
        listing.order.len()
    );
    out
}

fn preamble(source: &str) -> String {
    format!(
        "% Equations of motion of `{source}`, written by lsdc. The align* environment can be\n\
         % pasted into any document that loads amsmath.\n\
         \\documentclass{{article}}\n\\usepackage{{amsmath}}\n\\allowdisplaybreaks\n\\begin{{document}}\n\
         \\section*{{Equations of motion of \\texttt{{{}}}}}\n\
         \\[ M(p)\\,\\dot q = S(p, q) + F(p, q, t) + \\Delta^{{\\mathsf T}} \\Lambda, \\qquad \\Delta(p)\\,\\dot q + \\dot\\Delta q = 0 \\]\n\
         with $p$ the positions, $q$ their rates and $\\Lambda$ the constraints' multipliers. Indices count from 1 in the\n\
         order of the positions; constraint rows go by name. $M$ is symmetric: only $M_{{i,j}}$ with $i \\le j$ is written.\n\
         Entries equal to zero are left out.\n",
        escape(source)
    )
}

fn variables(out: &mut String, equations: &Equations, language: &Latex) {
    let v = &equations.variables;
    let mut items: Vec<String> = Vec::new();
    for (i, p) in v.positions.iter().enumerate() {
        items.push(format!(
            "${}$ (position {}): {}",
            language.symbol(Role::Position(i), &p.name),
            i + 1,
            prose(&p.meaning)
        ));
    }
    for (i, r) in v.rates.iter().enumerate() {
        items.push(format!(
            "${}$: {}",
            language.symbol(Role::Rate(i), &r.name),
            prose(&r.meaning)
        ));
    }
    for p in &v.parameters {
        items.push(format!(
            "${}$: {}",
            identifier(&p.name),
            prose(&described(&p.meaning, p.given))
        ));
    }
    for f in &v.functions {
        items.push(format!(
            "$\\operatorname{{{}}}$: an unknown function of the program",
            escape(&f.name)
        ));
    }
    items.push("$t$: time".to_string());
    let _ = writeln!(out, "\\subsection*{{Variables}}\n\\begin{{itemize}}");
    for item in items {
        let _ = writeln!(out, "\\item {item}");
    }
    let _ = writeln!(out, "\\end{{itemize}}");
}

fn label(entry: Entry, equations: &Equations) -> String {
    let row = |r: usize| format!("\\mathrm{{{}}}", escape(&equations.constraint_names[r]));
    match entry {
        Entry::Mass(i, j) => format!("M_{{{},{}}}", i + 1, j + 1),
        Entry::SecondMember(i) => format!("S_{{{}}}", i + 1),
        Entry::Force(i) => format!("F_{{{}}}", i + 1),
        Entry::Constraint(r, c) => format!("\\Delta_{{{},{}}}", row(r), c + 1),
        Entry::Bias(r) => format!("(\\dot\\Delta q)_{{{}}}", row(r)),
        Entry::Acceleration(i) => format!("\\dot q_{{{}}}", i + 1),
    }
}

/// `join.coordinate` as the coordinate with the join's name in its subscript, dotted for a rate.
fn coordinate(name: &str, dotted: bool) -> String {
    let (join, coordinate) = name.rsplit_once('.').unwrap_or(("", name));
    let (head, mut subscripts) = parts(coordinate);
    if !join.is_empty() {
        subscripts.push(format!("\\mathrm{{{}}}", escape(join)));
    }
    let head = if dotted {
        format!("\\dot{{{head}}}")
    } else {
        head
    };
    compose(head, &subscripts)
}

/// An identifier such as `mu_1`, `mIg_1_x` or `z34`: the part before the first underscore,
/// less its trailing digits, is the symbol (a Greek letter by its name); the rest is its
/// subscript.
fn identifier(name: &str) -> String {
    let (head, subscripts) = parts(name);
    compose(head, &subscripts)
}

fn parts(name: &str) -> (String, Vec<String>) {
    let mut pieces = name.split('_');
    let first = pieces.next().unwrap_or_default();
    let letters = first.trim_end_matches(|c: char| c.is_ascii_digit());
    let (letters, digits) = if letters.is_empty() {
        (first, "")
    } else {
        (letters, &first[letters.len()..])
    };
    let mut subscripts: Vec<String> = Vec::new();
    if !digits.is_empty() {
        subscripts.push(digits.to_string());
    }
    subscripts.extend(pieces.filter(|p| !p.is_empty()).map(subscript));
    (symbol(letters), subscripts)
}

fn symbol(letters: &str) -> String {
    if GREEK.contains(&letters) {
        format!("\\{letters}")
    } else if letters.chars().count() == 1 && letters.chars().all(|c| c.is_ascii_alphabetic()) {
        letters.to_string()
    } else {
        format!("\\mathit{{{}}}", escape(letters))
    }
}

fn subscript(piece: &str) -> String {
    if GREEK.contains(&piece) {
        format!("\\{piece}")
    } else if piece.chars().all(|c| c.is_ascii_digit()) || piece.chars().count() == 1 {
        escape(piece)
    } else {
        format!("\\mathrm{{{}}}", escape(piece))
    }
}

fn compose(head: String, subscripts: &[String]) -> String {
    if subscripts.is_empty() {
        head
    } else {
        format!("{head}_{{{}}}", subscripts.join(","))
    }
}

/// Characters that LaTeX reads as commands, escaped (in text and in `\mathrm`).
fn escape(text: &str) -> String {
    let mut out = String::new();
    for c in text.chars() {
        match c {
            '_' | '#' | '$' | '%' | '&' | '{' | '}' => {
                out.push('\\');
                out.push(c);
            }
            '\\' => out.push_str("\\textbackslash{}"),
            '~' => out.push_str("\\textasciitilde{}"),
            '^' => out.push_str("\\textasciicircum{}"),
            '\'' => out.push_str("{\\textquotesingle}"),
            _ => out.push(c),
        }
    }
    out
}

/// A meaning as text: escaped, with `code` in typewriter type.
fn prose(text: &str) -> String {
    let mut out = String::new();
    for (k, piece) in text.split('`').enumerate() {
        if k % 2 == 1 {
            let _ = write!(out, "\\texttt{{{}}}", escape(piece));
        } else {
            out.push_str(&escape(piece));
        }
    }
    out
}
