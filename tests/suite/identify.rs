//! `lsdc identify` on simulated excitation trajectories (sums of sines): the two-link arm of
//! `examples/identify_arm.lsd` (inertial parameters and friction) and the UR5 of
//! `tests/fixtures/urdf` (its six moving links, 36 base parameters). The efforts are written by
//! `lsdc inverse` (RNEA through the run's constraint stack, not the regressor), the arm's
//! friction added in closed form, c q̇ + F_c sign q̇. From noise-free data every base parameter
//! is the program's to 1e-8 (relative to max(1, |value|)); with Gaussian noise of 1 % of each
//! effort's rms, every estimate lies within 3 of its standard deviations of the program's value.
//! Bad input: golden files `tests/golden/commands/identify_*`.

use std::path::Path;

use serde_json::Value;

use crate::common::noise::Gaussian;
use crate::common::{lsdc, path_text as path, scratch_dir};

/// The CSV `text` with each effort column (`*.drive_effort`) changed by `change(column name,
/// row's fields by name, effort)`.
fn with_efforts(
    text: &str,
    mut change: impl FnMut(&str, &dyn Fn(&str) -> f64, f64) -> f64,
) -> String {
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().expect("a header").split(',').collect();
    let mut out = header.join(",") + "\n";
    for line in lines {
        let fields: Vec<f64> = line
            .split(',')
            .map(|f| f.parse().expect("a number"))
            .collect();
        let by_name =
            |name: &str| fields[header.iter().position(|h| *h == name).expect("a column")];
        let row: Vec<String> = (header.iter().zip(&fields))
            .map(|(name, &x)| match name.ends_with(".drive_effort") {
                true => format!("{:e}", change(name, &by_name, x)),
                false => format!("{x:e}"),
            })
            .collect();
        out += &(row.join(",") + "\n");
    }
    out
}

/// Gaussian noise of `level` times each effort column's rms.
fn noisy(text: &str, level: f64) -> String {
    let header: Vec<&str> = text.lines().next().expect("a header").split(',').collect();
    let rows: Vec<Vec<f64>> = (text.lines().skip(1))
        .map(|l| l.split(',').map(|f| f.parse().expect("a number")).collect())
        .collect();
    let rms = |k: usize| (rows.iter().map(|r| r[k] * r[k]).sum::<f64>() / rows.len() as f64).sqrt();
    let mut gaussian = Gaussian(0x5eed_1234_abcd_0001);
    with_efforts(text, |name, _, x| {
        let k = header.iter().position(|h| *h == name).expect("a column");
        x + level * rms(k) * gaussian.next()
    })
}

/// `lsdc identify --format json` on `data`: the parameters' entries.
fn identified(program: &str, data: &Path, parameters: &[&str]) -> serde_json::Map<String, Value> {
    let mut args = vec![
        "-q",
        "identify",
        program,
        "--data",
        path(data),
        "--format",
        "json",
    ];
    args.push("--parameters");
    args.extend_from_slice(parameters);
    let (code, stdout, stderr) = lsdc(&args);
    assert_eq!(code, 0, "{stderr}{stdout}");
    let json: Value = serde_json::from_str(&stdout).expect("JSON");
    json["parameters"].as_object().expect("parameters").clone()
}

/// Every estimate against the program's value: within `tolerance` × max(1, |value|) when
/// `deviations` is `None`, within that many standard deviations otherwise. The largest measure.
fn check(
    parameters: &serde_json::Map<String, Value>,
    deviations: Option<f64>,
    tolerance: f64,
) -> f64 {
    let mut worst = 0.0f64;
    let mut estimated = 0;
    for (name, entry) in parameters {
        let Some(value) = entry["value"].as_f64() else {
            continue;
        };
        estimated += 1;
        let program = entry["model"].as_f64().expect("the program's value");
        let std = entry["std"].as_f64().expect("a standard deviation");
        let measure = match deviations {
            None => (value - program).abs() / program.abs().max(1.0),
            Some(_) => (value - program).abs() / std,
        };
        let limit = deviations.unwrap_or(tolerance);
        assert!(
            measure <= limit,
            "{name}: {value} against {program} (std {std}): {measure:e} > {limit}"
        );
        worst = worst.max(measure);
    }
    assert!(estimated > 0, "nothing estimated: {parameters:?}");
    worst
}

