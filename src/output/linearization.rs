//! A linearisation (`lsdc linearize`) for people (text, matrices with their rows' and columns'
//! names) and for MATLAB or GNU Octave (a script that builds the state-space model `sys` with
//! `ss`, named states, inputs and outputs). Its JSON is its `Serialize` form, which
//! python-control reads as `control.ss(m["A"], m["B"], m["C"], m["D"])`.

use nalgebra::DMatrix;

use crate::studies::linearize::Linearization;

/// The linearisation as text; with `modes`, the eigenvalues' natural frequencies and damping
/// ratios.
pub fn text(l: &Linearization, modes: bool) -> String {
    let mut out = format!("linearised at the {} state, t = {}\n", l.point, l.time);
    out += &format!("coordinates: {} ({})\n", list(&l.coordinates), l.choice);
    if !l.dependent.is_empty() {
        out += &format!(
            "following from them through the loops: {}\n",
            list(&l.dependent)
        );
    }
    if !l.held.is_empty() {
        out += &format!(
            "held where they are (motions without mass): {}\n",
            list(&l.held)
        );
    }
    if !l.driven.is_empty() {
        out += &format!(
            "imposed by their laws of time at t = {} (not states): {}\n",
            l.time,
            list(&l.driven)
        );
    }
    if !l.program_states.is_empty() {
        out += &format!("states of the program: {}\n", list(&l.program_states));
    }
    let inputs = match l.inputs.is_empty() {
        true => "none".to_string(),
        false => list(&l.inputs) + " (generalised forces along coordinates, or states held)",
    };
    out += &format!("inputs: {inputs}\n");
    out += &format!("outputs: {}\n\n", list(&l.outputs));
    out += &vector("operating state x", &l.states, &l.state);
    if !l.inputs.is_empty() {
        out += &vector("operating inputs u", &l.inputs, &l.input);
    }
    let n = l.coordinates.len();
    let rates: Vec<String> = (l.states[n..2 * n].iter())
        .chain(&l.program_states)
        .map(|s| format!("{s}'"))
        .collect();
    let values: Vec<f64> = l
        .accelerations
        .iter()
        .chain(&l.state_rates)
        .copied()
        .collect();
    out += &vector("rates there", &rates, &values);
    out += &matrix("A", &l.states, &l.states, &l.a);
    out += &matrix("B", &l.states, &l.inputs, &l.b);
    out += &matrix("C", &l.outputs, &l.states, &l.c);
    out += &matrix("D", &l.outputs, &l.inputs, &l.d);
    out += &format!(
        "derivatives: {}; largest error estimate {:.1e} in A, {:.1e} in B, {:.1e} in C\n",
        l.method,
        l.a_error.amax(),
        l.b_error.amax(),
        l.c_error.amax()
    );
    if let Some(why) = &l.differenced_because {
        out += &format!("differenced because {why}\n");
    }
    if modes {
        out += "\nmodes (eigenvalues of A):\n";
        out += &format!(
            "  {:>14}  {:>14}  {:>14}  {:>10}\n",
            "real", "imaginary", "ωn (rad/s)", "ζ"
        );
        for mode in &l.modes {
            let ratio = mode
                .damping_ratio
                .map_or("—".to_string(), |z| format!("{z:.6}"));
            out += &format!(
                "  {:>14.6e}  {:>14.6e}  {:>14.6e}  {:>10}\n",
                mode.eigenvalue.re, mode.eigenvalue.im, mode.natural_frequency, ratio
            );
        }
    }
    out
}

/// A MATLAB (or GNU Octave with its `control` package) script that builds `sys`, the
/// state-space model, with `A`, `B`, `C`, `D` and the names; `source` names the program.
pub fn matlab(l: &Linearization, source: &str) -> String {
    let mut out = format!(
        "% lsdc linearize {source}: the {} state, t = {}\n% coordinates: {} ({})\n% derivatives: {}\n",
        l.point,
        l.time,
        l.coordinates.join(", "),
        l.choice,
        l.method
    );
    for (name, m) in [("A", &l.a), ("B", &l.b), ("C", &l.c), ("D", &l.d)] {
        out += &format!("{name} = {};\n", matlab_matrix(m));
    }
    out += &format!(
        "x0 = {};\n",
        matlab_matrix(&DMatrix::from_column_slice(l.state.len(), 1, &l.state))
    );
    out += &format!(
        "u0 = {};\n",
        matlab_matrix(&DMatrix::from_column_slice(l.input.len(), 1, &l.input))
    );
    for (name, names) in [
        ("states", &l.states),
        ("inputs", &l.inputs),
        ("outputs", &l.outputs),
    ] {
        let quoted: Vec<String> = names
            .iter()
            .map(|n| format!("'{}'", n.replace('\'', "''")))
            .collect();
        out += &format!("{name} = {{{}}};\n", quoted.join(", "));
    }
    out +=
        "sys = ss(A, B, C, D, 'StateName', states, 'InputName', inputs, 'OutputName', outputs);\n";
    out
}

/// `[a, b; c, d]`, or `zeros(r, c)` for a matrix without entries (MATLAB's `[]` is 0 × 0).
fn matlab_matrix(m: &DMatrix<f64>) -> String {
    if m.is_empty() {
        return format!("zeros({}, {})", m.nrows(), m.ncols());
    }
    let rows: Vec<String> = m
        .row_iter()
        .map(|row| {
            let entries: Vec<String> = row.iter().map(|&x| matlab_number(x)).collect();
            entries.join(", ")
        })
        .collect();
    format!("[{}]", rows.join("; "))
}

/// A number MATLAB reads back exactly (Rust's shortest round-trip form).
fn matlab_number(x: f64) -> String {
    match x {
        x if x.is_nan() => "NaN".to_string(),
        x if x.is_infinite() => (if x > 0.0 { "Inf" } else { "-Inf" }).to_string(),
        x => format!("{x:?}"),
    }
}

fn list(names: &[String]) -> String {
    match names.is_empty() {
        true => "none".to_string(),
        false => names.join(", "),
    }
}

fn vector(title: &str, names: &[String], values: &[f64]) -> String {
    let width = names.iter().map(|n| n.chars().count()).max().unwrap_or(0);
    let mut out = format!("{title}:\n");
    for (name, value) in names.iter().zip(values) {
        out += &format!("  {name:width$}  {value:>14.6e}\n");
    }
    out + "\n"
}

/// A matrix with its rows' and columns' names.
fn matrix(title: &str, rows: &[String], columns: &[String], m: &DMatrix<f64>) -> String {
    if m.is_empty() {
        return format!("{title} ({} × {}): empty\n\n", m.nrows(), m.ncols());
    }
    let width = rows.iter().map(|n| n.chars().count()).max().unwrap_or(0);
    let column_width = columns
        .iter()
        .map(|n| n.chars().count())
        .max()
        .unwrap_or(0)
        .max(14);
    let mut out = format!("{title}:\n  {:width$}", "");
    for name in columns {
        out += &format!("  {name:>column_width$}");
    }
    out += "\n";
    for (r, name) in rows.iter().enumerate() {
        out += &format!("  {name:width$}");
        for c in 0..m.ncols() {
            out += &format!("  {:>column_width$.6e}", m[(r, c)]);
        }
        out += "\n";
    }
    out + "\n"
}
