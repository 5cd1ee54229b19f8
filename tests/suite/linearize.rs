//! `lsdc linearize`: A, B, C, D against closed forms (pendulum, cart-pole, a four-bar's
//! Lagrangian in its crank angle), the Delta against plain central differences of its
//! closed-loop model through the program's own assembly, eigenvalues and damping ratios, the
//! cart-pole's LQR gain and its closed loop, and the command's diagnostics (golden files under
//! `tests/golden/linearize/`: `NAME.args`, the arguments after `lsdc linearize`, and
//! `NAME.stderr`; `UPDATE_GOLDEN=1` rewrites them).

use nalgebra::DMatrix;

use crate::common::programs::{assembled_rates, example_text, prepared};
use crate::common::{check_command_goldens, lsdc, skip};
use crate::derivatives::mismatch;
use crate::dual_numbers::loop_programs;
use lsdc::studies::linearize::differences;
use lsdc::studies::linearize::{
    linearize, linearize_by, Derivatives, Linearization, OperatingPoint, Request, LOOP_METHOD,
};

fn request(point: OperatingPoint, inputs: &[&str], coordinates: &[&str]) -> Request {
    Request {
        point,
        inputs: inputs.iter().map(|s| s.to_string()).collect(),
        coordinates: coordinates.iter().map(|s| s.to_string()).collect(),
    }
}

fn largest_difference(a: &DMatrix<f64>, b: &DMatrix<f64>) -> f64 {
    assert_eq!(a.shape(), b.shape());
    (a - b).amax()
}

/// The pendulum of examples/pendulum.lsd: m = 1.2, centre of mass 0.5 below the pivot, 0.1 about
/// it, so I = 0.1 + m 0.5² = 0.4 about the axis; I θ'' = −m g l sin θ + u.
#[test]
fn pendulum_matches_its_closed_form() {
    let prepared = prepared("pendulum", &[]);
    let l = linearize(
        &prepared,
        &request(OperatingPoint::Initial, &["swing.q"], &[]),
    )
    .unwrap();
    let (m, g, arm, inertia) = (1.2, 9.81, 0.5, 0.4);
    let theta = std::f64::consts::PI / 3.0;
    let a = DMatrix::from_row_slice(2, 2, &[0.0, 1.0, -m * g * arm * theta.cos() / inertia, 0.0]);
    let b = DMatrix::from_row_slice(2, 1, &[0.0, 1.0 / inertia]);
    assert!(largest_difference(&l.a, &a) < 1e-9, "{}", l.a);
    assert!(largest_difference(&l.b, &b) < 1e-9, "{}", l.b);
    assert!((l.accelerations[0] + m * g * arm * theta.sin() / inertia).abs() < 1e-9);
    // The estimates bound the errors.
    assert!((l.a - &a)
        .abs()
        .iter()
        .zip(l.a_error.iter())
        .all(|(e, bound)| e <= bound));
    assert_eq!(l.states, ["swing.q", "swing.q'"]);
    assert_eq!(l.c, DMatrix::identity(2, 2));
    assert_eq!(l.d, DMatrix::zeros(2, 1));
}

/// The cart-pole of examples/control/cart_pole.lsd about upright (see its header comment).
#[test]
fn cart_pole_matches_its_closed_form() {
    let prepared = prepared("control/cart_pole", &[]);
    let l = linearize(
        &prepared,
        &request(OperatingPoint::Initial, &["rail.q"], &[]),
    )
    .unwrap();
    let (cart, pole, length, g) = (1.0, 0.1, 1.0, 9.81);
    let arm = length / 2.0;
    let inertia = pole * length * length / 12.0;
    let mass = DMatrix::from_row_slice(
        2,
        2,
        &[
            cart + pole,
            pole * arm,
            pole * arm,
            inertia + pole * arm * arm,
        ],
    );
    let inverse = mass.try_inverse().unwrap();
    let stiffness = DMatrix::from_row_slice(2, 2, &[0.0, 0.0, 0.0, pole * g * arm]);
    let mut a = DMatrix::zeros(4, 4);
    a.view_mut((0, 2), (2, 2)).fill_with_identity();
    a.view_mut((2, 0), (2, 2))
        .copy_from(&(&inverse * stiffness));
    let mut b = DMatrix::zeros(4, 1);
    b.view_mut((2, 0), (2, 1)).copy_from(&inverse.column(0));
    assert!(largest_difference(&l.a, &a) < 1e-9, "{}", l.a);
    assert!(largest_difference(&l.b, &b) < 1e-9, "{}", l.b);
    assert_eq!(l.states, ["rail.q", "hinge.q", "rail.q'", "hinge.q'"]);
}

