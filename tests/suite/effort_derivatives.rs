//! The derivatives `lsdc eval --derivatives` gives with the program's efforts differentiated
//! (`dynamics::effort_derivatives`, forward mode through the efforts' tape) against central
//! differences of the whole forward dynamics that `eval` computes at moved states: its
//! accelerations under the efforts evaluated afresh at each state (springs, dampers, weights,
//! laws of the frames' orientations and angular velocities), a different path from the tangents
//! through the tape. On every example without loops whose efforts they cover, and the inverse
//! dynamics' derivatives the same way. Each example at its initial positions, its rates moved by
//! 0.3 + 0.2 k (k the velocity's index), so that its springs keep their stretch: elsewhere the
//! stiff spring pendulum's k/m = 1e8 makes the accelerations large and the differences'
//! rounding, ε |q̈| / δ, the larger error (measured: its positions moved by 0.02 k, ∂q̈/∂v off
//! by 4.7e-6 of its largest entry, the radial row's; at arbitrary positions by 5e-4). The measure is that
//! of `derivatives`, max |analytic − differences| / max(1, max |analytic|), accepted at 1e-6; a
//! step of 1e-6 relative to the coordinate (central differences' truncation error is O(δ²)
//! relative).

use lsdc::dynamics::algorithms::{forward_kinematics, Data};
use lsdc::dynamics::angles::AngleReference;
use lsdc::dynamics::effort_derivatives::{self, EffortDerivatives};
use lsdc::dynamics::efforts::Declared;
use nalgebra::DMatrix;
use serde_json::{json, Value};

use crate::common::example_paths;
use crate::common::programs::{initial_state, prepared_file};
use crate::derivatives::{example_model, mismatch};

const TOLERANCE: f64 = 1e-6;

fn matrix(value: &Value, n: usize) -> DMatrix<f64> {
    DMatrix::from_fn(n, n, |i, j| value[i][j].as_f64().expect("number"))
}

fn vector(value: &Value) -> Vec<f64> {
    let numbers = value.as_array().expect("list");
    numbers
        .iter()
        .map(|x| x.as_f64().expect("number"))
        .collect()
}

/// The states of central differences about (q, v): q_j ± δ_j, then v_j ± δ_j, for each j.
fn moved_states(q: &[f64], v: &[f64], a: &[f64], tau: &[f64], steps: &[f64]) -> Vec<Value> {
    let mut states = vec![json!({"q": q, "v": v, "a": a, "tau": tau})];
    for (j, step) in steps.iter().enumerate() {
        for sign in [1.0, -1.0] {
            let mut moved = q.to_vec();
            moved[j] += sign * step;
            states.push(json!({"q": moved, "v": v, "a": a, "tau": tau}));
        }
    }
    for (j, step) in steps.iter().enumerate() {
        for sign in [1.0, -1.0] {
            let mut moved = v.to_vec();
            moved[j] += sign * step;
            states.push(json!({"q": q, "v": moved, "a": a, "tau": tau}));
        }
    }
    states
}

/// Central differences of `quantity` ("aba" or "rnea") over the moved states: along q, along v.
fn differenced(states: &[Value], quantity: &str, steps: &[f64]) -> (DMatrix<f64>, DMatrix<f64>) {
    let n = steps.len();
    let column = |first: usize, j: usize| {
        let plus = vector(&states[first + 2 * j][quantity]);
        let minus = vector(&states[first + 2 * j + 1][quantity]);
        (0..n).map(move |i| (plus[i] - minus[i]) / (2.0 * steps[j]))
    };
    let by_q = DMatrix::from_fn(n, n, |i, j| column(1, j).nth(i).expect("row"));
    let by_v = DMatrix::from_fn(n, n, |i, j| column(1 + 2 * n, j).nth(i).expect("row"));
    (by_q, by_v)
}

