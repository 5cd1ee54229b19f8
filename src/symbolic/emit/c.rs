//! The equations as a self-contained C99 source file (`math.h` only), the same functions as the
//! Rust emitter's; `forward_dynamics` returns 0, or an error code `forward_dynamics_message`
//! explains.

use std::fmt::Write;

use super::code::{array_symbol, comment, Routine, Routines, Statements};
use super::shared::{described, Language, PowerSyntax, Role, Symbols};
use super::zero_products;
use crate::symbolic::expr::Function;
use crate::symbolic::lower::Variable;
use crate::symbolic::Equations;

struct C;

impl Language for C {
    fn infinity(&self) -> String {
        "INFINITY".to_string()
    }
    fn not_a_number(&self) -> String {
        "NAN".to_string()
    }
    fn symbol(&self, role: Role, name: &str) -> String {
        array_symbol(role, name)
    }
    fn temporary(&self, k: usize) -> String {
        format!("x{k}")
    }
    fn unknown_function(&self, index: usize, _name: &str, arguments: &[String]) -> String {
        format!("f({index}, (const double[]){{{}}})", arguments.join(", "))
    }
    fn function(&self, f: Function, argument: &str) -> String {
        let name = if f == Function::Abs { "fabs" } else { f.name() };
        format!("{name}({argument})")
    }
    fn atan2(&self, y: &str, x: &str) -> String {
        format!("atan2({y}, {x})")
    }
    fn select(&self, test: &str, when_nonnegative: &str, otherwise: &str) -> String {
        format!("({test} >= 0.0 ? {when_nonnegative} : {otherwise})")
    }
    fn power_syntax(&self) -> PowerSyntax {
        PowerSyntax::Call
    }
}

impl Statements for C {
    fn declare(&self, name: &str, value: &str) -> String {
        format!("const double {name} = {value};")
    }
    fn zero(&self, array: &str, length: usize) -> String {
        format!("for (int i = 0; i < {length}; i++) {array}[i] = 0.0;")
    }
}

const FUNCTION_ARGUMENT: &str = "double (*f)(int, const double *)";

/// The equations of `source` as C99.
pub fn c(equations: &Equations, source: &str) -> String {
    let (equations, guards) = &zero_products::folded(equations);
    let symbols = Symbols::new(equations);
    let routines = Routines::new(&symbols, equations, guards);
    let mut out = header(equations, source);
    if equations.pool.uses_exponential_profile() {
        out.push_str(&crate::symbolic::exponential_profile::c_definition());
    }
    let with_f = |routine: &Routine| {
        if routine.uses_functions {
            format!(", {FUNCTION_ARGUMENT}")
        } else {
            String::new()
        }
    };
    let time = |routine: &Routine| if routine.uses_time { "double t, " } else { "" };
    let mass = &routines.mass;
    let _ = writeln!(
        out,
        "\n/* M(p), row-major N x N (only the upper triangle is computed; the rest is its mirror). */\n\
         void mass_matrix({}const double *p, const double *k, double *m{}) {{\n{}}}",
        time(mass),
        with_f(mass),
        with_unused(&inputs(mass, &["p", "k"]), mass.body(&symbols, &C, &C, "m"))
    );
    let rhs = &routines.right_hand_side;
    let _ = writeln!(
        out,
        "\n/* S(p, q) + F(p, q, t): the velocity-product terms and the generalised forces. */\n\
         void right_hand_side(double t, const double *p, const double *q, const double *k, double *rhs{}) {{\n{}}}",
        with_f(rhs),
        with_unused(&["t", "p", "q", "k"], rhs.body(&symbols, &C, &C, "rhs"))
    );
    if let Some((delta, bias)) = &routines.loops {
        let _ = writeln!(
            out,
            "\n/* Delta(p), row-major CONSTRAINTS x N: Delta q = 0 on the mechanism's motions. */\n\
             void constraints({}const double *p, const double *k, double *delta{}) {{\n{}}}",
            time(delta),
            with_f(delta),
            with_unused(&inputs(delta, &["p", "k"]), delta.body(&symbols, &C, &C, "delta"))
        );
        let _ = writeln!(
            out,
            "\n/* d(Delta)/dt q: Delta q' + d(Delta)/dt q = 0, with q' the rates' derivatives. */\n\
             void constraint_bias({}const double *p, const double *q, const double *k, double *out{}) {{\n{}}}",
            time(bias),
            with_f(bias),
            with_unused(&inputs(bias, &["p", "q", "k"]), bias.body(&symbols, &C, &C, "out"))
        );
    }
    out.push_str(&forward_dynamics(&symbols, &routines));
    out
}