/// The four-bar of examples/four_bar.lsd (bars of 1 kg/m, gravity −y) reduced to its crank
/// angle θ by hand: B = l1 e(θ), C = B + l2 e(φ) = D + l3 e(ψ) with C above the ground line,
/// φ', ψ' and φ'', ψ'' from the closure's first and second derivatives in θ, then
/// M(θ) = I_O1 + m2 |v_G2|² + I_G2 φ'² + I_D3 ψ'² and V(θ) = g Σ m y_G. At rest, held by
/// u* = V'(θ*), θ'' = (u − V'(θ))/M(θ) linearises to A = [[0, 1], [−V''/M, 0]], B = [0; 1/M].
pub(crate) struct FourBarReference {
    /// M(θ), the reduced mass in the crank's angle.
    pub(crate) mass: f64,
    pub(crate) holding: f64,
    a21: f64,
    b: f64,
    /// d(coupler.q)/dθ = φ' − 1.
    coupler_rate: f64,
}

pub(crate) fn four_bar_reference(theta: f64) -> FourBarReference {
    let (l0, l1, l2, l3, g) = (4.0_f64, 1.0_f64, 3.5_f64, 3.0_f64, 9.81);
    let (m1, m2, m3) = (l1, l2, l3);
    let b = (l1 * theta.cos(), l1 * theta.sin());
    let (dx, dy) = (l0 - b.0, -b.1);
    let d = dx.hypot(dy);
    let along = (l2 * l2 - l3 * l3 + d * d) / (2.0 * d);
    let height = (l2 * l2 - along * along).sqrt();
    // The intersection above the ground line: the one with the larger y.
    let candidates = [1.0, -1.0].map(|s| {
        (
            b.0 + along * dx / d - s * height * dy / d,
            b.1 + along * dy / d + s * height * dx / d,
        )
    });
    let c = if candidates[0].1 > candidates[1].1 {
        candidates[0]
    } else {
        candidates[1]
    };
    let phi = (c.1 - b.1).atan2(c.0 - b.0);
    let psi = c.1.atan2(c.0 - l0);
    // l2 e⊥(φ) φ' − l3 e⊥(ψ) ψ' = r, by Cramer's rule.
    let solve = |r: (f64, f64)| {
        let (a11, a12, a21, a22) = (
            -l2 * phi.sin(),
            l3 * psi.sin(),
            l2 * phi.cos(),
            -l3 * psi.cos(),
        );
        let det = a11 * a22 - a12 * a21;
        ((r.0 * a22 - a12 * r.1) / det, (a11 * r.1 - a21 * r.0) / det)
    };
    let (p1, s1) = solve((l1 * theta.sin(), -l1 * theta.cos()));
    let (p2, s2) = solve((
        l1 * theta.cos() + l2 * phi.cos() * p1 * p1 - l3 * psi.cos() * s1 * s1,
        l1 * theta.sin() + l2 * phi.sin() * p1 * p1 - l3 * psi.sin() * s1 * s1,
    ));
    let (i1, i2, i3) = (m1 * l1 * l1 / 3.0, m2 * l2 * l2 / 12.0, m3 * l3 * l3 / 3.0);
    let vx = -l1 * theta.sin() - l2 / 2.0 * phi.sin() * p1;
    let vy = l1 * theta.cos() + l2 / 2.0 * phi.cos() * p1;
    let mass = i1 + m2 * (vx * vx + vy * vy) + i2 * p1 * p1 + i3 * s1 * s1;
    let first = g
        * (m1 * l1 / 2.0 * theta.cos()
            + m2 * (l1 * theta.cos() + l2 / 2.0 * phi.cos() * p1)
            + m3 * l3 / 2.0 * psi.cos() * s1);
    let second = g
        * (-m1 * l1 / 2.0 * theta.sin()
            + m2 * (-l1 * theta.sin() + l2 / 2.0 * (phi.cos() * p2 - phi.sin() * p1 * p1))
            + m3 * l3 / 2.0 * (psi.cos() * s2 - psi.sin() * s1 * s1));
    FourBarReference {
        mass,
        holding: first,
        a21: -second / mass,
        b: 1.0 / mass,
        coupler_rate: p1 - 1.0,
    }
}

