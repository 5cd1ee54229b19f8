//! What every format shares: which symbol stands for what, which nodes get a name (the
//! temporaries), and printing an expression with as few parentheses as its operators allow.
//!
//! Parentheses follow the tree exactly: the right operand of `-`, `+`, `*` and `/` is
//! parenthesised whenever it has the same precedence, so `a + (b + c)` stays as written. The
//! generated code then computes the same floating-point operations in the same order as
//! `Tape::eval`.

use std::collections::{HashMap, HashSet};

use crate::symbolic::expr::{ExponentialProfile, ExprId, Function, Node, Pool};
use crate::symbolic::lower::{Variable, Variables};
use crate::symbolic::Equations;

/// What a pool symbol stands for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Role {
    Position(usize),
    Rate(usize),
    Parameter(usize),
    /// The value of an unknown function applied to arguments: index into `variables.functions`.
    Function(usize),
    Time,
}

/// The roles of the symbols of one set of equations.
pub struct Symbols<'a> {
    pub pool: &'a Pool,
    pub variables: &'a Variables,
    roles: HashMap<u32, Role>,
}

impl<'a> Symbols<'a> {
    pub fn new(equations: &'a Equations) -> Symbols<'a> {
        let pool = &equations.pool;
        let variables = &equations.variables;
        let mut roles = HashMap::new();
        let mut add = |id: ExprId, role: Role| {
            if let Node::Symbol(i) = pool.node(id) {
                roles.insert(i, role);
            }
        };
        add(variables.time, Role::Time);
        variables
            .positions
            .iter()
            .enumerate()
            .for_each(|(i, v)| add(v.symbol, Role::Position(i)));
        variables
            .rates
            .iter()
            .enumerate()
            .for_each(|(i, v)| add(v.symbol, Role::Rate(i)));
        variables
            .parameters
            .iter()
            .enumerate()
            .for_each(|(i, v)| add(v.symbol, Role::Parameter(i)));
        variables
            .functions
            .iter()
            .enumerate()
            .for_each(|(i, f)| add(f.symbol, Role::Function(i)));
        Symbols {
            pool,
            variables,
            roles,
        }
    }

    /// The role of a symbol node; `None` for other nodes (and for a symbol the lowering did not
    /// create, which cannot happen for generated equations).
    pub fn role(&self, id: ExprId) -> Option<Role> {
        match self.pool.node(id) {
            Node::Symbol(i) => self.roles.get(&i).copied(),
            _ => None,
        }
    }

    /// The operands of a node, counting an unknown function's arguments as the operands of its
    /// value: they must be computed before it.
    pub fn operands(&self, id: ExprId) -> Vec<ExprId> {
        match self.role(id) {
            Some(Role::Function(k)) => self.variables.functions[k].arguments.clone(),
            _ => self.pool.operands(id),
        }
    }

    /// The name a person would use: the variable's name (`hinge.x'`, `mu_1`, `t`), or for a
    /// function use, the function's name.
    pub fn name(&self, id: ExprId) -> String {
        match (self.role(id), self.pool.node(id)) {
            (Some(Role::Function(k)), _) => self.variables.functions[k].name.clone(),
            (_, Node::Symbol(i)) => self.pool.symbol_name(i).to_string(),
            _ => format!("e{}", id.index()),
        }
    }

    /// Every variable name, for choosing names that cannot collide with them.
    pub fn all_names(&self) -> Vec<String> {
        let v = self.variables;
        let names = v
            .positions
            .iter()
            .chain(&v.rates)
            .chain(&v.parameters)
            .map(|v| v.name.clone());
        names
            .chain(v.functions.iter().map(|f| f.name.clone()))
            .chain(["t".to_string()])
            .collect()
    }
}

/// The nodes some roots need, in evaluation order, and the names of the shared ones.
pub struct Listing {
    /// Every node the roots reach, operands first (an unknown function's arguments first too).
    pub order: Vec<ExprId>,
    /// The nodes used more than once that are neither constants nor plain symbols, in `order`:
    /// each is computed once, as the temporary `{prefix}{k}`.
    pub temporaries: Vec<ExprId>,
    named: HashMap<ExprId, usize>,
}

impl Listing {
    pub fn new(symbols: &Symbols, roots: &[ExprId]) -> Listing {
        let order = reachable(symbols, roots);
        let mut uses: HashMap<ExprId, usize> = HashMap::new();
        for &id in order.iter() {
            for operand in symbols.operands(id) {
                *uses.entry(operand).or_default() += 1;
            }
        }
        for &root in roots {
            *uses.entry(root).or_default() += 1;
        }
        let worth_naming = |id: ExprId| match symbols.pool.node(id) {
            Node::Constant(_) => false,
            Node::Symbol(_) => symbols
                .role(id)
                .is_some_and(|r| matches!(r, Role::Function(_))),
            _ => true,
        };
        let temporaries: Vec<ExprId> = order
            .iter()
            .copied()
            .filter(|&id| uses.get(&id).copied().unwrap_or(0) > 1 && worth_naming(id))
            .collect();
        let named = temporaries
            .iter()
            .enumerate()
            .map(|(k, &id)| (id, k))
            .collect();
        Listing {
            order,
            temporaries,
            named,
        }
    }