/// The arm's data: `lsdc inverse` on the program without its friction, which the test adds.
fn arm_data(dir: &Path) -> String {
    let text = std::fs::read_to_string("examples/identify_arm.lsd").expect("the example");
    let rigid = text
        .replace(
            "friction_revolute([0, 0, 1], 0.5, 0.2)",
            "revolute([0, 0, 1])",
        )
        .replace(
            "friction_revolute([0, 1, 0], 0.3, 0.1)",
            "revolute([0, 1, 0])",
        );
    assert_ne!(rigid, text, "the example's friction moved");
    let program = dir.join("rigid.lsd");
    std::fs::write(&program, rigid).expect("writable");
    let (code, efforts, stderr) = lsdc(&["-q", "inverse", path(&program)]);
    assert_eq!(code, 0, "{stderr}");
    let friction = [("shoulder", 0.5, 0.2), ("elbow", 0.3, 0.1)];
    with_efforts(&efforts, |name, row, x| {
        let (join, dry, viscous) = (friction.iter())
            .find(|(join, _, _)| name == format!("{join}.drive_effort"))
            .copied()
            .expect("a joint with friction");
        let rate = row(&format!("{join}.q'"));
        x + dry * rate.signum() + viscous * rate
    })
}

const ARM_PARAMETERS: [&str; 4] = ["upper.Izz", "fore", "shoulder", "elbow"];

#[test]
fn the_two_link_arm_is_identified_exactly_from_noise_free_data() {
    let dir = scratch_dir("identify-arm");
    let data = dir.join("arm.csv");
    std::fs::write(&data, arm_data(&dir)).expect("writable");
    let parameters = identified("examples/identify_arm.lsd", &data, &ARM_PARAMETERS);
    // 11 + 4 friction asked, 12 base parameters: fore.my, fore.mass and upper.Izz folded.
    let estimated = parameters
        .values()
        .filter(|e| e["value"].is_number())
        .count();
    assert_eq!(estimated, 12, "{parameters:#?}");
    let worst = check(&parameters, None, 1e-8);
    eprintln!("arm, noise-free: worst relative error {worst:.1e}");
}

#[test]
fn the_two_link_arm_is_identified_within_three_deviations_from_noisy_data() {
    let dir = scratch_dir("identify-arm-noisy");
    let data = dir.join("arm.csv");
    std::fs::write(&data, noisy(&arm_data(&dir), 0.01)).expect("writable");
    let parameters = identified("examples/identify_arm.lsd", &data, &ARM_PARAMETERS);
    let worst = check(&parameters, Some(3.0), 0.0);
    eprintln!("arm, 1 % noise: worst error {worst:.2} standard deviations");
}

const UR5_LINKS: [&str; 6] = [
    "shoulder_link",
    "upper_arm_link",
    "forearm_link",
    "wrist_1_link",
    "wrist_2_link",
    "wrist_3_link",
];

/// The UR5's efforts along sums of three sines per joint (10 s, 1001 samples): the motion
/// file with its exact rates and accelerations, through `lsdc inverse --motion`.
fn ur5_data(dir: &Path) -> String {
    let joints = [
        "shoulder_pan_joint",
        "shoulder_lift_joint",
        "elbow_joint",
        "wrist_1_joint",
        "wrist_2_joint",
        "wrist_3_joint",
    ];
    let mut header = vec!["time".to_string()];
    for suffix in ["", "'", "''"] {
        header.extend(joints.iter().map(|j| format!("{j}.q{suffix}")));
    }
    let mut text = header.join(",") + "\n";
    for k in 0..=1000 {
        let t = k as f64 * 0.01;
        // Per joint, its position, rate and acceleration.
        let motion: Vec<[f64; 3]> = (0..6)
            .map(|j| {
                let mut sum = [0.0; 3];
                for (i, frequency) in [0.1, 0.23, 0.37].iter().enumerate() {
                    let amplitude = 0.5 / (1.0 + i as f64) * (1.0 + 0.1 * j as f64);
                    let w = 2.0 * std::f64::consts::PI * frequency * (1.0 + 0.13 * j as f64);
                    let phase = w * t + 0.7 * j as f64 + 1.3 * i as f64;
                    sum[0] += amplitude * phase.sin();
                    sum[1] += amplitude * w * phase.cos();
                    sum[2] -= amplitude * w * w * phase.sin();
                }
                sum
            })
            .collect();
        let row: Vec<String> = std::iter::once(t)
            .chain((0..3).flat_map(|order| motion.iter().map(move |m| m[order])))
            .map(|x| format!("{x:e}"))
            .collect();
        text += &(row.join(",") + "\n");
    }
    let motion = dir.join("motion.csv");
    std::fs::write(&motion, text).expect("writable");
    let urdf = "tests/fixtures/urdf/ur5.urdf";
    let (code, efforts, stderr) = lsdc(&["-q", "inverse", urdf, "--motion", path(&motion)]);
    assert_eq!(code, 0, "{stderr}");
    efforts
}

