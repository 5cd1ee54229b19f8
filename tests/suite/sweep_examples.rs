//! The worked examples of `lsdc sweep`: the four-bar's Grashof classes mapped over its crank's
//! and rocker's lengths (`examples/four_bar_grashof.lsd`) against Grashof's criterion, and the
//! Delta's nacelle under link-length and pivot tolerances (`examples/delta_tolerances.lsd`)
//! against the closed-form forward kinematics of the parallelogram Delta (three spheres).

use std::f64::consts::PI;

use crate::common::lsdc;

/// The rows of a CSV text as (header, rows of fields).
fn read_rows(csv: &str) -> (Vec<String>, Vec<Vec<String>>) {
    let mut lines = csv.lines();
    let header = lines
        .next()
        .expect("header")
        .split(',')
        .map(String::from)
        .collect();
    // A failure message may hold quoted commas: the columns after `failure` are read only in
    // rows without one.
    let rows = lines
        .map(|l| l.split(',').map(String::from).collect())
        .collect();
    (header, rows)
}

fn field<'a>(header: &[String], row: &'a [String], name: &str) -> &'a str {
    let k = header
        .iter()
        .position(|h| h == name)
        .unwrap_or_else(|| panic!("no column {name}"));
    &row[k]
}

fn number(header: &[String], row: &[String], name: &str) -> f64 {
    field(header, row, name)
        .parse()
        .unwrap_or_else(|_| panic!("{name}: {row:?}"))
}