    /// The nodes with no temporary: every expression written out in full.
    pub fn inline(symbols: &Symbols, roots: &[ExprId]) -> Listing {
        Listing {
            order: reachable(symbols, roots),
            temporaries: Vec::new(),
            named: HashMap::new(),
        }
    }

    pub fn temporary(&self, id: ExprId) -> Option<usize> {
        self.named.get(&id).copied()
    }

    /// Whether any of the nodes is the symbol with this role.
    pub fn uses(&self, symbols: &Symbols, wanted: impl Fn(Role) -> bool) -> bool {
        self.order
            .iter()
            .any(|&id| symbols.role(id).is_some_and(&wanted))
    }
}

/// The nodes `roots` reach through `Symbols::operands` (an unknown function's arguments count as
/// its operands), operands before users.
fn reachable(symbols: &Symbols, roots: &[ExprId]) -> Vec<ExprId> {
    crate::symbolic::expr::topological_order(roots, |id| symbols.operands(id))
}

/// A prefix for temporaries (`x`, else `xx`, …) that no variable name followed by digits uses.
pub fn temporary_prefix(names: &[String]) -> String {
    let mut prefix = "x".to_string();
    let clashes = |prefix: &str| {
        names.iter().any(|n| {
            n.strip_prefix(prefix)
                .is_some_and(|rest| !rest.is_empty() && rest.bytes().all(|b| b.is_ascii_digit()))
        })
    };
    while clashes(&prefix) {
        prefix.push('x');
    }
    prefix
}

/// The names every script defines itself: its matrices, the accelerations' solve and time.
const SCRIPT_DEFINED: [&str; 7] = ["M", "S", "F", "Delta", "Delta_bias", "accelerations", "t"];

/// A program name in the characters every script language accepts in an identifier: `.` and
/// any other punctuation written `_`, a rate's `'` written `_dot` (`hinge.x'` is `hinge_x_dot`).
/// Each language then mends a start it does not accept.
pub fn identifier_characters(name: &str) -> String {
    let mut out = String::new();
    for c in name.chars() {
        match c {
            '\'' => out.push_str("_dot"),
            c if c.is_ascii_alphanumeric() || c == '_' => out.push(c),
            _ => out.push('_'),
        }
    }
    out
}

/// The names a script (the Maple worksheet, the SymPy module) gives the variables: each
/// program name written as an identifier of the language, made unique against the language's
/// reserved names (and the names every script defines, `SCRIPT_DEFINED`) and the names before it
/// by trailing `_`s, and a prefix for the temporaries
/// that none of them uses.
pub struct ScriptNames {
    pub positions: Vec<String>,
    pub rates: Vec<String>,
    pub parameters: Vec<String>,
    /// One per distinct unknown function name: (the program's name, the script's).
    pub functions: Vec<(String, String)>,
    temporary_prefix: String,
    identifier: fn(&str) -> String,
}

impl ScriptNames {
    pub fn new(equations: &Equations, reserved: &[&str], identifier: fn(&str) -> String) -> Self {
        let v = &equations.variables;
        let mut taken: HashSet<String> = (reserved.iter().chain(&SCRIPT_DEFINED))
            .map(|s| s.to_string())
            .collect();
        let mut unique = |name: &str| {
            let mut candidate = identifier(name);
            while taken.contains(&candidate) {
                candidate.push('_');
            }
            taken.insert(candidate.clone());
            candidate
        };
        let mut names =
            |list: &[Variable]| list.iter().map(|x| unique(&x.name)).collect::<Vec<_>>();
        let (positions, rates, parameters) =
            (names(&v.positions), names(&v.rates), names(&v.parameters));
        let mut functions: Vec<(String, String)> = Vec::new();
        for f in &v.functions {
            if !functions.iter().any(|(name, _)| *name == f.name) {
                functions.push((f.name.clone(), unique(&f.name)));
            }
        }
        let every: Vec<String> = (positions.iter().chain(&rates).chain(&parameters))
            .chain(functions.iter().map(|(_, script)| script))
            .cloned()
            .collect();
        ScriptNames {
            temporary_prefix: temporary_prefix(&every),
            positions,
            rates,
            parameters,
            functions,
            identifier,
        }
    }