#[test]
fn the_ur5_is_identified_exactly_from_noise_free_data_and_within_three_deviations_with_noise() {
    let dir = scratch_dir("identify-ur5");
    let efforts = ur5_data(&dir);
    let urdf = "tests/fixtures/urdf/ur5.urdf";
    let data = dir.join("ur5.csv");
    std::fs::write(&data, &efforts).expect("writable");
    let parameters = identified(urdf, &data, &UR5_LINKS);
    let estimated = parameters
        .values()
        .filter(|e| e["value"].is_number())
        .count();
    assert_eq!(estimated, 36, "the UR5's base parameters");
    let worst = check(&parameters, None, 1e-8);
    eprintln!("UR5, noise-free: worst relative error {worst:.1e}");
    std::fs::write(&data, noisy(&efforts, 0.01)).expect("writable");
    let parameters = identified(urdf, &data, &UR5_LINKS);
    let worst = check(&parameters, Some(3.0), 0.0);
    eprintln!("UR5, 1 % noise: worst error {worst:.2} standard deviations");
}

/// A parameter named itself that has no effect is refused by name; asked for through its
/// body's name it is reported without effect. The upper arm turns about the vertical through
/// its frame's origin: only its inertia about that axis acts on the measured efforts.
#[test]
fn parameters_without_effect_are_refused_by_name_or_reported() {
    let dir = scratch_dir("identify-refusal");
    let data = dir.join("arm.csv");
    std::fs::write(&data, arm_data(&dir)).expect("writable");
    let program = "examples/identify_arm.lsd";
    let args = [
        "identify",
        program,
        "--data",
        path(&data),
        "--parameters",
        "upper.mx",
        "fore.mass",
    ];
    let (code, _, stderr) = lsdc(&args);
    assert_eq!(code, 2, "{stderr}");
    assert!(
        stderr.contains("cannot identify `upper.mx`: it has no effect"),
        "{stderr}"
    );
    let args = [
        "-q",
        "identify",
        program,
        "--data",
        path(&data),
        "--parameters",
        "upper",
        "--format",
        "json",
    ];
    let (code, stdout, stderr) = lsdc(&args);
    assert_eq!(code, 0, "{stderr}");
    let json: Value = serde_json::from_str(&stdout).expect("JSON");
    assert_eq!(
        json["without_effect"].as_array().map(Vec::len),
        Some(9),
        "{json}"
    );
    assert!(
        json["parameters"]["upper.Izz"]["value"].is_number(),
        "{json}"
    );
}

