//! The equations as a self-contained Rust source file: the mass matrix, the right-hand side
//! S + F, the constraints, and the forward dynamics, with no allocation and no dependency.

use std::fmt::Write;

use super::code::{array_symbol, comment, Routine, Routines, Statements};
use super::shared::{described, Language, PowerSyntax, Role, Symbols};
use super::zero_products;
use crate::symbolic::expr::Function;
use crate::symbolic::lower::Variable;
use crate::symbolic::Equations;

struct Rust;

impl Language for Rust {
    fn infinity(&self) -> String {
        "f64::INFINITY".to_string()
    }
    fn not_a_number(&self) -> String {
        "f64::NAN".to_string()
    }
    fn symbol(&self, role: Role, name: &str) -> String {
        array_symbol(role, name)
    }
    fn temporary(&self, k: usize) -> String {
        format!("x{k}")
    }
    fn unknown_function(&self, index: usize, _name: &str, arguments: &[String]) -> String {
        format!("f({index}, &[{}])", arguments.join(", "))
    }
    fn function(&self, f: Function, argument: &str) -> String {
        let name = if f == Function::Log { "ln" } else { f.name() };
        format!("f64::{name}({argument})")
    }
    fn atan2(&self, y: &str, x: &str) -> String {
        format!("f64::atan2({y}, {x})")
    }
    fn select(&self, test: &str, when_nonnegative: &str, otherwise: &str) -> String {
        format!("(if {test} >= 0.0 {{ {when_nonnegative} }} else {{ {otherwise} }})")
    }
    fn power_syntax(&self) -> PowerSyntax {
        PowerSyntax::Call
    }
    fn power_call(&self, base: &str, exponent: &str) -> String {
        format!("f64::powf({base}, {exponent})")
    }
}

impl Statements for Rust {
    fn declare(&self, name: &str, value: &str) -> String {
        format!("let {name} = {value};")
    }
    fn zero(&self, array: &str, length: usize) -> String {
        format!("{array}[..{length}].fill(0.0);")
    }
}

const FUNCTION_ARGUMENT: &str = "f: &dyn Fn(usize, &[f64]) -> f64";

/// The equations of `source` as Rust.
pub fn rust(equations: &Equations, source: &str) -> String {
    let (equations, guards) = &zero_products::folded(equations);
    let symbols = Symbols::new(equations);
    let routines = Routines::new(&symbols, equations, guards);
    let mut out = header(equations, source);
    if equations.pool.uses_exponential_profile() {
        out.push_str(&crate::symbolic::exponential_profile::rust_definition());
    }
    let with_f = |routine: &Routine| {
        if routine.uses_functions {
            format!(", {FUNCTION_ARGUMENT}")
        } else {
            String::new()
        }
    };
    let time = |routine: &Routine| if routine.uses_time { "t: f64, " } else { "" };
    let mass = &routines.mass;
    let _ = writeln!(
        out,
        "\n/// M(p), row-major N × N (only the upper triangle is computed; the rest is its mirror).\n\
         pub fn mass_matrix({}p: &[f64], k: &[f64], m: &mut [f64]{}) {{\n{}}}",
        time(mass),
        with_f(mass),
        mass.body(&symbols, &Rust, &Rust, "m")
    );
    let rhs = &routines.right_hand_side;
    let _ = writeln!(
        out,
        "\n/// S(p, q) + F(p, q, t): the velocity-product terms and the generalised forces.\n\
         pub fn right_hand_side(t: f64, p: &[f64], q: &[f64], k: &[f64], rhs: &mut [f64]{}) {{\n{}}}",
        with_f(rhs),
        rhs.body(&symbols, &Rust, &Rust, "rhs")
    );
    if let Some((delta, bias)) = &routines.loops {
        let _ = writeln!(
            out,
            "\n/// Δ(p), row-major CONSTRAINTS × N: Δ q = 0 on the mechanism's motions.\n\
             pub fn constraints({}p: &[f64], k: &[f64], delta: &mut [f64]{}) {{\n{}}}",
            time(delta),
            with_f(delta),
            delta.body(&symbols, &Rust, &Rust, "delta")
        );
        let _ = writeln!(
            out,
            "\n/// Δ̇(p, q) q: Δ q' + Δ̇q = 0, with q' the rates' derivatives.\n\
             pub fn constraint_bias({}p: &[f64], q: &[f64], k: &[f64], out: &mut [f64]{}) {{\n{}}}",
            time(bias),
            with_f(bias),
            bias.body(&symbols, &Rust, &Rust, "out")
        );
    }
    out.push_str(&forward_dynamics(&symbols, &routines));
    out
}

