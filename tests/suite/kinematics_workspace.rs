//! `lsdc workspace` on the Delta ISIR88: the volume of the nacelle's workspace over the arms'
//! box [0.6, 1.2]³ rad converging at second order as the grid is refined, against an
//! independent count of the positions whose closed-form inverse geometric model (the seed's,
//! §3.3, branch β − δ) falls in the box; and the commands' diagnostics against their golden
//! files (`tests/golden/commands/NAME.args` → `NAME.stderr`).

use lsdc::studies::kinematic_models::{Actuation, SINGULAR_TOLERANCE};
use lsdc::studies::workspace::{sample, Range};
use lsdc::studies::workspace_positions::{sample_positions, PositionBox};

use crate::common::lsdc;
use crate::kinematics_models::{delta, igm, Delta};

const L1: f64 = 0.200;
const L2: f64 = 0.300;
const R: f64 = 0.126;

/// Whether the seed's inverse geometric model reaches p with every arm in [low, high].
fn in_box(p: [f64; 3], low: f64, high: f64) -> bool {
    (0..3).all(|i| {
        let phi = 2.0 * std::f64::consts::PI * i as f64 / 3.0;
        let (s, c) = phi.sin_cos();
        let (x, y, z) = (c * p[0] + s * p[1], -s * p[0] + c * p[1], p[2]);
        let e2 = L2 * L2 - y * y;
        let ab = (z * z + (x - R).powi(2)).sqrt();
        let cosine = (L1 * L1 + ab * ab - e2) / (2.0 * L1 * ab);
        let alpha = (-z).atan2(x - R) - cosine.acos();
        e2 >= 0.0 && cosine.abs() <= 1.0 && (low..=high).contains(&alpha)
    })
}

/// The volume of the positions in the box, counted on a grid of n³ cells over a box holding
/// them (x, y in ±0.12 m, z in [−0.42, −0.14] m: the sampled points span ±0.09 and
/// [−0.41, −0.19]).
fn counted_volume(n: usize, low: f64, high: f64) -> f64 {
    let (lower, upper) = ([-0.12, -0.12, -0.42], [0.12, 0.12, -0.14]);
    let h: [f64; 3] = std::array::from_fn(|k| (upper[k] - lower[k]) / n as f64);
    let mut count = 0usize;
    for i in 0..n {
        for j in 0..n {
            for k in 0..n {
                let cell = [i, j, k];
                let p = std::array::from_fn(|d| lower[d] + (cell[d] as f64 + 0.5) * h[d]);
                count += usize::from(in_box(p, low, high));
            }
        }
    }
    count as f64 * h.iter().product::<f64>()
}

/// Every actuated coordinate over [low, high].
fn same_ranges(actuation: &Actuation, low: f64, high: f64) -> Vec<Range> {
    (actuation.names.iter())
        .map(|name| Range {
            name: name.clone(),
            low,
            high,
        })
        .collect()
}

#[test]
fn kinematics_workspace_volume_of_the_delta_converges_to_the_counted_volume() {
    let Delta {
        prepared,
        output,
        actuation,
    } = delta();
    let (low, high) = (0.6, 1.2);
    let ranges = same_ranges(&actuation, low, high);
    // Grids of 2³, 4³ and 8³ cells (measured: volumes 1.6563e-3, 1.6425e-3, 1.6391e-3 m³,
    // ratio 4.05, extrapolated 2.7e-4 from the count): the ratio and the extrapolation hold
    // from the coarsest grids, so the finer 16³ grid (4,096 closures, 9 % of the suite's run
    // with the test below) is not needed for them.
    let volumes: Vec<f64> = [2, 4, 8]
        .iter()
        .map(|&n| {
            let workspace = sample(
                &prepared,
                &actuation,
                &output,
                &ranges,
                n,
                SINGULAR_TOLERANCE,
            )
            .expect("sampled");
            assert_eq!(
                workspace.reachable,
                n * n * n,
                "every arm angle in the box assembles"
            );
            assert!(
                workspace.crossings.is_empty(),
                "no singular locus in the box"
            );
            workspace.volume
        })
        .collect();
    // The midpoint rule: the error falls fourfold when the cells halve.
    let ratio = (volumes[0] - volumes[1]) / (volumes[1] - volumes[2]);
    assert!((3.5..4.5).contains(&ratio), "{volumes:?}: ratio {ratio}");
    let extrapolated = volumes[2] + (volumes[2] - volumes[1]) / 3.0;
    let counted = counted_volume(100, low, high);
    let difference = (extrapolated - counted).abs() / counted;
    assert!(
        difference < 2e-3,
        "{volumes:?} → {extrapolated:e} against {counted:e}"
    );
}