/// The Delta's nacelle mass (the seed's mass estimator): `lsdc inverse` on the Delta with a
/// payload (the nacelle at 0.0616 kg, where the program says 0.0416) writes its arms' angles,
/// rates, accelerations and torques alone; `identify` closes the loops at the measured angles
/// and projects the regressor on them. On the reduced R-U-U model
/// (`examples/identify_delta.lsd`) and on the full one, two rods per chain on ball joints whose
/// spins carry no mass (`examples/identify_delta_full.lsd`). The two models' torques are the
/// same (each rod pair of the full model is a parallelogram that moves as the reduced model's
/// one rod), by loops of other joints; noise-free, the payload's mass to 1e-8; with 1 % noise
/// on each torque, within 3 deviations.
#[test]
fn the_delta_nacelle_mass_is_identified_from_its_arms_torques() {
    let dir = scratch_dir("identify-delta");
    let mut torques = Vec::new();
    for program in [
        "examples/identify_delta.lsd",
        "examples/identify_delta_full.lsd",
    ] {
        let args = ["-q", "inverse", program, "--set", "m_nacelle=0.0616"];
        let (code, efforts, stderr) = lsdc(&args);
        assert_eq!(code, 0, "{stderr}");
        let mut these = Vec::new();
        with_efforts(&efforts, |_, _, x| {
            these.push(x);
            x
        });
        torques.push(these);
        let header = efforts.lines().next().expect("a header");
        assert!(
            !header.contains("C1") && !header.contains("P1"),
            "only the arms are measured: {header}"
        );
        let truth = 0.0616;
        for (noise, limit) in [(0.0, None), (0.01, Some(3.0))] {
            let stem = program
                .trim_start_matches("examples/")
                .trim_end_matches(".lsd");
            let data = dir.join(format!("{stem}-{noise}.csv"));
            let text = match noise {
                0.0 => efforts.clone(),
                _ => noisy(&efforts, noise),
            };
            std::fs::write(&data, text).expect("writable");
            let parameters = identified(program, &data, &["nacelle.mass"]);
            let entry = &parameters["nacelle.mass"];
            let value = entry["value"].as_f64().expect("a value");
            let std = entry["std"].as_f64().expect("a std");
            assert_eq!(entry["model"].as_f64(), Some(0.0416));
            let error = (value - truth).abs();
            match limit {
                None => assert!(error <= 1e-8, "{program}: {value} against {truth}"),
                Some(deviations) => {
                    let message = format!("{program}: {value} ± {std} against {truth}");
                    assert!(error <= deviations * std, "{message}");
                    // The deviation is the noise's: a few percent of the payload at most.
                    assert!(std < 0.05 * truth && std > 1e-6 * truth, "{message}");
                }
            }
            eprintln!(
                "{program} nacelle mass, noise {noise}: {value} ± {std:.2e} against {truth} ({:.2} std)",
                error / std
            );
        }
    }
    let largest = torques[0].iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    let apart =
        (torques[0].iter().zip(&torques[1])).fold(0.0_f64, |m, (a, b)| m.max((a - b).abs()));
    assert!(
        torques[0].len() == torques[1].len() && apart <= 1e-10 * largest,
        "the full and the reduced Delta's torques differ by {apart:e} (of {largest})"
    );
}

/// What `identify` cannot read is refused, not guessed: a tree's ball joint (its orientation
/// would be measured as a quaternion) at the joint (E0870); on the full Delta with only one
/// arm's torque measured, the two other arms are motions with mass that the measured
/// coordinate leaves free (the rods' massless spins are not counted among them).
#[test]
fn a_trees_ball_joint_and_a_loops_free_motion_with_mass_are_refused() {
    let dir = scratch_dir("identify-refused");
    let unread = dir.join("unread.csv");
    let top = [
        "-q",
        "identify",
        "examples/heavy_top.lsd",
        "--data",
        path(&unread),
    ];
    let (code, _, stderr) = lsdc(&[&top[..], &["--parameters", "top.mass"]].concat());
    assert_ne!(code, 0);
    assert!(
        stderr.contains("E0870") && stderr.contains("`pivot`"),
        "{stderr}"
    );

    let program = "examples/identify_delta_full.lsd";
    let (code, efforts, stderr) = lsdc(&["-q", "inverse", program]);
    assert_eq!(code, 0, "{stderr}");
    let header: Vec<&str> = efforts
        .lines()
        .next()
        .expect("a header")
        .split(',')
        .collect();
    let kept: Vec<usize> = (0..header.len())
        .filter(|&k| !["A2.drive_effort", "A3.drive_effort"].contains(&header[k]))
        .collect();
    let one_arm: String = (efforts.lines())
        .map(|line| {
            let fields: Vec<&str> = line.split(',').collect();
            kept.iter()
                .map(|&k| fields[k])
                .collect::<Vec<_>>()
                .join(",")
                + "\n"
        })
        .collect();
    let data = dir.join("one-arm.csv");
    std::fs::write(&data, one_arm).expect("writable");
    let args = [
        "-q",
        "identify",
        program,
        "--data",
        path(&data),
        "--parameters",
        "nacelle.mass",
    ];
    let (code, _, stderr) = lsdc(&args);
    assert_ne!(code, 0);
    assert!(
        stderr.contains("the loops leave 2 motions with mass free"),
        "{stderr}"
    );
}