#[test]
fn eval_differentiates_the_efforts_as_differences_of_the_whole_dynamics() {
    let (mut covered, mut held) = (Vec::new(), Vec::new());
    for path in example_paths() {
        let Ok(model) = example_model(&path) else {
            continue;
        };
        let has_efforts = !model.applied.is_empty() || !model.link_efforts.is_empty();
        if !has_efforts || model.nq != model.nv {
            continue;
        }
        let y = initial_state(&prepared_file(path.to_str().expect("path")));
        let (q, mut v) = (y[..model.nq].to_vec(), y[model.nq..].to_vec());
        for (k, rate) in v.iter_mut().enumerate() {
            *rate += 0.3 + 0.2 * k as f64;
        }
        let a: Vec<f64> = (0..model.nv).map(|k| 0.1 * k as f64 - 0.2).collect();
        let tau: Vec<f64> = (0..model.nv).map(|k| 0.3 - 0.2 * k as f64).collect();
        let steps: Vec<f64> = q.iter().map(|x| 1e-6 * x.abs().max(1.0)).collect();
        let states = moved_states(&q, &v, &a, &tau, &steps);
        let file = std::env::temp_dir().join(format!(
            "effort-derivatives-{}-{}.json",
            std::process::id(),
            covered.len() + held.len()
        ));
        std::fs::write(&file, serde_json::to_string(&states).expect("json")).expect("write");
        let (code, out, err) = crate::common::lsdc(&[
            "eval",
            path.to_str().expect("path"),
            "--states",
            file.to_str().expect("path"),
            "--derivatives",
        ]);
        let _ = std::fs::remove_file(&file);
        assert_eq!(code, 0, "{}: {err}", path.display());
        let json: Value = serde_json::from_str(&out).expect("json");
        let evaluated = json["states"].as_array().expect("states");
        let derivatives = &evaluated[0]["derivatives"];
        if derivatives["efforts_held"] != false {
            held.push(path.display().to_string());
            continue;
        }
        let n = model.nv;
        let mut worst: f64 = 0.0;
        for quantity in ["aba", "rnea"] {
            let (by_q, by_v) = differenced(evaluated, quantity, &steps);
            let dq = matrix(&derivatives[quantity]["dq"], n);
            let dv = matrix(&derivatives[quantity]["dv"], n);
            let measure = mismatch(&dq, &by_q).max(mismatch(&dv, &by_v));
            assert!(
                measure <= TOLERANCE,
                "{} {quantity}: {measure:e}\nanalytic dq {dq}differences {by_q}\nanalytic dv {dv}differences {by_v}",
                path.display()
            );
            worst = worst.max(measure);
        }
        covered.push(format!("{} ({worst:.1e})", path.display()));
    }
    eprintln!("covered: {covered:#?}\nefforts held: {held:#?}");
    let names = covered.join(" ");
    for example in ["governor", "elastic_pendulum", "stiff_spring_pendulum"] {
        assert!(
            names.contains(example),
            "{example} is not covered: {held:#?}"
        );
    }
}

/// The efforts' derivatives through the tape (`Tape::tangents_prefix_into`, the forward mode
/// behind `eval --derivatives` and the implicit integrator's tree Jacobian) against the same
/// tape evaluated in dual numbers (`EffortTape::eval_dual`, num-dual's own rule for each
/// operation), from the same symbols and the same seeds (the frames' states' derivatives along
/// (q, v) that `EffortDerivatives::compute` forms): every effort component along each of the
/// 2 nv directions, on every example whose efforts the derivatives cover, at the state of the
/// test above. The measure: max |tangent − dual| / max(1, max |dual|) per example, accepted at
/// 1e-12.
#[test]
fn the_tapes_tangents_agree_with_dual_numbers_on_the_examples() {
    let mut covered = Vec::new();
    for path in example_paths() {
        let Ok(model) = example_model(&path) else {
            continue;
        };
        if !model.has_efforts() || effort_derivatives::covers(&model).is_err() {
            continue;
        }
        let tape = model.effort_tape.as_ref().expect("covered");
        let prepared = prepared_file(path.to_str().expect("path"));
        let y = initial_state(&prepared);
        let (q, mut v) = (y[..model.nq].to_vec(), y[model.nq..].to_vec());
        for (k, rate) in v.iter_mut().enumerate() {
            *rate += 0.3 + 0.2 * k as f64;
        }
        let reference = AngleReference::at_rest(prepared.coordinates.clone());
        let (coordinates, rates) = (model.declared((0.0, &q, &v), &reference)).expect("declared");
        let mut data = Data::new(&model);
        forward_kinematics(&model, &mut data, &q, &v).expect("kinematics");
        let declared = Declared {
            model: &model,
            coordinates: &coordinates,
            rates: &rates,
            states: &[],
        };
        let mut derivatives = EffortDerivatives::new(&model);
        (derivatives.compute(&model, &mut data, &declared, 0.0)).expect("derivatives");
        let (tangents, seeds) = derivatives.tape_tangents();
        let directions = 2 * model.nv;
        let (mut largest, mut worst, mut components) = (0.0f64, 0.0f64, 0);
        for x in 0..directions {
            let duals = tape.eval_dual(&data.efforts, seeds, (directions, x));
            components = duals.len();
            for (k, dual) in duals.iter().enumerate() {
                let found = tape.root_tangent(tangents, k)[x];
                assert!(dual.eps.is_finite(), "{}: root {k}", path.display());
                largest = largest.max(dual.eps.abs());
                worst = worst.max((found - dual.eps).abs());
            }
        }
        // Derivatives that all vanish would agree whatever the tangent sweep did.
        assert!(largest > 0.0, "{}: no derivative", path.display());
        let measure = worst / largest.max(1.0);
        assert!(measure <= 1e-12, "{}: {measure:e}", path.display());
        covered.push(format!(
            "{} ({components} components, largest derivative {largest:.1e}, {measure:.1e})",
            path.display()
        ));
    }
    eprintln!("covered: {covered:#?}");
    let names = covered.join(" ");
    for example in ["governor", "elastic_pendulum", "stiff_spring_pendulum"] {
        assert!(names.contains(example), "{example} is not covered");
    }
}