    /// The script's name of an unknown function, by the program's name.
    fn function<'a>(&'a self, name: &'a str) -> &'a str {
        (self.functions.iter())
            .find(|(n, _)| n == name)
            .map(|(_, script)| script.as_str())
            .unwrap_or(name)
    }

    /// `Language::symbol` for a script.
    pub fn symbol(&self, role: Role, name: &str) -> String {
        match role {
            Role::Position(i) => self.positions[i].clone(),
            Role::Rate(i) => self.rates[i].clone(),
            Role::Parameter(i) => self.parameters[i].clone(),
            Role::Time => "t".to_string(),
            Role::Function(_) => (self.identifier)(name),
        }
    }

    /// `Language::temporary` for a script.
    pub fn temporary(&self, k: usize) -> String {
        format!("{}{k}", self.temporary_prefix)
    }

    /// `Language::unknown_function` for a script: the function's name applied to its arguments.
    pub fn unknown_function(&self, name: &str, arguments: &[String]) -> String {
        format!("{}({})", self.function(name), arguments.join(", "))
    }
}

/// Binding strength of a printed expression, loosest first.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Precedence {
    Lowest,
    Sum,
    Product,
    /// Unary minus, and negative constants.
    Unary,
    Power,
    Atom,
}

/// How `a ^ b` is written.
pub enum PowerSyntax {
    /// A call such as `pow(a, b)`: an atom.
    Call,
    /// An infix operator (`**`, `^`), binding tighter than unary minus and right-associative;
    /// the exponent is parenthesised below `exponent`.
    Operator { exponent: Precedence },
}

/// How one target language writes leaves and operations; `Printer` places the parentheses.
pub trait Language {
    /// A finite constant's text; `constant_text` handles signs and infinities.
    fn number(&self, value: f64) -> String {
        format!("{value:?}")
    }
    /// Names for +∞ and NaN (never produced by the generator, but constants may overflow).
    fn infinity(&self) -> String;
    fn not_a_number(&self) -> String;
    /// A symbol that is not a function use.
    fn symbol(&self, role: Role, name: &str) -> String;
    fn temporary(&self, k: usize) -> String;
    /// An unknown function of the program applied to its printed arguments.
    fn unknown_function(&self, index: usize, name: &str, arguments: &[String]) -> String;
    /// A known function applied to its printed argument.
    fn function(&self, f: Function, argument: &str) -> String;
    /// The exponential law's profile at τ (`symbolic::exponential_profile`): the function of
    /// that name with its σ and λ, which the code emitters define beside the equations.
    fn exponential_profile(&self, tau: &str, profile: ExponentialProfile) -> String {
        format!(
            "exponential_profile({tau}, {:?}, {:?})",
            profile.sigma(),
            profile.lambda()
        )
    }
    fn atan2(&self, y: &str, x: &str) -> String;
    /// `when_nonnegative` where `test ≥ 0`, else `otherwise`, as an atom (a NaN test takes
    /// `otherwise`, as the tape does).
    fn select(&self, test: &str, when_nonnegative: &str, otherwise: &str) -> String;
    fn power_syntax(&self) -> PowerSyntax;
    /// `pow(a, b)`, for `PowerSyntax::Call`.
    fn power_call(&self, base: &str, exponent: &str) -> String {
        format!("pow({base}, {exponent})")
    }
    /// `a ** b`, for `PowerSyntax::Operator`: the base is an atom already.
    fn power_operator(&self, base: &str, exponent: &str) -> String {
        format!("{base}^{exponent}")
    }
    fn times(&self) -> &'static str {
        " * "
    }
    /// `a / b`; a language with fractions (`\frac`) returns them as atoms instead.
    fn fraction(&self, _numerator: &str, _denominator: &str) -> Option<String> {
        None
    }
    /// The least precedence a product's right operand may have without parentheses.
    fn product_operand(&self) -> Precedence {
        Precedence::Unary
    }
    fn parenthesize(&self, text: &str) -> String {
        format!("({text})")
    }
}