fn header(equations: &Equations, source: &str) -> String {
    let v = &equations.variables;
    let mut out = format!(
        "//! Equations of motion of `{}`, written by lsdc:\n\
         //!\n\
         //!     M(p) q' = S(p, q) + F(p, q, t) + Δᵀ Λ,   Δ(p) q' + Δ̇q = 0\n\
         //!\n\
         //! `p` holds the positions, `q` their rates, `k` the parameters (in the orders of `POSITIONS`,\n\
         //! `RATES` and `PARAMETERS`), `t` is the time; q' are the rates' derivatives.\n\
         #![allow(unused, clippy::all, clippy::pedantic)]\n\n\
         /// Number of coordinates.\npub const N: usize = {};\n",
        comment(source),
        equations.dimension()
    );
    names(
        &mut out,
        "The positions, in the order of `p`:",
        "POSITIONS",
        "N",
        &v.positions,
    );
    names(
        &mut out,
        "Their rates, in the order of `q`:",
        "RATES",
        "N",
        &v.rates,
    );
    names(
        &mut out,
        "The parameters, in the order of `k`:",
        "PARAMETERS",
        &v.parameters.len().to_string(),
        &v.parameters,
    );
    if !v.functions.is_empty() {
        let list: Vec<String> = v
            .functions
            .iter()
            .map(|f| format!("{:?}", equations.pool.name_of(f.symbol).unwrap_or_default()))
            .collect();
        let _ = writeln!(
            out,
            "\n/// The unknown functions as applied: a function taking `f` calls `f(i, &arguments)` for the\n\
             /// value of `FUNCTIONS[i]`.\npub const FUNCTIONS: [&str; {}] = [{}];",
            list.len(),
            list.join(", ")
        );
    }
    if equations.constraint_rows() > 0 {
        let rows: Vec<String> = equations
            .constraint_names
            .iter()
            .map(|n| format!("{n:?}"))
            .collect();
        let _ = writeln!(
            out,
            "\n/// Number of constraint rows (six per complementary link).\npub const CONSTRAINTS: usize = {};\n\
             /// The constraint rows, which are also the multipliers' names.\npub const CONSTRAINT_NAMES: [&str; CONSTRAINTS] = [{}];",
            rows.len(),
            rows.join(", ")
        );
    }
    out
}

fn names(out: &mut String, title: &str, constant: &str, length: &str, list: &[Variable]) {
    let _ = writeln!(out, "\n/// {title}");
    for v in list {
        let _ = writeln!(
            out,
            "/// - `{}`: {}",
            v.name,
            comment(&described(&v.meaning, v.given))
        );
    }
    let quoted: Vec<String> = list.iter().map(|v| format!("{:?}", v.name)).collect();
    let _ = writeln!(
        out,
        "pub const {constant}: [&str; {length}] = [{}];",
        quoted.join(", ")
    );
}

