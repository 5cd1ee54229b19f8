//! Motions read from a file (`lsdc inverse --motion`): the Delta along a path of its nacelle
//! against an independent computation (bench/delta_path_torques.py, virtual power on the full
//! model from the seed's closed-form inverse geometric model), its run's energy balance; the
//! four-bar's crank from a file of angles against the closed form of virtual power, with rates
//! and accelerations from the file or from the quintic spline (its error measured); the laws
//! through knots; the refusals.

use lsdc::api::{Program, SettingsChanges};
use lsdc::kinematics::tabulated_law::TabulatedLaw;
use lsdc::simulate::run::Simulation;
use lsdc::studies::inverse::{from_run, InverseDynamics};
use lsdc::studies::kinematic_models::{actuation, Output, OutputKind};
use lsdc::studies::motion_file::{read_motion, Derivation};
use lsdc::studies::trajectory::{impose, Target};

use crate::drives::four_bar_torque_moving;

/// A CSV's header and rows, `#` lines skipped.
fn table(text: &str) -> (Vec<String>, Vec<Vec<f64>>) {
    let mut lines = text
        .lines()
        .filter(|l| !l.starts_with('#') && !l.is_empty());
    let header = lines.next().expect("header").split(',').map(String::from);
    let rows = lines
        .map(|l| l.split(',').map(|x| x.parse().expect("a number")).collect())
        .collect();
    (header.collect(), rows)
}

/// `program` driven along the motion file `motion` (a path of `frame` moved by `actuated`, or
/// coordinates): the run and its inverse dynamics.
fn driven_run(
    program: &str,
    motion: &str,
    frame: Option<(&str, &[&str])>,
) -> (Simulation, InverseDynamics) {
    let program = Program::from_file(program, &Default::default()).expect("loads");
    let mut prepared = program
        .prepare(&[], &SettingsChanges::default())
        .expect("prepares");
    let text = std::fs::read_to_string(motion).expect("motion file");
    let motion = read_motion(&text, "motion.csv", 0.0).expect("reads");
    match frame {
        None => impose(&mut prepared, &motion, Target::Coordinates).expect("imposes"),
        Some((name, actuated)) => {
            let mechanism = program.mechanism().expect("mechanism");
            let frame = lsdc::kinematics::frames::resolve(mechanism, &prepared.kinematics, name)
                .expect("frame");
            let output = Output {
                frame,
                kind: OutputKind::Point,
            };
            let names: Vec<String> = actuated.iter().map(|s| s.to_string()).collect();
            let actuation = actuation(&prepared, &names).expect("actuated");
            let target = Target::Frame {
                output: &output,
                actuation: &actuation,
            };
            impose(&mut prepared, &motion, target).expect("imposes")
        }
    };
    inverse_run(&prepared)
}

/// The run of `prepared`, which must not fail, and its inverse dynamics.
pub fn inverse_run(prepared: &lsdc::prepare::Prepared) -> (Simulation, InverseDynamics) {
    let simulation = lsdc::api::run(prepared, &mut |_| {});
    assert!(
        simulation.report.failure.is_none(),
        "{:?}",
        simulation.report.failure
    );
    let inverse = from_run(prepared, &simulation);
    (simulation, inverse)
}

