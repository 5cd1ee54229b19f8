//! The emitted equations against `Equations::evaluate`: the Rust and C code compiled and run at
//! a few states, the JSON DAG evaluated again, and the text formats' shape.

use crate::common::c_compiler;
use crate::common::symbolic::{equations_of, written_equations, Sequence};
use std::collections::HashMap;
use std::path::PathBuf;
use std::process::Command;

use lsdc::symbolic::equations::Values;
use lsdc::symbolic::expr::Tape;
use lsdc::symbolic::{emit, Equations};
use nalgebra::{DMatrix, DVector};

/// Tree examples, one with loops (`four_bar`), and one with unknown functions and parameters
/// (`satellite`).
const EXAMPLES: [&str; 6] = [
    "pendulum",
    "double_pendulum",
    "satellite_fixed",
    "four_bar",
    "satellite_numeric",
    "satellite",
];

/// Entries agree when |a − b| ≤ TOLERANCE · max(|b|, largest |entry| of the quantity).
const TOLERANCE: f64 = 1e-12;

fn equations(name: &str) -> Equations {
    equations_of(&format!("examples/{name}.lsd"))
}

/// The unknown functions' law in every harness: f_i(a) = (i + 1)/4 + Σⱼ sin((j + 1) aⱼ).
fn unknown(index: usize, arguments: &[f64]) -> f64 {
    0.25 * (index + 1) as f64
        + arguments
            .iter()
            .enumerate()
            .map(|(j, a)| ((j + 1) as f64 * a).sin())
            .sum::<f64>()
}

const RUST_UNKNOWN: &str = "fn unknown(index: usize, arguments: &[f64]) -> f64 {
    0.25 * (index + 1) as f64 + arguments.iter().enumerate().map(|(j, a)| ((j + 1) as f64 * a).sin()).sum::<f64>()
}";

/// The same law in C, which needs each function's number of arguments.
fn c_unknown(eq: &Equations) -> String {
    let arities: Vec<String> = eq
        .variables
        .functions
        .iter()
        .map(|f| f.arguments.len().to_string())
        .chain(["0".to_string()])
        .collect();
    format!(
        "static double unknown(int index, const double *arguments) {{
    static const int arity[] = {{{}}};
    double sum = 0.25 * (index + 1);
    for (int j = 0; j < arity[index]; j++) sum += sin((j + 1) * arguments[j]);
    return sum;
}}",
        arities.join(", ")
    )
}

/// One state: time, positions, rates, parameters.
struct State {
    t: f64,
    p: Vec<f64>,
    q: Vec<f64>,
    k: Vec<f64>,
}

/// States at pseudo-random points; parameters are positive (they are masses and lengths too).
fn states(eq: &Equations, count: usize) -> Vec<State> {
    let mut random = Sequence(11);
    let n = eq.dimension();
    (0..count)
        .map(|_| State {
            t: random.next(),
            p: (0..n).map(|_| 1.5 * random.next()).collect(),
            q: (0..n).map(|_| random.next()).collect(),
            k: eq
                .variables
                .parameters
                .iter()
                .map(|_| 1.0 + 0.5 * random.next())
                .collect(),
        })
        .collect()
}

/// The symbol values of a state, the unknown functions' included (their arguments evaluated
/// in order: an argument may itself use an earlier function).
fn symbol_values(eq: &Equations, state: &State) -> Vec<f64> {
    let v = &eq.variables;
    let mut named: HashMap<String, f64> = HashMap::from([("t".to_string(), state.t)]);
    named.extend(
        v.positions
            .iter()
            .zip(&state.p)
            .map(|(x, &value)| (x.name.clone(), value)),
    );
    named.extend(
        v.rates
            .iter()
            .zip(&state.q)
            .map(|(x, &value)| (x.name.clone(), value)),
    );
    named.extend(
        v.parameters
            .iter()
            .zip(&state.k)
            .map(|(x, &value)| (x.name.clone(), value)),
    );
    let mut symbols = eq
        .symbol_values(|name| Some(named.get(name).copied().unwrap_or(0.0)))
        .expect("values");
    for (index, use_) in v.functions.iter().enumerate() {
        let arguments = Tape::new(&eq.pool, &use_.arguments).eval(&symbols);
        symbols[eq
            .pool
            .symbol_index(use_.symbol)
            .expect("a function use's value is a symbol")] = unknown(index, &arguments);
    }
    symbols
}