/// Prints the expressions of one listing: temporaries by name, other nodes inline.
pub struct Printer<'a, L: Language> {
    pub symbols: &'a Symbols<'a>,
    pub listing: &'a Listing,
    pub language: &'a L,
}

impl<L: Language> Printer<'_, L> {
    /// The expression `id`, a temporary by its name.
    pub fn expression(&self, id: ExprId) -> String {
        self.at_least(id, Precedence::Lowest)
    }

    /// The definition of a node: its operation, even when it is itself a temporary.
    pub fn definition(&self, id: ExprId) -> String {
        self.render(id).0
    }

    /// The sum of some expressions (zero terms left out), `zero` when none is left.
    pub fn sum(&self, terms: &[ExprId], zero: &str) -> String {
        let terms: Vec<ExprId> = terms
            .iter()
            .copied()
            .filter(|&t| !self.symbols.pool.is_zero(t))
            .collect();
        match terms.as_slice() {
            [] => zero.to_string(),
            [first, rest @ ..] => {
                let mut text = self.at_least(*first, Precedence::Sum);
                for &term in rest {
                    text = format!("{text} + {}", self.at_least(term, Precedence::Product));
                }
                text
            }
        }
    }

    fn at_least(&self, id: ExprId, least: Precedence) -> String {
        let (text, precedence) = self.operand(id);
        if precedence < least {
            self.language.parenthesize(&text)
        } else {
            text
        }
    }

    fn operand(&self, id: ExprId) -> (String, Precedence) {
        match self.listing.temporary(id) {
            Some(k) => (self.language.temporary(k), Precedence::Atom),
            None => self.render(id),
        }
    }

    /// The node's operation with its operands printed, and the precedence of the result.
    fn render(&self, id: ExprId) -> (String, Precedence) {
        let pool = self.symbols.pool;
        let language = self.language;
        use Precedence::*;
        match pool.node(id) {
            Node::Constant(bits) => self.constant(f64::from_bits(bits)),
            Node::Symbol(_) => match self.symbols.role(id) {
                Some(Role::Function(k)) => {
                    let use_ = &self.symbols.variables.functions[k];
                    let arguments: Vec<String> =
                        use_.arguments.iter().map(|&a| self.expression(a)).collect();
                    (language.unknown_function(k, &use_.name, &arguments), Atom)
                }
                Some(role) => (language.symbol(role, &self.symbols.name(id)), Atom),
                None => (self.symbols.name(id), Atom),
            },
            Node::Add(a, b) => self.render_sum(a, b),
            Node::Mul(a, b) => (
                format!(
                    "{}{}{}",
                    self.at_least(a, Product),
                    language.times(),
                    self.at_least(b, language.product_operand())
                ),
                Product,
            ),
            Node::Div(a, b) => match language.fraction(&self.expression(a), &self.expression(b)) {
                Some(fraction) => (fraction, Atom),
                None => (
                    format!(
                        "{} / {}",
                        self.at_least(a, Product),
                        self.at_least(b, Unary)
                    ),
                    Product,
                ),
            },
            Node::Neg(a) => (format!("-{}", self.at_least(a, Power)), Unary),
            Node::Pow(a, b) => match language.power_syntax() {
                PowerSyntax::Call => (
                    language.power_call(&self.expression(a), &self.expression(b)),
                    Atom,
                ),
                PowerSyntax::Operator { exponent } => (
                    language.power_operator(&self.at_least(a, Atom), &self.at_least(b, exponent)),
                    Power,
                ),
            },
            Node::Atan2(y, x) => (
                language.atan2(&self.expression(y), &self.expression(x)),
                Atom,
            ),
            Node::Apply(Function::ExponentialProfile(profile), a) => (
                language.exponential_profile(&self.expression(a), profile),
                Atom,
            ),
            Node::Apply(f, a) => (language.function(f, &self.expression(a)), Atom),
            Node::Select {
                test,
                when_nonnegative,
                otherwise,
            } => (
                language.select(
                    &self.expression(test),
                    &self.expression(when_nonnegative),
                    &self.expression(otherwise),
                ),
                Atom,
            ),
        }
    }

    /// `a + b`, written `a - c` when b is −c (or a negative constant), and `b - c` when a is.
    /// Both are the same floating-point operation as the sum.
    fn render_sum(&self, a: ExprId, b: ExprId) -> (String, Precedence) {
        let (first, second) = if self.negated(a).is_some() && self.negated(b).is_none() {
            (b, a)
        } else {
            (a, b)
        };
        let left = self.at_least(first, Precedence::Sum);
        let text = match self.negated(second) {
            Some(Negated::Node(c)) => format!("{left} - {}", self.at_least(c, Precedence::Product)),
            Some(Negated::Constant(value)) => format!("{left} - {}", self.constant(value).0),
            None => format!("{left} + {}", self.at_least(second, Precedence::Product)),
        };
        (text, Precedence::Sum)
    }

    /// −c or a negative constant printed inline: what a sum can write as a subtraction.
    fn negated(&self, id: ExprId) -> Option<Negated> {
        if self.listing.temporary(id).is_some() {
            return None;
        }
        match self.symbols.pool.node(id) {
            Node::Neg(c) => Some(Negated::Node(c)),
            Node::Constant(bits) if f64::from_bits(bits) < 0.0 => {
                Some(Negated::Constant(-f64::from_bits(bits)))
            }
            _ => None,
        }
    }

    fn constant(&self, value: f64) -> (String, Precedence) {
        let language = self.language;
        let (magnitude, negative) = (value.abs(), value < 0.0);
        let text = if value.is_nan() {
            language.not_a_number()
        } else if magnitude.is_infinite() {
            language.infinity()
        } else {
            language.number(magnitude)
        };
        if negative {
            (format!("-{text}"), Precedence::Unary)
        } else {
            (text, Precedence::Atom)
        }
    }
}