#[test]
fn four_bar_about_its_equilibrium_matches_its_reduced_lagrangian() {
    let prepared = prepared("four_bar", &[]);
    let reference = four_bar_reference(1.0);
    let point = OperatingPoint::Equilibrium;
    let l = linearize(&prepared, &request(point, &["crank.q"], &["crank.q"])).unwrap();
    assert_eq!(l.coordinates, ["crank.q"]);
    assert!(
        (l.input[0] - reference.holding).abs() < 1e-9,
        "{}",
        l.input[0]
    );
    eprintln!(
        "four-bar at rest, {}: A {:.1e}, B {:.1e} from the closed form",
        l.method,
        (l.a[(1, 0)] - reference.a21).abs(),
        (l.b[(1, 0)] - reference.b).abs()
    );
    assert!((l.a[(1, 0)] - reference.a21).abs() < 1e-8, "{}", l.a);
    assert!((l.b[(1, 0)] - reference.b).abs() < 1e-8, "{}", l.b);
    assert!(l.a[(1, 1)].abs() < 1e-8 && l.accelerations[0].abs() < 1e-8);
    // In the run's own chart (the coupler's angle z), δz = z'(θ) δθ at rest: the same
    // eigenvalues, B scaled by z'.
    let own = linearize(&prepared, &request(point, &["crank.q"], &[])).unwrap();
    assert_eq!(own.coordinates, ["coupler.q"]);
    assert!((own.a[(1, 0)] - reference.a21).abs() < 1e-8, "{}", own.a);
    assert!((own.b[(1, 0)] - reference.coupler_rate * reference.b).abs() < 1e-8);
}

/// The Delta at its initial pose, in its actuated angles: A's lower rows against plain central
/// differences (step 1e-4) of its accelerations, each state made by the program's own assembly
/// (the arms' angles `fixed`, the rates given to the actuated joints and completed by the
/// loops), independent of the linearisation's chart and extrapolation.
#[test]
fn delta_matches_central_differences_of_its_closed_loop_model() {
    let actuated = ["A1.q", "A2.q", "A3.q"];
    let prepared_delta = prepared("delta_isir88", &[]);
    let l = linearize(
        &prepared_delta,
        &request(OperatingPoint::Initial, &["A1.q"], &actuated),
    )
    .unwrap();
    assert_eq!(l.held.len(), 6, "{:?}", l.held);
    // Its rods spin without mass between ball joints: the derivatives refuse, A is differenced.
    let why = l.differenced_because.as_deref().unwrap_or_default();
    assert!(why.contains("move no mass"), "{why}");
    let accelerations = |moved: &str, by: f64| -> Vec<f64> {
        let (from, to) = match moved.ends_with('\'') {
            false => {
                let from = format!("{} = 40 * pi / 180 fixed", &moved[..4]);
                let to = format!("{} = 40 * pi / 180 + {by:e} fixed", &moved[..4]);
                (from, to)
            }
            // Every actuated rate given: the loops complete the others.
            true => {
                let rates: Vec<String> = actuated
                    .iter()
                    .map(|a| match a == &&moved[..4] {
                        true => format!("{a}' = {by:e}"),
                        false => format!("{a}' = 0"),
                    })
                    .collect();
                let from = "A1.q = 40 * pi / 180 fixed,".to_string();
                (from.clone(), format!("{from} {},", rates.join(", ")))
            }
        };
        let prepared = prepared("delta_isir88", &[(&from, &to)]);
        assembled_rates(&prepared, &actuated).0
    };
    let step = 1e-4;
    let states = ["A1.q", "A2.q", "A3.q", "A1.q'", "A2.q'", "A3.q'"];
    let mut largest = 0.0_f64;
    for (column, state) in states.iter().enumerate() {
        let ahead = accelerations(state, step);
        let behind = accelerations(state, -step);
        for row in 0..3 {
            let difference = (ahead[row] - behind[row]) / (2.0 * step);
            largest = largest.max((difference - l.a[(3 + row, column)]).abs());
        }
    }
    assert!(largest < 1e-6, "largest difference {largest:e}\n{}", l.a);
}