#[test]
fn the_four_bar_sweep_maps_grashof_classes() {
    let dir = std::env::temp_dir().join(format!("lsdc-sweep-grashof-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("directory");
    let out = dir.join("grashof.csv").display().to_string();
    let (code, _, stderr) = lsdc(&[
        "sweep",
        "examples/four_bar_grashof.lsd",
        "--grid",
        "l1=0.55:4.55:9",
        "--grid",
        "l3=0.8:6.8:7",
        "-o",
        &out,
    ]);
    assert_eq!(code, 0, "{stderr}");
    let csv = std::fs::read_to_string(&out).expect("written");
    let (header, rows) = read_rows(&csv);
    let (ground, coupler) = (4.0, 4.5);
    let mut classes = std::collections::BTreeMap::new();
    for row in &rows {
        let (crank, rocker) = (number(&header, row, "l1"), number(&header, row, "l3"));
        let mut lengths = [ground, crank, coupler, rocker];
        lengths.sort_by(f64::total_cmp);
        let grashof = lengths[0] + lengths[3] < lengths[1] + lengths[2];
        let shortest = [ground, crank, coupler, rocker]
            .into_iter()
            .fold(f64::INFINITY, f64::min);
        let class = match (grashof, shortest) {
            (true, s) if s == crank => "crank-rocker",
            (true, s) if s == ground => "double-crank",
            (true, s) if s == coupler => "double-rocker",
            (true, _) => "rocker-crank",
            (false, _) => "triple-rocker",
        };
        *classes.entry(class).or_insert(0) += 1;
        let status = field(&header, row, "status");
        let turns = matches!(class, "crank-rocker" | "double-crank");
        assert_eq!(
            status == "ok",
            turns,
            "l1 = {crank}, l3 = {rocker} ({class}): {row:?}"
        );
        if turns {
            // The crank turned once: the rocker oscillates, or turns once with it.
            let range = |name: &str| {
                number(&header, row, &format!("max({name})"))
                    - number(&header, row, &format!("min({name})"))
            };
            assert!((range("crank.q") - 2.0 * PI).abs() < 1e-9);
            let rocker_turns = range("rocker.q") > PI;
            assert_eq!(
                rocker_turns,
                class == "double-crank",
                "{class}: rocker range {}",
                range("rocker.q")
            );
            if rocker_turns {
                assert!(
                    (range("rocker.q") - 2.0 * PI).abs() < 0.2,
                    "{}",
                    range("rocker.q")
                );
            }
        }
    }
    // Every class the lengths allow is met (the coupler, 4.5, is never the shortest here).
    for class in [
        "crank-rocker",
        "double-crank",
        "rocker-crank",
        "triple-rocker",
    ] {
        assert!(classes.contains_key(class), "no {class} in {classes:?}");
    }
}

/// The nacelle's point P of a parallelogram Delta whose rod pairs are equal (the nacelle then
/// only translates): the lower intersection of the three spheres of radius `rods[i]` about
/// the elbows C_i (trilateration).
fn delta_nacelle(
    angles: [f64; 3],
    arms: [f64; 3],
    rods: [f64; 3],
    radii: [f64; 3],
    offsets: [f64; 3],
) -> [f64; 3] {
    let elbow = |i: usize| {
        let phi = 2.0 * PI * i as f64 / 3.0;
        let local = [
            radii[i] + arms[i] * angles[i].cos(),
            offsets[i],
            -arms[i] * angles[i].sin(),
        ];
        [
            phi.cos() * local[0] - phi.sin() * local[1],
            phi.sin() * local[0] + phi.cos() * local[1],
            local[2],
        ]
    };
    let (c1, c2, c3) = (elbow(0), elbow(1), elbow(2));
    let sub = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let scale = |a: [f64; 3], s: f64| [a[0] * s, a[1] * s, a[2] * s];
    let cross = |a: [f64; 3], b: [f64; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let d = dot(sub(c2, c1), sub(c2, c1)).sqrt();
    let ex = scale(sub(c2, c1), 1.0 / d);
    let i = dot(ex, sub(c3, c1));
    let ey_raw = sub(sub(c3, c1), scale(ex, i));
    let ey = scale(ey_raw, 1.0 / dot(ey_raw, ey_raw).sqrt());
    let ez = cross(ex, ey);
    let j = dot(ey, sub(c3, c1));
    let x = (rods[0].powi(2) - rods[1].powi(2) + d * d) / (2.0 * d);
    let y = (rods[0].powi(2) - rods[2].powi(2) + i * i + j * j) / (2.0 * j) - i * x / j;
    let z = (rods[0].powi(2) - x * x - y * y).sqrt();
    let candidates =
        [1.0, -1.0].map(|sign| [0, 1, 2].map(|k| c1[k] + x * ex[k] + y * ey[k] + sign * z * ez[k]));
    match candidates[0][2] < candidates[1][2] {
        true => candidates[0],
        false => candidates[1],
    }
}

#[test]
fn the_delta_nacelle_under_tolerances_meets_the_closed_form() {
    let dir = std::env::temp_dir().join(format!("lsdc-sweep-delta-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("directory");
    // Runs with equal rods in each pair (the parallelogram kept) and every other value moved
    // by up to a millimetre: the closed form holds exactly.
    let names = "A1.q,A2.q,A3.q,la1,la2,la3,lr1p,lr1m,lr2p,lr2m,lr3p,lr3m,r1,r2,r3,e1,e2,e3";
    let runs = [
        [
            40.0f64.to_radians(),
            40.0f64.to_radians(),
            40.0f64.to_radians(),
            0.2,
            0.2,
            0.2,
            0.3,
            0.3,
            0.3,
            0.3,
            0.3,
            0.3,
            0.126,
            0.126,
            0.126,
            0.0,
            0.0,
            0.0,
        ],
        [
            0.5, 0.9, 0.7, 0.2004, 0.1995, 0.2001, 0.3008, 0.3008, 0.2993, 0.2993, 0.3, 0.3,
            0.1262, 0.1259, 0.126, 0.0005, -0.0003, 0.0,
        ],
        [
            1.0, 0.4, 0.6, 0.1999, 0.2, 0.2009, 0.2999, 0.2999, 0.3002, 0.3002, 0.2996, 0.2996,
            0.1255, 0.1266, 0.1261, -0.001, 0.0002, 0.0008,
        ],
    ];
    let mut list = format!("{names}\n");
    for run in &runs {
        list += &run
            .iter()
            .map(|x| format!("{x:e}"))
            .collect::<Vec<_>>()
            .join(",");
        list.push('\n');
    }
    let values = dir.join("pairs.csv");
    std::fs::write(&values, list).expect("written");
    let out = dir.join("pairs.out.csv").display().to_string();
    let (code, _, stderr) = lsdc(&[
        "sweep",
        "examples/delta_tolerances.lsd",
        "--values",
        &values.display().to_string(),
        "-o",
        &out,
    ]);
    assert_eq!(code, 0, "{stderr}");
    let (header, rows) = read_rows(&std::fs::read_to_string(&out).expect("written"));
    for (run, row) in runs.iter().zip(&rows) {
        assert_eq!(field(&header, row, "status"), "ok", "{row:?}");
        let three = |k: usize| [run[k], run[k + 1], run[k + 2]];
        let rods = [run[6], run[8], run[10]];
        let expected = delta_nacelle(three(0), three(3), rods, three(12), three(15));
        for (axis, value) in ["x", "y", "z"].into_iter().zip(expected) {
            let found = number(&header, row, &format!("end(nacelle.{axis})"));
            assert!(
                (found - value).abs() < 1e-9,
                "{axis}: {found} against {value}"
            );
            // At rest from the start: the extremes are the end.
            assert_eq!(found, number(&header, row, &format!("min(nacelle.{axis})")));
        }
    }
    // The nominal Delta at 40°: the seed notes' P = (0, 0, -0.2382954).
    let nominal = number(&header, &rows[0], "end(nacelle.z)");
    assert!((nominal + 0.238_295_4).abs() < 1e-7, "{nominal}");
    // Rods of a pair unequal: the nacelle tilts (its quaternion leaves the identity) and every
    // run of a Monte Carlo over the workspace assembles, its error of the order of the
    // tolerances (2e-5 m on 18 values; amplified by the parallel structure, not beyond 1 mm).
    let tolerances: Vec<String> = ["la1", "la2", "la3"]
        .map(|n| format!("{n}=normal(0.2, 2e-5)"))
        .into_iter()
        .chain(
            ["lr1p", "lr1m", "lr2p", "lr2m", "lr3p", "lr3m"]
                .map(|n| format!("{n}=normal(0.3, 2e-5)")),
        )
        .chain(["r1", "r2", "r3"].map(|n| format!("{n}=normal(0.126, 2e-5)")))
        .chain(["e1", "e2", "e3"].map(|n| format!("{n}=normal(0, 2e-5)")))
        .chain(["A1.q", "A2.q", "A3.q"].map(|n| format!("{n}=uniform(0.7, 1.0)")))
        .collect();
    let mut args = vec![
        "sweep",
        "examples/delta_tolerances.lsd",
        "--sample",
        "16",
        "--design",
        "latin",
        "--seed",
        "4",
    ];
    for t in &tolerances {
        args.extend(["--vary", t]);
    }
    let built = dir.join("built.csv").display().to_string();
    let (code, _, stderr) = lsdc(&[&args[..], &["-o", &built]].concat());
    assert_eq!(code, 0, "{stderr}");
    let (header, rows) = read_rows(&std::fs::read_to_string(&built).expect("written"));
    let mut tilted = 0;
    for row in &rows {
        assert_eq!(field(&header, row, "status"), "ok", "{row:?}");
        let angle = |name: &str| number(&header, row, name);
        let nominal = delta_nacelle(
            [angle("A1.q"), angle("A2.q"), angle("A3.q")],
            [0.2; 3],
            [0.3; 3],
            [0.126; 3],
            [0.0; 3],
        );
        let error: f64 = (["x", "y", "z"].into_iter().zip(nominal))
            .map(|(axis, p)| (number(&header, row, &format!("end(nacelle.{axis})")) - p).powi(2))
            .sum::<f64>()
            .sqrt();
        assert!(error > 1e-7 && error < 1e-3, "error {error}");
        tilted += usize::from(number(&header, row, "end(nacelle.qw)") < 1.0 - 1e-12);
    }
    assert_eq!(tilted, rows.len(), "unequal rods tilt the nacelle");
}