/// The accelerations the equations give: M q' = S + F for a tree; for loops, the KKT system's
/// least-squares solution by SVD (its accelerations are unique even with redundant rows).
fn accelerations(values: &Values) -> DVector<f64> {
    let n = values.mass.nrows();
    let rhs = &values.second_member + &values.forces;
    let m = values.constraints.nrows();
    if m == 0 {
        return values
            .mass
            .clone()
            .cholesky()
            .expect("M positive definite")
            .solve(&rhs);
    }
    let mut kkt = DMatrix::zeros(n + m, n + m);
    kkt.view_mut((0, 0), (n, n)).copy_from(&values.mass);
    kkt.view_mut((n, 0), (m, n)).copy_from(&values.constraints);
    kkt.view_mut((0, n), (n, m))
        .copy_from(&values.constraints.transpose());
    let mut b = DVector::zeros(n + m);
    b.rows_mut(0, n).copy_from(&rhs);
    b.rows_mut(n, m).copy_from(&(-&values.constraint_bias));
    let svd = kkt.svd(true, true);
    let cutoff = 1e-12 * svd.singular_values.max();
    svd.solve(&b, cutoff)
        .expect("SVD solve")
        .rows(0, n)
        .into_owned()
}

/// The largest relative deviation of `got` from `expected` (relative to max(|entry|, the
/// largest |entry| of `expected`)).
fn deviation(got: &[f64], expected: &[f64]) -> f64 {
    assert_eq!(got.len(), expected.len(), "number of values");
    let scale = expected.iter().fold(0.0f64, |s, x| s.max(x.abs()));
    got.iter()
        .zip(expected)
        .map(|(g, e)| {
            if g == e {
                0.0
            } else {
                (g - e).abs() / e.abs().max(scale).max(f64::MIN_POSITIVE)
            }
        })
        .fold(0.0, f64::max)
}

/// What a harness printed: label → values, one line per quantity per state.
fn parse_output(text: &str) -> Vec<HashMap<String, Vec<f64>>> {
    let mut states = Vec::new();
    for line in text.lines() {
        let mut words = line.split_whitespace();
        let Some(label) = words.next() else { continue };
        if label == "STATE" {
            states.push(HashMap::new());
            continue;
        }
        let values = words
            .map(|w| {
                w.parse::<f64>()
                    .unwrap_or_else(|_| panic!("a number in `{line}`"))
            })
            .collect();
        states
            .last_mut()
            .expect("a STATE line first")
            .insert(label.to_string(), values);
    }
    states
}

/// Compares a harness's output with the equations at the same states; returns the largest
/// deviation of M, S + F, Δ, Δ̇q (to the symbolic values) and of q' (to nalgebra's solution).
fn compare(eq: &Equations, states: &[State], output: &str, what: &str) -> (f64, f64) {
    let tape = eq.tape();
    let printed = parse_output(output);
    assert_eq!(
        printed.len(),
        states.len(),
        "{what}: one block per state in\n{output}"
    );
    let (mut values_deviation, mut dynamics_deviation) = (0.0f64, 0.0f64);
    for (state, printed) in states.iter().zip(&printed) {
        let values = eq.evaluate(&tape, &symbol_values(eq, state));
        let row_major = |m: &DMatrix<f64>| m.transpose().iter().copied().collect::<Vec<f64>>();
        let rhs: Vec<f64> = (&values.second_member + &values.forces)
            .iter()
            .copied()
            .collect();
        let mut expected = vec![("M", row_major(&values.mass)), ("RHS", rhs)];
        if eq.constraint_rows() > 0 {
            expected.push(("DELTA", row_major(&values.constraints)));
            expected.push(("BIAS", values.constraint_bias.iter().copied().collect()));
        }
        for (label, expected) in expected {
            let got = printed
                .get(label)
                .unwrap_or_else(|| panic!("{what}: no {label} in\n{output}"));
            let d = deviation(got, &expected);
            assert!(
                d <= TOLERANCE,
                "{what}: {label} deviates by {d:e}\n got {got:?}\nwant {expected:?}"
            );
            values_deviation = values_deviation.max(d);
        }
        let qdd = printed
            .get("QDD")
            .unwrap_or_else(|| panic!("{what}: forward dynamics failed:\n{output}"));
        let expected: Vec<f64> = accelerations(&values).iter().copied().collect();
        let d = deviation(qdd, &expected);
        assert!(
            d <= TOLERANCE,
            "{what}: q' deviates by {d:e}\n got {qdd:?}\nwant {expected:?}"
        );
        dynamics_deviation = dynamics_deviation.max(d);
    }
    (values_deviation, dynamics_deviation)
}

