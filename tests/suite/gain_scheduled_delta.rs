//! The Delta seed's gain-scheduled law in closed loop (notes on the Delta seed, §6 "Gain
//! scheduling" and §5 R12, R13, R21, R23), `examples/control/gain_scheduled_delta.lsd`: state
//! feedback with integral action on the 12-state augmented system, its gains placed by
//! `examples/control/gain_schedule_delta.py` at operating points along the reference from
//! `lsdc linearize` of the program with its law switched off, interpolated in time. Here: the
//! eigenvalues of A_e − B_e K computed from the linearisation and the table (independently of
//! the placement), the tracking with every integrator that integrates states, and the seed's
//! robustness signals.

use nalgebra::DMatrix;

use crate::common::programs::{example_text, mechanism, run_example};
use crate::nonlinear_delta::{
    errors_under_the_seeds_signals, every_integrator_duration, largest_error, settings, FIRST_MOVE,
};
use crate::states::refused;
use lsdc::api::Override;
use lsdc::integrators::INTEGRATORS;
use lsdc::prepare::{prepare, Integrator, Settings};
use lsdc::simulate::run::Simulation;
use lsdc::studies::linearize::{linearize, Linearization, OperatingPoint, Request};

const EXAMPLE: &str = "control/gain_scheduled_delta";
/// The example's own settings and test signals, which the tests replace.
const SETTINGS: &str =
    "simulate duration = 1.5, output = 0.005, integrator = implicit, tolerance = 1e-8 end ;";
const SIGNALS: &str = "given A_in = 0, B_noise = 0 ;";
/// The poles the design places (1/s), each once per arm: the arms' three and the winding's.
const POLES: [f64; 4] = [-100.0, -120.0, -140.0, -2250.0];
const ARMS: [&str; 3] = ["leg[1]", "leg[2]", "leg[3]"];

/// An operating point of the example's gain table: its time, the reference's angles and rates
/// and the current I_0 there, and the gain K = [K_angle K_rate K_current K_integral] (3 × 12)
/// of the motors' voltages on (α, α', I, Z).
struct Point {
    time: f64,
    angles: [f64; 3],
    rates: [f64; 3],
    currents: [f64; 3],
    gain: DMatrix<f64>,
}

/// The numbers written in `text`, in order: those that a letter, digit or `_` does not
/// precede (`feedback0` is a name, not a number; `1 - x` is 1).
fn numbers(text: &str) -> Vec<f64> {
    let mut found = Vec::new();
    let mut token = String::new();
    let mut previous = ' ';
    for c in text.chars().chain([' ']) {
        let starts = token.is_empty()
            && (c.is_ascii_digit() || c == '-')
            && !(previous.is_alphanumeric() || previous == '_');
        let continues =
            !token.is_empty() && (c.is_ascii_digit() || matches!(c, '.' | 'e' | '-' | '+'));
        if starts || continues {
            token.push(c);
        } else if !token.is_empty() {
            // A minus sign alone is an operator.
            if token != "-" {
                found.push(token.parse().unwrap_or_else(|_| panic!("`{token}`")));
            }
            token.clear();
        }
        previous = c;
    }
    found
}

/// The example's gain table: per point a comment `(* k: t = …, angles […], rates […],
/// currents […] *)` and `let feedbackk = feedback(K_angle, K_rate, K_current, K_integral)`,
/// the blocks by rows.
fn gain_table() -> Vec<Point> {
    let text = example_text(EXAMPLE, &[]);
    let begin = text.find("(* The gain table").expect("the table's start");
    let end = text.find("(* End of the gain table. *)").expect("its end");
    let points = text[begin..end].split("\n(* ").skip(1);
    (points.enumerate())
        .map(|(k, point)| {
            let n = numbers(point);
            assert_eq!((n.len(), n[0]), (47, k as f64), "point {k}: {point}");
            let triple = |at: usize| [n[at], n[at + 1], n[at + 2]];
            let mut gain = DMatrix::zeros(3, 12);
            for block in 0..4 {
                for row in 0..3 {
                    for column in 0..3 {
                        gain[(row, 3 * block + column)] = n[11 + 9 * block + 3 * row + column];
                    }
                }
            }
            Point {
                time: n[1],
                angles: triple(2),
                rates: triple(5),
                currents: triple(8),
                gain,
            }
        })
        .collect()
}

/// The interpolation's weight of each point of the table, by the numbers of its line in the
/// definition of `schedule`: `(1 - linear(time, t0, 0, t1, 1)) * f0`, `hat(t0, t1, t2) * f1`,
/// …, `linear(time, tm, 0, tn, 1) * fn`.
fn schedule_weights() -> Vec<Vec<f64>> {
    let text = example_text(EXAMPLE, &[]);
    let begin = text.find("let schedule(").expect("the schedule");
    let end = begin + text[begin..].find(" ;").expect("its end");
    (text[begin..end].lines().skip(1)).map(numbers).collect()
}