/// Each `tests/golden/commands/NAME.args` (the arguments, one per line) gives the standard
/// error of `lsdc` in `NAME.stderr`; `UPDATE_GOLDEN=1` rewrites them.
#[test]
fn kinematics_commands_diagnostics_match_golden_files() {
    let update = std::env::var_os("UPDATE_GOLDEN").is_some();
    let mut inputs: Vec<_> = std::fs::read_dir("tests/golden/commands")
        .expect("tests/golden/commands")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "args"))
        .collect();
    inputs.sort();
    assert!(inputs.len() >= 4, "the commands' golden files are gone");
    let mut failures = Vec::new();
    for input in inputs {
        let text = std::fs::read_to_string(&input).expect("readable");
        let args: Vec<&str> = text.lines().filter(|l| !l.is_empty()).collect();
        let (code, _, stderr) = lsdc(&args);
        let actual = format!("exit code {code}\n{stderr}");
        let expected_path = input.with_extension("stderr");
        if update {
            std::fs::write(&expected_path, &actual).expect("writable");
            continue;
        }
        let expected = std::fs::read_to_string(&expected_path).unwrap_or_default();
        if actual != expected {
            failures.push(format!("--- {}\n{actual}", expected_path.display()));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The slider-crank of examples/slider_crank.lsd turning over: its dead centres, where crank
/// and rod align (crank.q a multiple of π), are type-1 passages with the crank actuated and the
/// slider's point as output (the crank turns, the slider stops), type-2 ones with the slider
/// actuated and the crank's tip as output (the crank turns, the slider is locked); located in time to a tenth of the sampling interval (0.05 s; 1e-3 s measured).
#[test]
fn kinematics_slider_crank_dead_centres_are_singular_passages_along_a_run() {
    let dir = std::env::temp_dir().join(format!("lsdc-kinematics-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("a temporary directory");
    let run = dir.join("run.csv");
    let run_path = run.to_str().expect("a path");
    let (code, _, stderr) = lsdc(&["simulate", "examples/slider_crank.lsd", "-o", run_path]);
    assert_eq!(code, 0, "{stderr}");
    let text = std::fs::read_to_string(&run).expect("samples");
    let rows: Vec<Vec<f64>> = (text.lines().skip(1))
        .map(|l| l.split(',').map(|f| f.parse().expect("a number")).collect())
        .collect();
    // The dead centres from the samples: crank.q (column 1) crossing kπ, interpolated.
    let mut crossings = Vec::new();
    for pair in rows.windows(2) {
        let (a, b) = (
            pair[0][1] / std::f64::consts::PI,
            pair[1][1] / std::f64::consts::PI,
        );
        if a.floor() != b.floor() {
            let k = a.floor().max(b.floor());
            crossings.push(pair[0][0] + (k - a) / (b - a) * (pair[1][0] - pair[0][0]));
        }
    }
    // A passage is located from two samples on each side: none within two of the run's ends.
    let last = rows.last().expect("samples")[0];
    crossings.retain(|t| *t > 0.1 && *t < last - 0.1);
    assert!(crossings.len() >= 10, "the crank turns over: {crossings:?}");
    // Crank actuated, the slider's point as output; slider actuated, the crank's tip (the
    // rod's frame) as output.
    for (actuated, point, kind) in [("crank.q", "s3", "type1"), ("slider.q", "s2", "type2")] {
        let (code, stdout, stderr) = lsdc(&[
            "kinematics",
            "examples/slider_crank.lsd",
            "--actuate",
            actuated,
            "--point",
            point,
            "--along",
            run_path,
            "--format",
            "json",
        ]);
        assert_eq!(code, 0, "{stderr}");
        let scan: serde_json::Value = serde_json::from_str(&stdout).expect("JSON");
        let events = scan["events"].as_array().expect("events");
        let times: Vec<f64> = events
            .iter()
            .map(|e| e["time"].as_f64().expect(""))
            .collect();
        assert_eq!(
            times.len(),
            crossings.len(),
            "{actuated}: {times:?} against {crossings:?}"
        );
        for (event, (time, expected)) in events.iter().zip(times.iter().zip(&crossings)) {
            assert_eq!(event["kind"], kind, "{event}");
            assert!(
                (time - expected).abs() < 5e-3,
                "{actuated}: {time} against {expected}"
            );
            let moved = event["motion"]["coordinates"].as_array().expect("named");
            assert!(moved.iter().any(|c| c == "crank.q"), "{event}");
            assert_eq!(event["motion"]["loops"][0], "pin", "{event}");
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// `lsdc workspace --positions` on the Delta: over a box of positions holding the arms' box
/// [0.6, 1.2]³ rad, a position is reachable exactly where the seed's closed-form inverse
/// geometric model (branch β − δ) puts every arm in the box, with the arms it gives to 1e-9
/// rad; the volume is the count of those cells.
#[test]
fn kinematics_workspace_over_positions_is_the_closed_form_inverse_model() {
    let Delta {
        prepared,
        output,
        actuation,
    } = delta();
    let (low, high) = (0.6, 1.2);
    let ranges = same_ranges(&actuation, low, high);
    let positions = PositionBox {
        lower: [-0.12, -0.12, -0.42],
        upper: [0.12, 0.12, -0.14],
    };
    let n = 8;
    let workspace = sample_positions(
        &prepared,
        &actuation,
        &output,
        &ranges,
        &positions,
        n,
        SINGULAR_TOLERANCE,
    )
    .expect("sampled");
    let mut counted = 0;
    for s in &workspace.samples {
        let expected = in_box(s.point, low, high);
        assert_eq!(s.reachable, expected, "{s:?}");
        if expected {
            counted += 1;
            let arms = igm(&nalgebra::Vector3::from(s.point));
            let reached = s.actuated.as_ref().expect("reached");
            for k in 0..3 {
                assert!(
                    (reached[k] - arms[k]).abs() < 1e-9,
                    "{s:?} against {arms:?}"
                );
            }
        }
    }
    assert!(counted > 40, "{counted} cells reachable");
    let cell: f64 = (0..3)
        .map(|d| (positions.upper[d] - positions.lower[d]) / n as f64)
        .product();
    assert!((workspace.volume - counted as f64 * cell).abs() < 1e-15);
}