/// Whether the generated function `name` takes `parameter` (the time or the unknown functions).
fn takes(source: &str, name: &str, parameter: &str) -> bool {
    source
        .lines()
        .find(|l| l.contains(&format!(" {name}(")))
        .is_some_and(|l| l.contains(parameter))
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("lsdc-generated-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("a scratch directory");
    dir
}

fn run(command: &mut Command, what: &str) -> String {
    let output = command.output().unwrap_or_else(|e| panic!("{what}: {e}"));
    assert!(
        output.status.success(),
        "{what} failed:\n{}{}",
        String::from_utf8_lossy(&output.stdout),
        String::from_utf8_lossy(&output.stderr)
    );
    String::from_utf8_lossy(&output.stdout).into_owned()
}

fn list(values: &[f64], open: &str, close: &str) -> String {
    // Debug formatting is round-trip; a C double literal reads it the same.
    let items: Vec<String> = values.iter().map(|v| format!("{v:?}")).collect();
    format!("{open}{}{close}", items.join(", "))
}

/// A `main` that prints every quantity at the states.
fn rust_harness(eq: &Equations, source: &str, states: &[State]) -> String {
    let f = |name: &str| {
        if takes(source, name, "f: &dyn") {
            ", &unknown"
        } else {
            ""
        }
    };
    let t = |name: &str| {
        if takes(source, name, "t: f64") {
            "t, "
        } else {
            ""
        }
    };
    let mut body = format!(
        "    let mut m = [0.0; N * N];\n    mass_matrix({}p, k, &mut m{});\n    show(\"M\", &m);\n\
         \x20   let mut rhs = [0.0; N];\n    right_hand_side(t, p, q, k, &mut rhs{});\n    show(\"RHS\", &rhs);\n",
        t("mass_matrix"),
        f("mass_matrix"),
        f("right_hand_side")
    );
    if eq.constraint_rows() > 0 {
        body += &format!(
            "    let mut delta = [0.0; CONSTRAINTS * N];\n    constraints({}p, k, &mut delta{});\n    show(\"DELTA\", &delta);\n\
             \x20   let mut bias = [0.0; CONSTRAINTS];\n    constraint_bias({}p, q, k, &mut bias{});\n    show(\"BIAS\", &bias);\n",
            t("constraints"),
            f("constraints"),
            t("constraint_bias"),
            f("constraint_bias")
        );
    }
    body += &format!("    let mut qdd = [0.0; N];\n    if forward_dynamics(t, p, q, k, &mut qdd{}).is_ok() {{ show(\"QDD\", &qdd); }}\n", f("forward_dynamics"));
    let calls: Vec<String> = states
        .iter()
        .map(|s| {
            format!(
                "    at({:?}, &{}, &{}, &{});",
                s.t,
                list(&s.p, "[", "]"),
                list(&s.q, "[", "]"),
                list(&s.k, "[", "]")
            )
        })
        .collect();
    format!(
        "mod equations;\nuse equations::*;\n\n{RUST_UNKNOWN}\n\n\
         fn show(label: &str, values: &[f64]) {{\n    let text: Vec<String> = values.iter().map(|v| format!(\"{{v:?}}\")).collect();\n    println!(\"{{label}} {{}}\", text.join(\" \"));\n}}\n\n\
         fn at(t: f64, p: &[f64], q: &[f64], k: &[f64]) {{\n    println!(\"STATE\");\n{body}}}\n\n\
         fn main() {{\n{}\n}}\n",
        calls.join("\n")
    )
}

fn c_harness(eq: &Equations, source: &str, states: &[State]) -> String {
    let f = |name: &str| {
        if takes(source, name, "(*f)") {
            ", unknown"
        } else {
            ""
        }
    };
    let t = |name: &str| {
        if takes(source, name, "double t,") && name != "right_hand_side" {
            "t, "
        } else {
            ""
        }
    };
    let mut body = format!(
        "    double m[N * N], rhs[N], qdd[N];\n    mass_matrix({}p, k, m{});\n    show(\"M\", m, N * N);\n\
         \x20   right_hand_side(t, p, q, k, rhs{});\n    show(\"RHS\", rhs, N);\n",
        t("mass_matrix"),
        f("mass_matrix"),
        f("right_hand_side")
    );
    if eq.constraint_rows() > 0 {
        body += &format!(
            "    double delta[CONSTRAINTS * N], bias[CONSTRAINTS];\n    constraints({}p, k, delta{});\n    show(\"DELTA\", delta, CONSTRAINTS * N);\n\
             \x20   constraint_bias({}p, q, k, bias{});\n    show(\"BIAS\", bias, CONSTRAINTS);\n",
            t("constraints"),
            f("constraints"),
            t("constraint_bias"),
            f("constraint_bias")
        );
    }
    body += &format!(
        "    if (forward_dynamics(t, p, q, k, qdd{}) == 0) show(\"QDD\", qdd, N);\n",
        f("forward_dynamics")
    );
    // C has no empty arrays: a mechanism without parameters gets one unused.
    let calls: Vec<String> = states
        .iter()
        .map(|s| {
            let k = if s.k.is_empty() {
                vec![0.0]
            } else {
                s.k.clone()
            };
            format!(
                "    at({:?}, (const double[]){}, (const double[]){}, (const double[]){});",
                s.t,
                list(&s.p, "{", "}"),
                list(&s.q, "{", "}"),
                list(&k, "{", "}")
            )
        })
        .collect();
    format!(
        "#include <stdio.h>\n#include \"equations.c\"\n\n{}\n\n\
         static void show(const char *label, const double *values, int count) {{\n    printf(\"%s\", label);\n    for (int i = 0; i < count; i++) printf(\" %.17g\", values[i]);\n    printf(\"\\n\");\n}}\n\n\
         static void at(double t, const double *p, const double *q, const double *k) {{\n    printf(\"STATE\\n\");\n{body}}}\n\n\
         int main(void) {{\n{}\n    return 0;\n}}\n",
        c_unknown(eq),
        calls.join("\n")
    )
}

fn rustc() -> String {
    std::env::var("RUSTC").unwrap_or_else(|_| "rustc".to_string())
}

fn build_and_run_rust(name: &str, eq: &Equations, states: &[State]) -> String {
    let source = emit::rust(eq, &format!("examples/{name}.lsd"));
    let dir = scratch(&format!("rust-{name}"));
    std::fs::write(dir.join("equations.rs"), &source).expect("written");
    std::fs::write(dir.join("main.rs"), rust_harness(eq, &source, states)).expect("written");
    let binary = dir.join("harness");
    run(
        Command::new(rustc())
            .args(["-O", "--edition", "2021"])
            .arg(dir.join("main.rs"))
            .arg("-o")
            .arg(&binary),
        &format!("rustc on {name}"),
    );
    let output = run(
        &mut Command::new(&binary),
        &format!("the Rust harness of {name}"),
    );
    let _ = std::fs::remove_dir_all(&dir);
    output
}

fn build_and_run_c(compiler: &str, name: &str, eq: &Equations, states: &[State]) -> String {
    let source = emit::c(eq, &format!("examples/{name}.lsd"));
    let dir = scratch(&format!("c-{name}"));
    std::fs::write(dir.join("equations.c"), &source).expect("written");
    std::fs::write(dir.join("main.c"), c_harness(eq, &source, states)).expect("written");
    let binary = dir.join("harness");
    let compile = Command::new(compiler)
        .args([
            "-std=c99",
            "-O2",
            "-Wall",
            "-Werror=implicit-function-declaration",
        ])
        .arg(dir.join("main.c"))
        .arg("-o")
        .arg(&binary)
        .arg("-lm")
        .output();
    let output = compile.unwrap_or_else(|e| panic!("{compiler}: {e}"));
    assert!(
        output.status.success(),
        "{compiler} on {name} failed:\n{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let printed = run(
        &mut Command::new(&binary),
        &format!("the C harness of {name}"),
    );
    let _ = std::fs::remove_dir_all(&dir);
    printed
}

#[test]
fn generated_rust_computes_the_equations_and_the_forward_dynamics() {
    let results: Vec<String> = std::thread::scope(|scope| {
        let handles: Vec<_> = EXAMPLES
            .iter()
            .map(|&name| {
                scope.spawn(move || {
                    let eq = equations(name);
                    let states = states(&eq, 4);
                    let output = build_and_run_rust(name, &eq, &states);
                    let (values, dynamics) = compare(&eq, &states, &output, &format!("Rust for {name}"));
                    format!("{name}: equations within {values:.1e}, accelerations within {dynamics:.1e}")
                })
            })
            .collect();
        handles
            .into_iter()
            .map(|h| h.join().expect("no failure"))
            .collect()
    });
    println!("{}", results.join("\n"));
}

#[test]
fn generated_c_computes_the_equations_and_the_forward_dynamics() {
    let Some(compiler) = c_compiler() else {
        crate::common::skip(
            "no C compiler found (CC, cc, gcc, clang), the generated C is not checked",
        );
        return;
    };
    for name in EXAMPLES {
        let eq = equations(name);
        let states = states(&eq, 4);
        let output = build_and_run_c(&compiler, name, &eq, &states);
        let (values, dynamics) = compare(&eq, &states, &output, &format!("C for {name}"));
        println!("{name}: equations within {values:.1e}, accelerations within {dynamics:.1e}");
    }
}

/// Evaluates the JSON document's DAG at named symbol values; returns M (row-major), S, F, Δ, Δ̇q.
fn evaluate_json(document: &serde_json::Value, value_of: &dyn Fn(&str) -> f64) -> Vec<Vec<f64>> {
    let nodes = document["nodes"].as_array().expect("nodes");
    let mut values: Vec<f64> = Vec::with_capacity(nodes.len());
    for node in nodes {
        let arg = |k: usize| values[node["args"][k].as_u64().expect("an operand index") as usize];
        let value = match node["op"].as_str().expect("an op") {
            "constant" => node["value"].as_f64().expect("a value"),
            "symbol" | "unknown_function" => value_of(node["name"].as_str().expect("a name")),
            "add" => arg(0) + arg(1),
            "mul" => arg(0) * arg(1),
            "div" => arg(0) / arg(1),
            "pow" => arg(0).powf(arg(1)),
            "atan2" => arg(0).atan2(arg(1)),
            "neg" => -arg(0),
            function => lsdc::symbolic::expr::Function::from_name(function)
                .expect("a known function")
                .eval(arg(0)),
        };
        values.push(value);
    }
    let indices = |v: &serde_json::Value| -> Vec<f64> {
        let flat: Vec<&serde_json::Value> = v
            .as_array()
            .expect("a list")
            .iter()
            .flat_map(|x| {
                x.as_array()
                    .map(|row| row.iter().collect())
                    .unwrap_or_else(|| vec![x])
            })
            .collect();
        flat.iter()
            .map(|i| values[i.as_u64().expect("a node index") as usize])
            .collect()
    };
    [
        "mass",
        "second_member",
        "forces",
        "constraints",
        "constraint_bias",
    ]
    .iter()
    .map(|key| indices(&document[key]))
    .collect()
}

#[test]
fn json_holds_the_dag_that_gives_the_same_values() {
    for name in ["satellite", "four_bar", "double_pendulum"] {
        let eq = equations(name);
        let document: serde_json::Value =
            serde_json::from_str(&emit::json(&eq, name)).expect("valid JSON");
        let state = states(&eq, 1).remove(0);
        let symbols = symbol_values(&eq, &state);
        let by_name: HashMap<String, f64> = (0..eq.pool.symbol_count())
            .map(|i| (eq.pool.symbol_name(i as u32).to_string(), symbols[i]))
            .collect();
        let from_json = evaluate_json(&document, &|n| by_name[n]);
        let values = eq.evaluate(&eq.tape(), &symbols);
        let row_major = |m: &DMatrix<f64>| m.transpose().iter().copied().collect::<Vec<f64>>();
        let expected = [
            row_major(&values.mass),
            values.second_member.iter().copied().collect(),
            values.forces.iter().copied().collect(),
            row_major(&values.constraints),
            values.constraint_bias.iter().copied().collect(),
        ];
        for (got, want) in from_json.iter().zip(&expected) {
            assert_eq!(got, want, "{name}: the JSON DAG evaluates to other values");
        }
        assert_eq!(
            document["size"].as_u64(),
            Some(document["nodes"].as_array().map_or(0, |n| n.len()) as u64)
        );
        assert_eq!(
            document["variables"]["positions"]
                .as_array()
                .map(|p| p.len()),
            Some(eq.dimension())
        );
    }
}

#[test]
fn text_latex_and_sympy_have_their_shape() {
    let eq = equations("pendulum");
    let text = emit::text(&eq, "examples/pendulum.lsd");
    assert!(text.contains("M[1,1] = "), "{text}");
    assert!(text.contains("swing.q"), "{text}");
    assert!(text.contains("distinct nodes"), "{text}");
    let latex = emit::latex(&eq, "examples/pendulum.lsd");
    assert!(
        latex.contains("\\begin{align*}")
            && latex.contains("\\end{document}")
            && latex.contains("M_{1,1} &="),
        "{latex}"
    );
    assert!(latex.contains("q_{\\mathrm{swing}}"), "{latex}");
    let loops = equations("four_bar");
    let text = emit::text(&loops, "examples/four_bar.lsd");
    assert!(text.contains("Δ[c.") && text.contains("Δ̇q[c."), "{text}");
    let sympy = emit::sympy(&eq, "examples/pendulum.lsd");
    assert!(
        sympy.contains("import sympy as sp")
            && sympy.contains("swing_q = sp.Symbol('swing.q')")
            && sympy.contains("M[0, 0] = "),
        "{sympy}"
    );
    let satellite = emit::sympy(&equations("satellite"), "examples/satellite.lsd");
    assert!(
        satellite.contains("cL2_x = sp.Function('cL2_x')")
            && satellite.contains("cL2_x(join2_x, join2_x_dot)"),
        "{satellite}"
    );
}

#[test]
fn temporaries_are_named_once_and_constants_are_literals_of_every_language() {
    let eq = equations("satellite_fixed");
    let source = emit::rust(&eq, "x");
    let definitions: Vec<&str> = source
        .lines()
        .filter(|l| l.trim_start().starts_with("let x"))
        .collect();
    assert!(!definitions.is_empty());
    let c = emit::c(&eq, "x");
    assert!(c.contains("const double x0 = "));
    // Constants always carry a point or an exponent: `40.0`, never `40`.
    assert!(source.contains("40.0") && !source.contains(" 40 "));
}

/// The forward dynamics of a tree multiplies by no zero constant: the articulated-body
/// recursion's products by the zero entries of its spatial quantities are folded (the values
/// are the unfolded equations' to `TOLERANCE`, by the tests above). On the double pendulum
/// what the folded products rest on to be finite is the accelerations themselves (the
/// quotients by its articulated inertias) or quotients by constants: nothing is checked but the
/// accelerations, in both languages.
#[test]
fn generated_forward_dynamics_folds_products_by_zero() {
    let eq = equations("double_pendulum");
    let body = |source: &str, start: &str| {
        let from = source.find(start).expect("forward_dynamics");
        source[from..].to_string()
    };
    let c = body(&emit::c(&eq, "x"), "int forward_dynamics(");
    let rust = body(&emit::rust(&eq, "x"), "pub fn forward_dynamics(");
    // A product by the literal 0.0, not by 40.0.
    let by_zero = |code: &str| {
        code.match_indices("0.0 * ").any(|(i, _)| {
            let before = code[..i].chars().next_back();
            !before.is_some_and(|c| c.is_ascii_digit() || c == '.' || c == 'e')
        })
    };
    for (language, code) in [("C", &c), ("Rust", &rust)] {
        assert!(!by_zero(code), "{language}:\n{code}");
    }
    assert!(c.contains("return all_finite(qdd, N) ? 0 : 1;"), "{c}");
    assert!(
        rust.contains("if qdd[..N].iter().any(|x| !x.is_finite()) {"),
        "{rust}"
    );
}

/// The C of every example compiles as a file of its own without a warning under
/// `-Wall -Wextra -Werror` (unused inputs and names were warnings).
#[test]
fn generated_c_of_every_example_compiles_without_warnings() {
    let Some(compiler) = c_compiler() else {
        crate::common::skip(
            "no C compiler found (CC, cc, gcc, clang), the generated C is not checked",
        );
        return;
    };
    let examples = crate::common::example_paths();
    let dir = scratch("c-warnings");
    let compile = |path: &PathBuf| {
        let name = path.file_stem().expect("a name").to_string_lossy();
        let Some(equations) = written_equations(&path.to_string_lossy()) else {
            return;
        };
        let source = emit::c(&equations, &name);
        let file = dir.join(format!("{name}.c"));
        std::fs::write(&file, source).expect("written");
        let output = Command::new(&compiler)
            .args(["-std=c99", "-Wall", "-Wextra", "-Werror", "-c", "-o"])
            .arg(dir.join(format!("{name}.o")))
            .arg(&file)
            .output()
            .unwrap_or_else(|e| panic!("{compiler}: {e}"));
        assert!(
            output.status.success(),
            "{compiler} -Wall -Wextra -Werror on the C of {name}:\n{}",
            String::from_utf8_lossy(&output.stderr)
        );
    };
    let (even, odd): (Vec<_>, Vec<_>) = examples.iter().enumerate().partition(|(i, _)| i % 2 == 0);
    std::thread::scope(|scope| {
        let other = scope.spawn(|| odd.iter().for_each(|(_, path)| compile(path)));
        even.iter().for_each(|(_, path)| compile(path));
        other.join().expect("no failure");
    });
    let _ = std::fs::remove_dir_all(&dir);
    println!("{} examples: C without warnings", examples.len());
}

/// A torque on the exponential law of motion (a quadrature node of the pool): the generated
/// Rust and C define `exponential_profile` with lsdc's rule, and give the equations' values at
/// states inside the law (its times from −1 to 1, the states' times in [−1, 1)).
#[test]
fn generated_code_evaluates_the_exponential_law_as_lsdc_does() {
    let path = "tests/fixtures/exponential_torque.lsd";
    let eq = equations_of(path);
    assert!(eq.pool.uses_exponential_profile());
    let states = states(&eq, 6);
    let output = build_and_run_rust("exponential_torque", &eq, &states);
    let (values, _) = compare(&eq, &states, &output, "Rust for the exponential law");
    println!("Rust: equations within {values:.1e}");
    let Some(compiler) = c_compiler() else {
        crate::common::skip(
            "no C compiler found (CC, cc, gcc, clang), the generated C is not checked",
        );
        return;
    };
    let output = build_and_run_c(&compiler, "exponential_torque", &eq, &states);
    let (values, _) = compare(&eq, &states, &output, "C for the exponential law");
    println!("C: equations within {values:.1e}");
}