/// Every example with loops that `linearize` accepts at its initial state, with a generalised
/// force along its first independent coordinate as an input: where the constrained dynamics'
/// derivatives cover it, A's and B's accelerations' rows are exact and agree with the
/// differenced linearisation (central differences of the nonlinear model through the chart,
/// Richardson-extrapolated) to 1e-6 of their largest entry; where they refuse, the
/// linearisation is the differenced one and says why.
#[test]
fn loop_examples_linearise_exactly_where_covered() {
    let (mut exact, mut refused, mut not_linearised) = (Vec::new(), Vec::new(), Vec::new());
    let point = OperatingPoint::Initial;
    for (name, prepared) in loop_programs() {
        let differenced =
            |request: &Request| linearize_by(&prepared, request, Derivatives::Differenced);
        let first = match differenced(&request(point, &[], &[])) {
            Ok(l) if !l.coordinates.is_empty() => l.coordinates[0].clone(),
            Ok(_) => continue,
            Err(e) => {
                not_linearised.push(format!("{name}: {e}"));
                continue;
            }
        };
        let with_input = request(point, &[&first], &[]);
        let reference = differenced(&with_input).unwrap_or_else(|e| panic!("{name}: {e}"));
        let l = linearize(&prepared, &with_input).unwrap_or_else(|e| panic!("{name}: {e}"));
        if let Some(why) = &l.differenced_because {
            assert_eq!(l.a, reference.a, "{name}");
            assert_eq!(l.b, reference.b, "{name}");
            refused.push(format!("{name}: {why}"));
            continue;
        }
        assert_eq!(l.method, LOOP_METHOD, "{name}");
        let n = l.coordinates.len();
        let lower = |m: &DMatrix<f64>| m.rows(n, n).into_owned();
        let (by_state, by_input) = (
            mismatch(&lower(&l.a), &lower(&reference.a)),
            mismatch(&lower(&l.b), &lower(&reference.b)),
        );
        // The exact rows carry no error estimate; the rest of the model is the same.
        assert_eq!(lower(&l.a_error).amax(), 0.0, "{name}");
        assert_eq!(l.c, reference.c, "{name}");
        assert!(
            by_state <= 1e-6 && by_input <= 1e-6,
            "{name}: A {by_state:.1e}, B {by_input:.1e}\nexact {}{}differenced {}{}",
            l.a,
            l.b,
            reference.a,
            reference.b
        );
        exact.push(format!("{name} (A {by_state:.1e}, B {by_input:.1e})"));
    }
    eprintln!("exact: {exact:#?}\ndifferenced: {refused:#?}\nnot linearised: {not_linearised:#?}");
    assert!(exact.len() >= 6, "only {} exact: {refused:#?}", exact.len());
    assert!(!refused.is_empty(), "no example falls back to differences");
}

fn real_parts_at_round_off(l: &Linearization) {
    let size = l
        .eigenvalues
        .iter()
        .map(|e| e.re.hypot(e.im))
        .fold(0.0, f64::max);
    for e in &l.eigenvalues {
        assert!(e.re.abs() <= 1e-12 * size, "{:?}", l.eigenvalues);
        assert!(e.im != 0.0, "{:?}", l.eigenvalues);
    }
}

#[test]
fn undamped_mechanisms_have_imaginary_eigenvalues() {
    let pendulum = prepared("pendulum", &[]);
    let l = linearize(&pendulum, &request(OperatingPoint::Initial, &[], &[])).unwrap();
    real_parts_at_round_off(&l);
    let omega = (1.2_f64 * 9.81 * 0.5 * (std::f64::consts::PI / 3.0).cos() / 0.4).sqrt();
    assert!((l.modes[0].natural_frequency - omega).abs() < 1e-9);
    // Hanging at rest: a stable equilibrium without any input.
    let hanging = "initial shoulder.q = 0, elbow.q = 0, shoulder.q' = 0, elbow.q' = 0 ;";
    let double = prepared(
        "double_pendulum",
        &[(
            "initial shoulder.q = 2, elbow.q = -1, shoulder.q' = 0.5, elbow.q' = 1 ;",
            hanging,
        )],
    );
    let point = OperatingPoint::Equilibrium;
    let rest = linearize(&double, &request(point, &[], &[])).unwrap();
    assert_eq!(rest.eigenvalues.len(), 4);
    real_parts_at_round_off(&rest);
}