/// `forward_dynamics`: the articulated-body recursion for a tree, the KKT system for loops.
fn forward_dynamics(symbols: &Symbols, routines: &Routines) -> String {
    let f = routines.uses_functions();
    let argument = if f {
        format!(", {FUNCTION_ARGUMENT}")
    } else {
        String::new()
    };
    let call = |routine: &Routine, arguments: &str| {
        let time = if routine.uses_time { "t, " } else { "" };
        let f = if routine.uses_functions { ", f" } else { "" };
        format!("{time}{arguments}{f}")
    };
    let mass = call(&routines.mass, "p, k, &mut m");
    // `right_hand_side` always takes the time.
    let rhs = format!(
        "t, p, q, k, &mut rhs{}",
        if routines.right_hand_side.uses_functions {
            ", f"
        } else {
            ""
        }
    );
    // The values folded out of products by 0 that may not be finite (`zero_products`).
    let guards: String = (routines.accelerations.iter())
        .flat_map(|a| a.guard_expressions(symbols, &Rust))
        .map(|guard| format!(" || !({guard}).is_finite()"))
        .collect();
    match &routines.loops {
        None => format!(
            "\n/// The rates' derivatives q' = M⁻¹ (S + F), by the articulated-body recursion (no solve).\n\
             pub fn forward_dynamics(t: f64, p: &[f64], q: &[f64], k: &[f64], qdd: &mut [f64]{argument}) -> Result<(), &'static str> {{\n\
             {}    \
                 if qdd[..N].iter().any(|x| !x.is_finite()){guards} {{\n        \
                     return Err(\"the accelerations are not finite at this state: a joint moves no mass, or a value is not finite\");\n    \
                 }}\n    \
                 Ok(())\n\
             }}\n",
            routines.accelerations.as_ref().map(|a| a.body(symbols, &Rust, &Rust, "qdd")).unwrap_or_default()
        ),
        Some((delta, bias)) => {
            let delta = call(delta, "p, k, &mut delta");
            let rhs = rhs.replace("&mut rhs", "&mut b[..N]");
            let bias = call(bias, "p, q, k, &mut b[N..]");
            format!(
                "\n/// The rates' derivatives q' from the KKT system [[M, Δᵀ], [Δ, 0]] [q'; −Λ] = [S + F; −Δ̇q], solved by\n\
                 /// Gaussian elimination with complete pivoting. Redundant constraint rows are allowed: the\n\
                 /// multipliers are then not unique, but the accelerations are.\n\
                 pub fn forward_dynamics(t: f64, p: &[f64], q: &[f64], k: &[f64], qdd: &mut [f64]{argument}) -> Result<(), &'static str> {{\n    \
                     let mut m = [0.0; N * N];\n    \
                     mass_matrix({mass});\n    \
                     let mut delta = [0.0; CONSTRAINTS * N];\n    \
                     constraints({delta});\n    \
                     let mut b = [0.0; SIZE];\n    \
                     right_hand_side({rhs});\n    \
                     constraint_bias({bias});\n    \
                     let mut a = [0.0; SIZE * SIZE];\n    \
                     for i in 0..N {{\n        \
                         a[i * SIZE..i * SIZE + N].copy_from_slice(&m[i * N..i * N + N]);\n    \
                     }}\n    \
                     for r in 0..CONSTRAINTS {{\n        \
                         b[N + r] = -b[N + r];\n        \
                         for c in 0..N {{\n            \
                             a[(N + r) * SIZE + c] = delta[r * N + c];\n            \
                             a[c * SIZE + N + r] = delta[r * N + c];\n        \
                         }}\n    \
                     }}\n    \
                     solve_kkt(&mut a, &mut b)?;\n    \
                     qdd[..N].copy_from_slice(&b[..N]);\n    \
                     Ok(())\n\
                 }}\n{KKT}"
            )
        }
    }
}

const KKT: &str = r#"
/// Unknowns of the KKT system: the accelerations, then the multipliers.
const SIZE: usize = N + CONSTRAINTS;

/// Solves a x = b (row-major; both overwritten, x in b) by Gaussian elimination with complete
/// pivoting. Pivots below 1e-12 times the largest entry count as zero; their unknowns are set to
/// zero. That is harmless for multipliers of redundant constraints, but an acceleration without
/// a pivot is not determined by the equations: an error.
fn solve_kkt(a: &mut [f64; SIZE * SIZE], b: &mut [f64; SIZE]) -> Result<(), &'static str> {
    if a.iter().chain(b.iter()).any(|x| !x.is_finite()) {
        return Err("the equations are not finite at this state");
    }
    // unknown[j]: the unknown whose column is now column j.
    let mut unknown = [0usize; SIZE];
    for (j, u) in unknown.iter_mut().enumerate() {
        *u = j;
    }
    let mut rank = SIZE;
    let mut largest = 0.0;
    for step in 0..SIZE {
        let (mut row, mut column, mut pivot) = (step, step, 0.0);
        for r in step..SIZE {
            for c in step..SIZE {
                if a[r * SIZE + c].abs() > pivot {
                    (row, column, pivot) = (r, c, a[r * SIZE + c].abs());
                }
            }
        }
        if step == 0 {
            largest = pivot;
        }
        if pivot == 0.0 || pivot < 1e-12 * largest {
            rank = step;
            break;
        }
        for c in 0..SIZE {
            a.swap(step * SIZE + c, row * SIZE + c);
        }
        b.swap(step, row);
        for r in 0..SIZE {
            a.swap(r * SIZE + step, r * SIZE + column);
        }
        unknown.swap(step, column);
        for r in step + 1..SIZE {
            let factor = a[r * SIZE + step] / a[step * SIZE + step];
            if factor != 0.0 {
                for c in step..SIZE {
                    a[r * SIZE + c] -= factor * a[step * SIZE + c];
                }
                b[r] -= factor * b[step];
            }
        }
    }
    if unknown[rank..].iter().any(|&u| u < N) {
        return Err("the accelerations are not determined: the mass matrix is singular along motions the constraints allow");
    }
    let mut x = [0.0; SIZE];
    for j in (0..rank).rev() {
        let mut s = b[j];
        for c in j + 1..rank {
            s -= a[j * SIZE + c] * x[c];
        }
        x[j] = s / a[j * SIZE + j];
    }
    for j in 0..SIZE {
        b[unknown[j]] = if j < rank { x[j] } else { 0.0 };
    }
    Ok(())
}
"#;