/// The example's references at t (out by 0.3, −0.1, 0.2 rad from 40° on quintics in 0.2 to
/// 0.7 s, back in 1.0 to 1.5 s): angles, rates and accelerations, from the quintic's closed
/// form 10τ³ − 15τ⁴ + 6τ⁵.
fn reference(t: f64) -> [[f64; 3]; 3] {
    let quintic = |t0: f64, t1: f64, d: f64| {
        let span = t1 - t0;
        let s = ((t - t0) / span).clamp(0.0, 1.0);
        [
            d * (10.0 * s.powi(3) - 15.0 * s.powi(4) + 6.0 * s.powi(5)),
            d * (30.0 * s.powi(2) - 60.0 * s.powi(3) + 30.0 * s.powi(4)) / span,
            d * (60.0 * s - 180.0 * s.powi(2) + 120.0 * s.powi(3)) / span.powi(2),
        ]
    };
    let mut law = [[0.0; 3]; 3];
    for (arm, d) in [0.3, -0.1, 0.2].into_iter().enumerate() {
        let (out, back) = (quintic(0.2, 0.7, d), quintic(1.0, 1.5, -d));
        for derivative in 0..3 {
            law[derivative][arm] = out[derivative] + back[derivative];
        }
        law[0][arm] += 40f64.to_radians();
    }
    law
}

/// `lsdc linearize` of the example with its law off (`law = 0`) at a point's state, its
/// voltages the inputs: the seed's A_e and B_e.
fn plant_at(mechanism: &lsdc::elab::Mechanism, point: &Point) -> Linearization {
    let mut values = vec![Override {
        name: "law".to_string(),
        value: 0.0,
    }];
    for (arm, name) in ARMS.iter().enumerate() {
        for (unknown, value) in [
            ("alpha0", point.angles[arm]),
            ("rate0", point.rates[arm]),
            ("current0", point.currents[arm]),
        ] {
            values.push(Override {
                name: format!("{name}:{unknown}"),
                value,
            });
        }
    }
    let prepared = prepare(mechanism, &values, &Settings::default())
        .unwrap_or_else(|d| panic!("{:?}", d.iter().map(|d| &d.message).collect::<Vec<_>>()));
    let request = Request {
        point: OperatingPoint::Initial,
        inputs: ARMS.iter().map(|a| format!("{a}:voltage_input")).collect(),
        coordinates: ARMS.iter().map(|a| format!("{a}:A.q")).collect(),
    };
    linearize(&prepared, &request).expect("linearises")
}

/// The plant's block of a linearisation of the example with its law off: A and B on the plant's
/// `states` (α, α', I, Z per arm), the observer's states (held with the law off) left out. The
/// plant does not read them (its rows of A are zero on their columns, checked), so that the
/// block is the seed's A_e and B_e.
fn plant_block(plant: &Linearization, states: &[String]) -> (DMatrix<f64>, DMatrix<f64>) {
    let index = |name: &String| {
        (plant.states.iter().position(|s| s == name)).unwrap_or_else(|| panic!("no state {name}"))
    };
    let rows: Vec<usize> = states.iter().map(index).collect();
    let others: Vec<usize> = (0..plant.states.len())
        .filter(|k| !rows.contains(k))
        .collect();
    let a = plant.a.select_rows(&rows);
    assert_eq!(
        a.select_columns(&others).amax(),
        0.0,
        "the plant reads the observer"
    );
    (a.select_columns(&rows), plant.b.select_rows(&rows))
}

/// `matrix` balanced: D⁻¹ M D with D diagonal, in powers of 2 (exact), so that each row and
/// column of the same index have about the same norm (Parlett & Reinsch, "Balancing a matrix
/// for calculation of eigenvalues and eigenvectors", Numer. Math. 13, 1969; LAPACK's dgebal).
/// A_e − B_e K spans 1 to 3e7 (angles, rates, currents and integrals in their units); balanced,
/// 1 to 3e3, so that its norm weighs every state alike.
fn balanced(mut matrix: DMatrix<f64>) -> DMatrix<f64> {
    let n = matrix.nrows();
    let mut done = false;
    while !done {
        done = true;
        for i in 0..n {
            let off_diagonal = |values: Vec<f64>| -> f64 {
                (values.iter().enumerate())
                    .filter(|&(j, _)| j != i)
                    .map(|(_, x)| x.abs())
                    .sum()
            };
            let column = off_diagonal(matrix.column(i).iter().copied().collect());
            let row = off_diagonal(matrix.row(i).iter().copied().collect());
            if column == 0.0 || row == 0.0 {
                continue;
            }
            let (mut scaled, mut factor) = (column, 1.0);
            while scaled < row / 2.0 {
                (scaled, factor) = (scaled * 4.0, factor * 2.0);
            }
            while scaled > row * 2.0 {
                (scaled, factor) = (scaled / 4.0, factor / 2.0);
            }
            if (scaled + row) / factor < 0.95 * (column + row) {
                done = false;
                matrix.row_mut(i).scale_mut(1.0 / factor);
                matrix.column_mut(i).scale_mut(factor);
            }
        }
    }
    matrix
}