/// A rotor on a torsion spring and damper: J θ'' = −k θ − c θ', ζ = c / (2 √(k J)),
/// ωn = √(k / J).
#[test]
fn damping_ratios_match_a_spring_and_damper() {
    let text = "import forces ;\n\
        let rotor = body mass = 2, iframe = 1, inertia = [0.3, 0.3, 0.5] end ;\n\
        join earth and rotor with revolute_spring_damper([0, 0, 1], 8, 0.6, 0) as spin ;\n\
        initial spin.q = 0.1 ;\n";
    let mechanism = lsdc::driver::compile_text("rotor.lsd", text, None, &Default::default())
        .mechanism
        .expect("elaborates");
    let prepared = lsdc::prepare::prepare(&mechanism, &[], &Default::default()).unwrap();
    let l = linearize(&prepared, &request(OperatingPoint::Initial, &[], &[])).unwrap();
    let (k, c, inertia) = (8.0_f64, 0.6, 0.5);
    for mode in &l.modes {
        assert!((mode.natural_frequency - (k / inertia).sqrt()).abs() < 1e-9);
        let ratio = mode.damping_ratio.unwrap();
        assert!(
            (ratio - c / (2.0 * (k * inertia).sqrt())).abs() < 1e-9,
            "{ratio}"
        );
    }
}

/// At the end of a run the model is the pendulum's at the angle reached.
#[test]
fn linearises_where_a_run_ends() {
    let prepared = prepared(
        "pendulum",
        &[(
            "duration = 5, output = 0.05",
            "duration = 0.7, output = 0.05",
        )],
    );
    let l = linearize(&prepared, &request(OperatingPoint::EndOfRun, &[], &[])).unwrap();
    assert_eq!((l.point, l.time), ("end of run", 0.7));
    let theta = l.state[0];
    assert!(theta < 1.0, "the pendulum fell from π/3: {theta}");
    assert!((l.a[(1, 0)] + 1.2 * 9.81 * 0.5 * theta.cos() / 0.4).abs() < 1e-9);
}

#[test]
fn differences_reach_round_off_on_a_smooth_function() {
    let x = [0.7, -1.3];
    let found = differences::jacobian(&x, &[0, 1], 1, |x| {
        Ok::<_, ()>(vec![x[0].sin() * x[1].exp()])
    })
    .unwrap();
    let exact = [x[0].cos() * x[1].exp(), x[0].sin() * x[1].exp()];
    for (c, exact) in exact.iter().enumerate() {
        let error = (found.value[(0, c)] - exact).abs();
        assert!(error < 1e-12, "column {c}: {error}");
        assert!(found.error[(0, c)] >= error && found.error[(0, c)] < 1e-10);
    }
}

/// The JSON keys, and a MATLAB script naming the states.
#[test]
fn command_writes_json_and_matlab() {
    let args = [
        "linearize",
        "examples/control/cart_pole.lsd",
        "--input",
        "rail.q",
    ];
    let (code, stdout, stderr) = lsdc(&[&args[..], &["--format", "json", "--modes"]].concat());
    assert_eq!(code, 0, "{stderr}");
    let value: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    for key in [
        "A",
        "B",
        "C",
        "D",
        "states",
        "inputs",
        "outputs",
        "eigenvalues",
        "modes",
    ] {
        assert!(value.get(key).is_some(), "{key} missing: {stdout}");
    }
    assert_eq!(value["A"].as_array().unwrap().len(), 4);
    assert_eq!(value["B"][3].as_array().unwrap().len(), 1);
    let (code, stdout, stderr) = lsdc(&[&args[..], &["--format", "matlab"]].concat());
    assert_eq!(code, 0, "{stderr}");
    assert!(
        stdout.contains("states = {'rail.q', 'hinge.q', 'rail.q''', 'hinge.q'''};"),
        "{stdout}"
    );
    assert!(stdout.contains("sys = ss(A, B, C, D,"), "{stdout}");
}

