//! `lsdc identify` on parameters that enter the motion nonlinearly, fitted by Levenberg–Marquardt
//! on the runs' sensitivities: the damped pendulum of `examples/identify_pendulum.lsd` (its
//! length L and damping c) and a spring-mass (its stiffness and its initial rate), each swing
//! simulated by `lsdc simulate` (a plain run, not the sensitivities) with known values, then
//! fitted from the program's wrong values. From noise-free angles the known values come back
//! to 1e-8; with seeded Gaussian noise of 1 % of the angle's rms, within 3 of the standard
//! deviations the fit reports. Parameters that act only together are refused by name (golden
//! file `tests/golden/commands/identify_unidentifiable`).

use std::path::Path;

use serde_json::Value;

use crate::common::noise::Gaussian;
use crate::common::{lsdc, path_text as path, scratch_dir};

/// `lsdc simulate` of `program` with `sets`, at a tolerance of 1e-12: the columns `time` and
/// `measured`, with Gaussian noise of `noise` times the measured column's rms.
fn measured(program: &str, sets: &[&str], measured: &str, noise: f64, file: &Path) {
    let mut args = vec!["-q", "simulate", program, "--tolerance", "1e-12"];
    for set in sets {
        args.extend(["--set", set]);
    }
    let (code, csv, stderr) = lsdc(&args);
    assert_eq!(code, 0, "{stderr}");
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().expect("a header").split(',').collect();
    let k = header
        .iter()
        .position(|h| *h == measured)
        .expect("the column");
    let rows: Vec<(f64, f64)> = lines
        .map(|l| {
            let fields: Vec<f64> = l.split(',').map(|f| f.parse().expect("a number")).collect();
            (fields[0], fields[k])
        })
        .collect();
    let rms = (rows.iter().map(|r| r.1 * r.1).sum::<f64>() / rows.len() as f64).sqrt();
    let mut gaussian = Gaussian(0x5eed_1234_abcd_0002);
    let mut text = format!("time,{measured}\n");
    for (t, y) in rows {
        text += &format!("{t:e},{:e}\n", y + noise * rms * gaussian.next());
    }
    std::fs::write(file, text).expect("writable");
}

/// `lsdc identify --format json` on `data`: the whole answer.
fn identified(program: &str, data: &Path, parameters: &[&str], sets: &[&str]) -> Value {
    let mut args = vec!["-q", "identify", program, "--data", path(data)];
    args.extend(["--tolerance", "1e-11", "--format", "json"]);
    for set in sets {
        args.extend(["--set", set]);
    }
    args.push("--parameters");
    args.extend_from_slice(parameters);
    let (code, stdout, stderr) = lsdc(&args);
    assert_eq!(code, 0, "{stderr}{stdout}");
    serde_json::from_str(&stdout).expect("JSON")
}

/// Each parameter's estimate against its known value: within `tolerance` × max(1, |value|)
/// when `deviations` is `None`, within that many standard deviations otherwise; every start
/// off its known value. The largest measure.
fn check(found: &Value, known: &[(&str, f64)], deviations: Option<f64>, tolerance: f64) -> f64 {
    let mut worst = 0.0f64;
    for &(name, truth) in known {
        let entry = &found["parameters"][name];
        let value = entry["value"].as_f64().expect("a value");
        let std = entry["std"].as_f64().expect("a standard deviation");
        let start = entry["model"].as_f64().expect("the start");
        assert!(
            (start - truth).abs() > 0.1 * truth.abs(),
            "{name} starts at its value"
        );
        let measure = match deviations {
            None => (value - truth).abs() / truth.abs().max(1.0),
            Some(_) => (value - truth).abs() / std,
        };
        let limit = deviations.unwrap_or(tolerance);
        assert!(
            measure <= limit,
            "{name}: {value} against {truth} (std {std}): {measure:e} > {limit}"
        );
        worst = worst.max(measure);
    }
    worst
}

const PENDULUM: &str = "examples/identify_pendulum.lsd";
const PENDULUM_VALUES: [(&str, f64); 2] = [("L", 0.8), ("c", 0.05)];

#[test]
fn the_pendulum_length_and_damping_are_recovered_exactly_from_noise_free_angles() {
    let dir = scratch_dir("identify-nonlinear-pendulum");
    let data = dir.join("swing.csv");
    measured(PENDULUM, &["L=0.8", "c=0.05"], "swing.q", 0.0, &data);
    let found = identified(PENDULUM, &data, &["L", "c"], &[]);
    let worst = check(&found, &PENDULUM_VALUES, None, 1e-8);
    eprintln!(
        "pendulum, noise-free: worst relative error {worst:.1e} in {} steps, {} runs",
        found["iterations"], found["runs"]
    );
}

#[test]
fn the_pendulum_length_and_damping_are_recovered_within_three_deviations_from_noisy_angles() {
    let dir = scratch_dir("identify-nonlinear-pendulum-noisy");
    let data = dir.join("swing.csv");
    measured(PENDULUM, &["L=0.8", "c=0.05"], "swing.q", 0.01, &data);
    let found = identified(PENDULUM, &data, &["L", "c"], &[]);
    let worst = check(&found, &PENDULUM_VALUES, Some(3.0), 0.0);
    // The deviations are those of the noise, not of round-off: a fit that reported huge ones
    // would pass any test of 3 deviations.
    for (name, value) in PENDULUM_VALUES {
        let std = found["parameters"][name]["std"].as_f64().expect("a std");
        assert!(
            std < 0.05 * value && std > 1e-6 * value,
            "{name}: std {std}"
        );
    }
    // The noise's σ is found from the residual: 1 % of the angle's rms, about 0.006 rad.
    let sigma = found["residual"]["sigmas"][0].as_f64().expect("weighted");
    assert!((0.003..0.012).contains(&sigma), "σ {sigma}");
    eprintln!("pendulum, 1 % noise: worst error {worst:.2} standard deviations");
}

/// A spring-mass of unknown stiffness, its initial rate unknown too (an initial value: its
/// sensitivity starts at a unit), from a wrong guess of both: the swing is simulated from the
/// program with its initial rate changed.
#[test]
fn a_spring_stiffness_and_an_initial_rate_are_recovered_exactly() {
    let program = "tests/golden/commands/identify_spring.lsd";
    let dir = scratch_dir("identify-nonlinear-spring");
    let text = std::fs::read_to_string(program).expect("the program");
    let truth = text.replace("slide.q' = -0.2", "slide.q' = -0.5");
    assert_ne!(truth, text, "the program's initial rate moved");
    let truth_program = dir.join("truth.lsd");
    std::fs::write(&truth_program, truth).expect("writable");
    let data = dir.join("slide.csv");
    measured(path(&truth_program), &["k=6.5"], "slide.q", 0.0, &data);
    let found = identified(program, &data, &["k", "slide.q'"], &[]);
    assert_eq!(found["parameters"]["slide.q'"]["kind"], "initial value");
    let worst = check(&found, &[("k", 6.5), ("slide.q'", -0.5)], None, 1e-8);
    eprintln!("spring, noise-free: worst relative error {worst:.1e}");
}