/// How nearly each of `POLES` is an eigenvalue of `closed` three times over: with M the
/// balanced matrix and s₁ ≥ … ≥ s₁₂ the singular values of M − p I, (s₁₀/s₁, s₉/s₁). M − p I
/// is within s₁₀ (2-norm) of a matrix of rank 9 (Eckart–Young), so that p is an eigenvalue of
/// geometric multiplicity 3 of a matrix within s₁₀ of M: s₁₀/s₁ is the placement's backward
/// error, s₉/s₁ how far a fourth eigenvalue is. A check of the spectrum by singular values
/// (nalgebra's SVD, which always converges here) rather than by the QR iteration, which
/// nalgebra's real Schur decomposition does not bring to convergence on some of these triple
/// eigenvalues at tolerances below 1e-10.
fn backward_errors(closed: &DMatrix<f64>) -> Vec<(f64, f64)> {
    let balanced = balanced(closed.clone());
    let identity = DMatrix::<f64>::identity(12, 12);
    (POLES.iter())
        .map(|&pole| {
            let shifted = &balanced - &identity * pole;
            let svd = lsdc::linalg::svd(shifted, false, false).expect("an SVD");
            let mut values: Vec<f64> = svd.singular_values.iter().copied().collect();
            values.sort_by(|a, b| b.total_cmp(a));
            (values[9] / values[0], values[8] / values[0])
        })
        .collect()
}

/// At each of the table's 22 operating points (on the reference: its angles and rates within
/// 1e-12 of the quintics' closed forms, its current I_0 giving the reference's accelerations
/// within 1e-9 rad/s²), the linear model `lsdc linearize` gives is the seed's augmented system
/// (12 × 12, R13: the states α, α', I, then the integrals Z' = α − r, their rows [I 0 0 0])
/// and each placed pole is an eigenvalue of A_e − B_e K three times over, the four poles
/// making its twelve: measured, a backward error of at most 2.4e-12 (relative to the balanced
/// matrix's norm), the next singular value at least 4.4e-2 of it. The law's weights interpolate
/// between the table's points, each weight rising from the point before and falling to the
/// point after. The schedule is needed: with the first point's gains at the move's far end
/// (t = 0.7 s) the backward errors are 9.9e-4 to 3.1e-2.
#[test]
fn at_every_operating_point_the_closed_loop_has_the_placed_poles() {
    let mechanism = mechanism(EXAMPLE, &[]);
    let table = gain_table();
    assert_eq!(table.len(), 22);
    let states: Vec<String> = ["A.q", "A.q'", "current", "integral"]
        .iter()
        .flat_map(|state| ARMS.iter().map(move |arm| format!("{arm}:{state}")))
        .collect();
    let times: Vec<f64> = table.iter().map(|p| p.time).collect();
    let weights = schedule_weights();
    let last = times.len() - 1;
    assert_eq!(weights[0], [1.0, times[0], 0.0, times[1], 1.0]);
    for k in 1..last {
        assert_eq!(weights[k], times[k - 1..=k + 1]);
    }
    assert_eq!(weights[last], [times[last - 1], 0.0, times[last], 1.0]);
    let plants: Vec<Linearization> = table.iter().map(|p| plant_at(&mechanism, p)).collect();
    let mut integrals = DMatrix::zeros(3, 12);
    integrals.view_mut((0, 0), (3, 3)).fill_with_identity();
    let (mut largest, mut smallest_gap) = (0.0_f64, f64::INFINITY);
    for (point, plant) in table.iter().zip(&plants) {
        let [angles, rates, accelerations] = reference(point.time);
        for arm in 0..3 {
            assert!(
                (point.angles[arm] - angles[arm]).abs() < 1e-12
                    && (point.rates[arm] - rates[arm]).abs() < 1e-12,
                "t = {}: not on the reference",
                point.time
            );
            let missed = (plant.accelerations[arm] - accelerations[arm]).abs();
            assert!(
                missed < 1e-9,
                "t = {}: I_0 misses by {missed:e}",
                point.time
            );
        }
        let (a, b) = plant_block(plant, &states);
        let rows = (a.rows(9, 3) - &integrals).amax() + b.rows(9, 3).amax();
        assert!(
            rows < 1e-12,
            "t = {}: the integrals' rows {rows:e}",
            point.time
        );
        for (error, fourth) in backward_errors(&(&a - &b * &point.gain)) {
            largest = largest.max(error);
            smallest_gap = smallest_gap.min(fourth);
        }
    }
    assert!(
        largest < 1e-11 && smallest_gap > 1e-2,
        "{largest:e}, {smallest_gap:e}"
    );
    let (far, far_plant) = (&table[10], &plants[10]);
    assert_eq!(far.time, 0.7);
    let (a, b) = plant_block(far_plant, &states);
    let frozen = backward_errors(&(&a - &b * &table[0].gain));
    assert!(frozen.iter().all(|&(error, _)| error > 1e-6), "{frozen:?}");
}