/// The Delta's nacelle on a circle with a vertical harmonic (tests/fixtures/delta_path): the
/// arm angles, their rates and accelerations, and the three arm torques agree with the numpy
/// computation to 1e-8 of each column's largest value (measured: 1.6e-10 for the
/// accelerations, 8e-11 for the torques), and the run's energy balance, with the drives' work,
/// closes to 1e-9.
#[test]
fn the_delta_along_a_nacelle_path_needs_the_torques_of_virtual_power() {
    let (simulation, inverse) = driven_run(
        "examples/delta_isir88.lsd",
        "tests/fixtures/delta_path/path.csv",
        Some(("nacelle", &["A1.q", "A2.q", "A3.q"])),
    );
    let reference = std::fs::read_to_string("tests/fixtures/delta_path/torques.csv").unwrap();
    let (header, rows) = table(&reference);
    assert_eq!(inverse.samples.len(), rows.len());
    assert_eq!(inverse.driven, ["A1.q", "A2.q", "A3.q"]);
    let ours = |s: &lsdc::studies::inverse::InverseSample, column: &str| {
        let (name, order) = (column.trim_end_matches('\''), column.matches('\'').count());
        match column.strip_suffix(".drive_effort") {
            Some(join) => {
                s.efforts[inverse
                    .efforts
                    .iter()
                    .position(|e| e == column)
                    .expect(join)]
            }
            None => {
                let k = inverse.driven.iter().position(|d| d == name).expect(name);
                [&s.positions, &s.rates, &s.accelerations][order][k]
            }
        }
    };
    for (c, column) in header.iter().enumerate().skip(1) {
        let largest = rows.iter().map(|r| r[c].abs()).fold(0.0, f64::max);
        for (sample, row) in inverse.samples.iter().zip(&rows) {
            assert!((sample.time - row[0]).abs() < 1e-12);
            let error = (ours(sample, column) - row[c]).abs() / largest;
            assert!(error < 1e-8, "{column} at t = {}: {error:e}", row[0]);
        }
    }
    let balance = simulation.report.energy_balance.expect("work tracked");
    assert!(balance < 1e-9, "energy balance {balance:e}");
}