/// The inputs of a routine's signature: the time when it reads it, then `others`.
fn inputs<'a>(routine: &Routine, others: &[&'a str]) -> Vec<&'a str> {
    let time = routine.uses_time.then_some("t");
    time.into_iter().chain(others.iter().copied()).collect()
}

/// `body` after a `(void)x;` for each input `x` it does not read. The signatures are the same
/// for every mechanism (a pendulum's right-hand side does not read the time, nor a mass matrix
/// the parameters when there are none), and the file compiles without a warning under
/// `-Wall -Wextra`.
fn with_unused(inputs: &[&str], body: String) -> String {
    let read: std::collections::HashSet<&str> = body
        .split(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
        .collect();
    let unused: Vec<String> = (inputs.iter())
        .filter(|input| !read.contains(*input))
        .map(|input| format!("(void){input};"))
        .collect();
    if unused.is_empty() {
        return body;
    }
    format!("    {}\n{body}", unused.join(" "))
}

fn header(equations: &Equations, source: &str) -> String {
    let v = &equations.variables;
    let mut out = format!(
        "/* Equations of motion of `{}`, written by lsdc:\n\
         \n\
         \x20      M(p) q' = S(p, q) + F(p, q, t) + Delta^T Lambda,   Delta(p) q' + d(Delta)/dt q = 0\n\
         \n\
         \x20  p holds the positions, q their rates, k the parameters (in the orders of POSITIONS, RATES\n\
         \x20  and PARAMETERS), t is the time; q' are the rates' derivatives. C99. */\n\
         #include <math.h>\n\n\
         /* Number of coordinates, and of constraint rows (six per complementary link). */\n\
         enum {{ N = {}, CONSTRAINTS = {}, PARAMETER_COUNT = {}, FUNCTION_COUNT = {} }};\n",
        comment(source),
        equations.dimension(),
        equations.constraint_rows(),
        v.parameters.len(),
        v.functions.len()
    );
    names(
        &mut out,
        "The positions, in the order of p:",
        "POSITIONS",
        &v.positions,
    );
    names(
        &mut out,
        "Their rates, in the order of q:",
        "RATES",
        &v.rates,
    );
    names(
        &mut out,
        "The parameters, in the order of k:",
        "PARAMETERS",
        &v.parameters,
    );
    if !v.functions.is_empty() {
        let list: Vec<String> = v
            .functions
            .iter()
            .map(|f| c_string(equations.pool.name_of(f.symbol).unwrap_or_default()))
            .collect();
        let _ = writeln!(
            out,
            "\n/* The unknown functions as applied: a function taking f calls f(i, arguments) for the value\n   \
             of FUNCTIONS[i]. */\nconst char *const FUNCTIONS[FUNCTION_COUNT] = {{{}}};",
            list.join(", ")
        );
    }
    if equations.constraint_rows() > 0 {
        let rows: Vec<String> = equations
            .constraint_names
            .iter()
            .map(|n| c_string(n))
            .collect();
        let _ = writeln!(
            out,
            "\n/* The constraint rows, which are also the multipliers' names. */\nconst char *const CONSTRAINT_NAMES[CONSTRAINTS] = {{{}}};",
            rows.join(", ")
        );
    }
    out
}

/// A `static const` array of names, with the meanings in its comment; none when empty (C has
/// no empty arrays).
fn names(out: &mut String, title: &str, constant: &str, list: &[Variable]) {
    if list.is_empty() {
        return;
    }
    let _ = writeln!(out, "\n/* {title}");
    for v in list {
        let _ = writeln!(
            out,
            "   - {}: {}",
            comment(&v.name),
            comment(&described(&v.meaning, v.given))
        );
    }
    let quoted: Vec<String> = list.iter().map(|v| c_string(&v.name)).collect();
    let _ = writeln!(
        out,
        "*/\nconst char *const {constant}[{}] = {{{}}};",
        list.len(),
        quoted.join(", ")
    );
}

fn c_string(text: &str) -> String {
    format!("\"{}\"", text.replace('\\', "\\\\").replace('"', "\\\""))
}

/// `forward_dynamics`: the articulated-body recursion for a tree, the KKT system for loops.
fn forward_dynamics(symbols: &Symbols, routines: &Routines) -> String {
    let argument = if routines.uses_functions() {
        format!(", {FUNCTION_ARGUMENT}")
    } else {
        String::new()
    };
    let call = |routine: &Routine, arguments: &str| {
        let time = if routine.uses_time { "t, " } else { "" };
        let f = if routine.uses_functions { ", f" } else { "" };
        format!("{time}{arguments}{f}")
    };
    let mass = call(&routines.mass, "p, k, m");
    let rhs_f = if routines.right_hand_side.uses_functions {
        ", f"
    } else {
        ""
    };
    let mut out = MESSAGES.to_string();
    match &routines.loops {
        None => {
            let body = routines
                .accelerations
                .as_ref()
                .map(|a| a.body(symbols, &C, &C, "qdd"))
                .unwrap_or_default();
            let body = with_unused(&["t", "p", "q", "k"], body);
            // The values folded out of products by 0 that may not be finite (`zero_products`).
            let guards: String = (routines.accelerations.iter())
                .flat_map(|a| a.guard_expressions(symbols, &C))
                .map(|guard| format!(" && isfinite({guard})"))
                .collect();
            let _ = write!(
                out,
                "\n/* The rates' derivatives q' = M^-1 (S + F), by the articulated-body recursion (no solve). */\n\
                 int forward_dynamics(double t, const double *p, const double *q, const double *k, double *qdd{argument}) {{\n\
                 {body}    \
                     return all_finite(qdd, N){guards} ? 0 : 1;\n\
                 }}\n"
            );
        }
        Some((delta, bias)) => {
            out.push_str(KKT);
            let delta = call(delta, "p, k, delta");
            let bias = call(bias, "p, q, k, b + N");
            let _ = write!(
                out,
                "\n/* The rates' derivatives q' from the KKT system [[M, Delta^T], [Delta, 0]] [q'; -Lambda] =\n   \
                 [S + F; -d(Delta)/dt q], solved by Gaussian elimination with complete pivoting. Redundant\n   \
                 constraint rows are allowed: the multipliers are then not unique, but the accelerations are. */\n\
                 int forward_dynamics(double t, const double *p, const double *q, const double *k, double *qdd{argument}) {{\n    \
                     double m[N * N], delta[CONSTRAINTS * N], a[SIZE * SIZE], b[SIZE];\n    \
                     mass_matrix({mass});\n    \
                     constraints({delta});\n    \
                     right_hand_side(t, p, q, k, b{rhs_f});\n    \
                     constraint_bias({bias});\n    \
                     for (int i = 0; i < SIZE * SIZE; i++) a[i] = 0.0;\n    \
                     for (int i = 0; i < N; i++)\n        \
                         for (int j = 0; j < N; j++) a[i * SIZE + j] = m[i * N + j];\n    \
                     for (int r = 0; r < CONSTRAINTS; r++) {{\n        \
                         b[N + r] = -b[N + r];\n        \
                         for (int c = 0; c < N; c++) {{\n            \
                             a[(N + r) * SIZE + c] = delta[r * N + c];\n            \
                             a[c * SIZE + N + r] = delta[r * N + c];\n        \
                         }}\n    \
                     }}\n    \
                     int status = solve_kkt(a, b);\n    \
                     if (status != 0) return status;\n    \
                     for (int i = 0; i < N; i++) qdd[i] = b[i];\n    \
                     return 0;\n\
                 }}\n"
            );
        }
    }
    out
}

const MESSAGES: &str = r#"
/* What a nonzero status of forward_dynamics means. */
const char *forward_dynamics_message(int status) {
    switch (status) {
    case 0: return "ok";
    case 1: return "the equations or the accelerations are not finite at this state (a joint that moves no mass?)";
    case 3: return "the accelerations are not determined: the mass matrix is singular along motions the constraints allow";
    default: return "unknown status";
    }
}

static int all_finite(const double *x, int count) {
    for (int i = 0; i < count; i++)
        if (!isfinite(x[i])) return 0;
    return 1;
}
"#;

const KKT: &str = r#"
/* Unknowns of the KKT system: the accelerations, then the multipliers. */
enum { SIZE = N + CONSTRAINTS };

/* Solves a x = b (row-major; both overwritten, x in b) by Gaussian elimination with complete
   pivoting. Pivots below 1e-12 times the largest entry count as zero; their unknowns are set to
   zero. That is harmless for multipliers of redundant constraints, but an acceleration without
   a pivot is not determined by the equations: status 3. */
static int solve_kkt(double *a, double *b) {
    if (!all_finite(a, SIZE * SIZE) || !all_finite(b, SIZE)) return 1;
    int unknown[SIZE]; /* unknown[j]: the unknown whose column is now column j */
    for (int j = 0; j < SIZE; j++) unknown[j] = j;
    int rank = SIZE;
    double largest = 0.0;
    for (int step = 0; step < SIZE; step++) {
        int row = step, column = step;
        double pivot = 0.0;
        for (int r = step; r < SIZE; r++)
            for (int c = step; c < SIZE; c++)
                if (fabs(a[r * SIZE + c]) > pivot) {
                    row = r;
                    column = c;
                    pivot = fabs(a[r * SIZE + c]);
                }
        if (step == 0) largest = pivot;
        if (pivot == 0.0 || pivot < 1e-12 * largest) {
            rank = step;
            break;
        }
        for (int c = 0; c < SIZE; c++) {
            double swap = a[step * SIZE + c];
            a[step * SIZE + c] = a[row * SIZE + c];
            a[row * SIZE + c] = swap;
        }
        double swap = b[step];
        b[step] = b[row];
        b[row] = swap;
        for (int r = 0; r < SIZE; r++) {
            double s = a[r * SIZE + step];
            a[r * SIZE + step] = a[r * SIZE + column];
            a[r * SIZE + column] = s;
        }
        int u = unknown[step];
        unknown[step] = unknown[column];
        unknown[column] = u;
        for (int r = step + 1; r < SIZE; r++) {
            double factor = a[r * SIZE + step] / a[step * SIZE + step];
            if (factor != 0.0) {
                for (int c = step; c < SIZE; c++) a[r * SIZE + c] -= factor * a[step * SIZE + c];
                b[r] -= factor * b[step];
            }
        }
    }
    for (int j = rank; j < SIZE; j++)
        if (unknown[j] < N) return 3;
    double x[SIZE];
    for (int j = rank - 1; j >= 0; j--) {
        double s = b[j];
        for (int c = j + 1; c < rank; c++) s -= a[j * SIZE + c] * x[c];
        x[j] = s / a[j * SIZE + j];
    }
    for (int j = 0; j < SIZE; j++) b[unknown[j]] = j < rank ? x[j] : 0.0;
    return 0;
}
"#;