/// A run of the example with `replacements`, its `simulate` declaration replaced by `settings`,
/// RK4's step 0.2 ms: within its stability for the observer's poles, 8000 /s (λh = 1.6 against
/// 2.78).
fn scheduled(replacements: &[(&str, &str)], integrator: &Integrator, duration: f64) -> Simulation {
    run_example(
        EXAMPLE,
        SETTINGS,
        replacements,
        &settings(integrator, duration),
    )
}

/// The arms follow their quintic laws out (0.2 to 0.7 s) and back (1.0 to 1.5 s), through the
/// whole schedule, with `implicit`, and through the first move with every other integrator
/// that integrates states: measured 1.4e-5 rad of the arm while the currents build from zero in
/// the first milliseconds, 1.1e-6 after 0.1 s (the feed-forward from the inverse dynamics does
/// most of it); the seed reports ~1e-3 (R12). The runs' errors after 0.1 s of the first move
/// agree within 1e-9 rad.
#[test]
fn gain_scheduling_tracks_the_delta_references_with_every_integrator() {
    let mut first: Option<(&str, f64)> = None;
    for entry in INTEGRATORS {
        let duration = every_integrator_duration(&entry.integrator, 1.5);
        let simulation = scheduled(&[], &entry.integrator, duration);
        if refused(&simulation, &entry.integrator) {
            continue;
        }
        let whole = largest_error(&simulation, 0.0, f64::INFINITY);
        let settled = largest_error(&simulation, 0.1, f64::INFINITY);
        assert!(
            whole < 2e-5 && settled < 2e-6,
            "{}: {whole:e}, after 0.1 s {settled:e}",
            entry.name
        );
        let in_the_first_move = largest_error(&simulation, 0.1, FIRST_MOVE);
        let (name, error) = *first.get_or_insert((entry.name, in_the_first_move));
        assert!(
            (in_the_first_move - error).abs() < 1e-9,
            "{}: {in_the_first_move:e}, {name}: {error:e}",
            entry.name
        );
    }
}

/// The seed's R23 test (R21's signals at A = B = 5: a 5 V step on every motor's voltage at
/// 0.1 s, a 10 Hz sinusoid of 5 V from 0.5 s, the noise 5 sin(500 t) on the motor's angle,
/// speed and current from 1.2 s), with the implicit method. Reading the observer of
/// `examples/lib/delta_observer.lsd`, its disturbance's estimate taken off the voltage, the law
/// leaves 1.6e-4 rad of the arm (the step), 1.6e-4 (the sinusoid) and 2.6e-3 (the noise with the
/// sinusoid): all rejected to the seed's order, 1e-3. Reading its sensors (`observer = 0`): the
/// step 3.6e-3, the sinusoid 6.0e-3, but the noise 0.12 rad, which the law feeds back through the
/// arms' poles at 100 to 140 /s (5 rad of the motor is 0.42 rad of the arm).
#[test]
fn gain_scheduling_with_its_observer_rejects_the_seeds_disturbances_and_noise() {
    let signals = (SIGNALS, "given A_in = 5, B_noise = 5 ;");
    let sensors = ("given observer = 1 ;", "given observer = 0 ;");
    let [step, sinusoid, noise] =
        errors_under_the_seeds_signals(&scheduled(&[signals], &Integrator::Implicit, 1.5));
    assert!(
        step < 3e-4 && sinusoid < 3e-4 && noise < 4e-3,
        "step {step:e}, sinusoid {sinusoid:e}, noise {noise:e}"
    );
    let sensed = scheduled(&[signals, sensors], &Integrator::Implicit, 1.5);
    let [sensed_step, sensed_sinusoid, sensed_noise] = errors_under_the_seeds_signals(&sensed);
    assert!(
        sensed_step < 4e-3 && sensed_sinusoid < 7e-3 && sensed_noise > 5e-2 && sensed_noise < 0.2,
        "sensors: step {sensed_step:e}, sinusoid {sensed_sinusoid:e}, noise {sensed_noise:e}"
    );
}