/// `--differenced` on a four-bar: the command's A is the exact one by default (its `method`
/// saying so, no reason to difference) and the differenced one with the flag, the two within
/// the differences' accuracy.
#[test]
fn command_differences_a_loop_on_request() {
    let args = [
        "linearize",
        "examples/four_bar.lsd",
        "--equilibrium",
        "--input",
        "crank.q",
        "--coordinate",
        "crank.q",
        "--format",
        "json",
    ];
    let run = |extra: &[&str]| {
        let (code, stdout, stderr) = lsdc(&[&args[..], extra].concat());
        assert_eq!(code, 0, "{stderr}");
        serde_json::from_str::<serde_json::Value>(&stdout).unwrap()
    };
    let (exact, differenced) = (run(&[]), run(&["--differenced"]));
    assert_eq!(exact["method"], LOOP_METHOD, "{exact}");
    assert!(exact["differenced_because"].is_null(), "{exact}");
    assert_ne!(differenced["method"], LOOP_METHOD, "{differenced}");
    let entries = |v: &serde_json::Value| -> Vec<f64> {
        (v["A"].as_array().unwrap().iter())
            .flat_map(|row| row.as_array().unwrap().iter().map(|x| x.as_f64().unwrap()))
            .collect()
    };
    let (a, b) = (entries(&exact), entries(&differenced));
    let largest = a.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    let apart = a
        .iter()
        .zip(&b)
        .fold(0.0_f64, |m, (x, y)| m.max((x - y).abs()));
    assert!(
        largest > 0.0 && apart <= 1e-6 * largest,
        "{a:?} against {b:?}"
    );
}

/// The LQR gain of examples/control/lqr_cart_pole.py is the one cart_pole_lqr.lsd applies,
/// its closed loop is stable (lsdc's own linearisation of it) and brings the pole up.
#[test]
fn cart_pole_balanced_by_the_lqr_gain_stays_up() {
    let python = std::process::Command::new("python3")
        .arg("--version")
        .output();
    if !python.is_ok_and(|o| o.status.success()) {
        return skip("python3 is not installed (examples/control/lqr_cart_pole.py needs it)");
    }
    let output = std::process::Command::new("python3")
        .args([
            "examples/control/lqr_cart_pole.py",
            "--lsdc",
            env!("CARGO_BIN_EXE_lsdc"),
        ])
        .output()
        .expect("python3 runs");
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let result: serde_json::Value = serde_json::from_slice(&output.stdout).unwrap();
    assert!(
        result["riccati_residual"].as_f64().unwrap() < 1e-8,
        "{result}"
    );
    let text = example_text("control/cart_pole_lqr", &[]);
    for line in result["lsd"].as_array().unwrap() {
        assert!(
            text.contains(line.as_str().unwrap()),
            "{line} not in cart_pole_lqr.lsd"
        );
    }
    let closed = prepared("control/cart_pole_lqr", &[]);
    let l = linearize(&closed, &request(OperatingPoint::Initial, &[], &[])).unwrap();
    assert!(
        l.eigenvalues.iter().all(|e| e.re < -0.5),
        "{:?}",
        l.eigenvalues
    );
    let simulation = crate::common::programs::simulated(&closed);
    let hinge = crate::common::programs::column(&simulation, "hinge.q");
    let rail = crate::common::programs::column(&simulation, "rail.q");
    let largest = simulation
        .samples
        .iter()
        .map(|s| s.coordinates[hinge].abs())
        .fold(0.0, f64::max);
    let last = simulation.samples.last().unwrap();
    assert!(largest <= 0.2 + 1e-12, "the pole fell: {largest}");
    assert!(last.coordinates[hinge].abs() < 1e-3 && last.coordinates[rail].abs() < 1e-2);
}

/// Each diagnostic of the command, as its golden file has it.
#[test]
fn diagnostics_match_their_golden_files() {
    check_command_goldens("linearize", "tests/golden/linearize", 5);
}

/// An input acts on a mechanism whose program applies no effort at all (where the equations
/// of motion skip the efforts): B = 1/J for a free rotor.
#[test]
fn inputs_act_without_any_effort_of_the_program() {
    let text = "import joints ;\n\
        let rotor = body mass = 2, iframe = 1, inertia = [0.3, 0.3, 0.5] end ;\n\
        join earth and rotor with revolute([0, 0, 1]) as spin ;\n";
    let mechanism = lsdc::driver::compile_text("rotor.lsd", text, None, &Default::default())
        .mechanism
        .expect("elaborates");
    let prepared = lsdc::prepare::prepare(&mechanism, &[], &Default::default()).unwrap();
    let l = linearize(
        &prepared,
        &request(OperatingPoint::Initial, &["spin.q"], &[]),
    )
    .unwrap();
    assert_eq!(l.b[(1, 0)], 2.0, "{}", l.b);
}