enum Negated {
    Node(ExprId),
    Constant(f64),
}

/// The upper triangle of M (i ≤ j), row by row, as (i, j, entry).
pub fn upper_triangle(equations: &Equations) -> Vec<(usize, usize, ExprId)> {
    let n = equations.dimension();
    (0..n)
        .flat_map(|i| (i..n).map(move |j| (i, j)))
        .map(|(i, j)| (i, j, equations.mass[i * n + j]))
        .collect()
}

/// An entry of the equations, by 0-based indices.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Entry {
    /// M[i, j], listed for i ≤ j only.
    Mass(usize, usize),
    SecondMember(usize),
    Force(usize),
    /// Δ[row, column].
    Constraint(usize, usize),
    /// Δ̇q[row].
    Bias(usize),
    /// q'[i], for a tree: the forward dynamics.
    Acceleration(usize),
}

/// The entries of the equations that are not the constant 0, M's upper triangle only, in the
/// order M, S, F, Δ, Δ̇q, then for a tree the accelerations q'.
pub fn nonzero_entries(equations: &Equations) -> Vec<(Entry, ExprId)> {
    let n = equations.dimension();
    let mut entries: Vec<(Entry, ExprId)> = upper_triangle(equations)
        .into_iter()
        .map(|(i, j, id)| (Entry::Mass(i, j), id))
        .collect();
    entries.extend(
        equations
            .second_member
            .iter()
            .enumerate()
            .map(|(i, &id)| (Entry::SecondMember(i), id)),
    );
    entries.extend(
        equations
            .forces
            .iter()
            .enumerate()
            .map(|(i, &id)| (Entry::Force(i), id)),
    );
    entries.extend(
        equations
            .constraints
            .iter()
            .enumerate()
            .map(|(k, &id)| (Entry::Constraint(k / n, k % n), id)),
    );
    entries.extend(
        equations
            .constraint_bias
            .iter()
            .enumerate()
            .map(|(r, &id)| (Entry::Bias(r), id)),
    );
    entries.extend(
        equations
            .accelerations
            .iter()
            .flatten()
            .enumerate()
            .map(|(i, &id)| (Entry::Acceleration(i), id)),
    );
    entries.retain(|(_, id)| !equations.pool.is_zero(*id));
    entries
}

/// A one-line description of the variables' meaning, with the given value if any.
pub fn described(meaning: &str, given: Option<f64>) -> String {
    match given {
        Some(value) => format!("{meaning} (given {value:?})"),
        None => meaning.to_string(),
    }
}