/// The four-bar's crank along θ(t) = 1 + 2πt + 0.3 sin 2πt, every 0.01 s for a second, read
/// from a file: with the exact rates and accelerations in the file, the torque is the closed
/// form of virtual power to 1e-9 of its largest value; from the positions alone, the quintic
/// spline's rates and accelerations give it to the error measured here (largest over the
/// turn, relative to the largest torque: 6.7e-3 at h = 0.01 and 3.3e-3 at h = 0.005, at the
/// ends, where the interpolating spline's natural end conditions (no third and fourth
/// derivatives) hold; 7.8e-7 and 5.5e-10 on the turn less its first and last tenths).
#[test]
fn the_four_bar_from_a_file_of_crank_angles_needs_the_closed_form_torque() {
    let law = |t: f64| {
        let w = 2.0 * std::f64::consts::PI;
        (
            1.0 + w * t + 0.3 * (w * t).sin(),
            w + 0.3 * w * (w * t).cos(),
            -0.3 * w * w * (w * t).sin(),
        )
    };
    let dir = std::env::temp_dir().join(format!("lsdc-trajectory-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let errors = |rows: usize, derivatives: bool| {
        let mut text = String::from(match derivatives {
            true => "time,crank.q,crank.q',crank.q''\n",
            false => "time,crank.q\n",
        });
        for k in 0..=rows {
            let t = k as f64 / rows as f64;
            let (q, w, a) = law(t);
            text += &match derivatives {
                true => format!("{t},{q},{w},{a}\n"),
                false => format!("{t},{q}\n"),
            };
        }
        let path = dir.join(format!("crank_{rows}_{derivatives}.csv"));
        std::fs::write(&path, text).unwrap();
        let (_, inverse) = driven_run("examples/four_bar.lsd", path.to_str().unwrap(), None);
        let expected: Vec<f64> = (inverse.samples.iter())
            .map(|s| {
                let (q, w, a) = law(s.time);
                four_bar_torque_moving(q, w, a)
            })
            .collect();
        let largest = expected.iter().map(|x| x.abs()).fold(0.0, f64::max);
        let error = |range: std::ops::Range<usize>| {
            (inverse.samples[range.clone()].iter().zip(&expected[range]))
                .map(|(s, e)| (s.efforts[0] - e).abs() / largest)
                .fold(0.0, f64::max)
        };
        let n = inverse.samples.len();
        (error(0..n), error(n / 10..n - n / 10))
    };
    let (exact, _) = errors(100, true);
    assert!(exact < 1e-9, "{exact:e}");
    let (whole, inside) = errors(100, false);
    let (whole_fine, inside_fine) = errors(200, false);
    eprintln!("spline: h = 0.01: {whole:e} ({inside:e} inside); h = 0.005: {whole_fine:e} ({inside_fine:e})");
    assert!(whole < 1e-2 && inside < 1e-6, "{whole:e} {inside:e}");
    assert!(whole_fine < 0.6 * whole, "{whole:e} → {whole_fine:e}");
    assert!(inside_fine < inside / 16.0, "{inside:e} → {inside_fine:e}");
    std::fs::remove_dir_all(&dir).ok();
}

/// A quintic is its own quintic Hermite interpolant: the law through knots of a quintic
/// polynomial gives its value, rate and acceleration everywhere, between knots and beyond them.
#[test]
fn a_law_through_knots_of_a_quintic_is_that_quintic() {
    let p = |t: f64| 1.0 - 2.0 * t + 0.5 * t.powi(3) - 0.25 * t.powi(4) + 0.1 * t.powi(5);
    let v = |t: f64| -2.0 + 1.5 * t.powi(2) - t.powi(3) + 0.5 * t.powi(4);
    let a = |t: f64| 3.0 * t - 3.0 * t.powi(2) + 2.0 * t.powi(3);
    let times = [0.0, 0.3, 1.0, 1.7, 2.0];
    let values = |f: &dyn Fn(f64) -> f64| times.iter().map(|&t| f(t)).collect::<Vec<_>>();
    let law = TabulatedLaw::through(&times, &values(&p), &values(&v), &values(&a)).unwrap();
    for k in 0..=50 {
        let t = -0.2 + 2.4 * k as f64 / 50.0;
        let [x, xd, xdd] = law.at(t);
        assert!((x - p(t)).abs() < 1e-13, "{t}");
        assert!((xd - v(t)).abs() < 1e-12, "{t}");
        assert!((xdd - a(t)).abs() < 1e-11, "{t}");
    }
    let refused = TabulatedLaw::through(&[0.0, 1.0, 1.0], &[0.0; 3], &[0.0; 3], &[0.0; 3]);
    assert!(refused.is_err());
}

/// A motion file's columns: rates and accelerations from their columns when given, from the
/// spline otherwise (said per column); a derivative without its positions, a time that does not
/// increase and a field that is not a number are refused with their line.
#[test]
fn a_motion_file_says_where_its_rates_come_from_and_refuses_bad_rows() {
    let rows: String = (0..8)
        .map(|k| format!("{},{},{}\n", k as f64 * 0.1, k, 2 * k))
        .collect();
    let motion = read_motion(&format!("# a comment\ntime,a.q,a.q'\n{rows}"), "m.csv", 0.0).unwrap();
    assert_eq!(motion.series.len(), 1);
    let series = &motion.series[0];
    assert_eq!(series.rates_from, Derivation::File);
    assert_eq!(series.accelerations_from, Derivation::Spline);
    assert_eq!(series.rates[3], 6.0);
    // The positions are linear in time: the spline's acceleration is zero.
    assert!(
        series.accelerations.iter().all(|a| a.abs() < 1e-9),
        "{:?}",
        series.accelerations
    );
    let refusal = |text: &str| read_motion(text, "m.csv", 0.0).unwrap_err();
    assert_eq!(
        refusal("time,a.q''\n0,1\n"),
        "m.csv:1: `a.q''` is a derivative of `a.q`, which is no column: give the positions"
    );
    assert_eq!(
        refusal("time,a.q\n0,1\n0.1,2\n0.1,3\n"),
        "m.csv:4: the time 0.1 does not follow 0.1: times must increase"
    );
    assert_eq!(
        refusal("time,a.q\n0,1\n0.1,x\n"),
        "m.csv:3: `x` is not a finite number"
    );
    assert_eq!(refusal("a.q\n1\n"), "m.csv:1: no `time` column");
}
