//! `lsdc drag`: the four-bar's coupler point dragged along its coupler curve (computed here in
//! closed form), by the exact method and by the seed's penalty method; the penalty gaps against
//! K_L/K_M; the symmetry of the penalty system and its agreement with the energy's Hessian.

use lsdc::kinematics::assembly::AssemblyOptions;
use lsdc::kinematics::drag::DragOptions;
use lsdc::kinematics::frames::{self, FramePoint};
use lsdc::kinematics::model::KinematicModel;
use lsdc::kinematics::penalty::{self, PlanarModel, Stiffness};
use lsdc::studies::drag::{follow_exact, follow_penalty, parse_targets, PenaltyOptions, Target};
use nalgebra::Vector2;

use crate::common::programs::mechanism;

/// The four-bar example assembled, and its coupler point.
fn four_bar() -> (KinematicModel, FramePoint, Vec<f64>) {
    let mechanism = mechanism("four_bar", &[]);
    let topology = lsdc::topology::build(&mechanism).expect("numbered");
    let (model, report, _) =
        lsdc::studies::analysis::assembled_model(&mechanism, topology, &AssemblyOptions::default())
            .expect("assembles");
    let frame = frames::resolve(&mechanism, &model, "coupler_point").expect("a frame");
    (model, frame, report.coordinates_vector())
}

fn planar(model: &KinematicModel) -> PlanarModel {
    penalty::planar_model(model, vec!["bar1".into(), "bar2".into(), "bar3".into()])
        .expect("the four-bar is planar")
}

/// The coupler point at crank angle t, in closed form: B on the crank circle, C where the
/// circles about B (coupler, 3.5) and D = (4, 0) (rocker, 3) meet above BD, the point 1.75
/// along BC and 1 to its left.
pub fn coupler_point(t: f64) -> [f64; 3] {
    let b = Vector2::new(t.cos(), t.sin());
    let bd = Vector2::new(4.0, 0.0) - b;
    let d = bd.norm();
    let along = (3.5_f64.powi(2) - 3.0_f64.powi(2) + d * d) / (2.0 * d);
    let height = (3.5_f64.powi(2) - along * along).sqrt();
    let e = bd / d;
    let c = b + along * e + height * Vector2::new(-e.y, e.x);
    let u = (c - b) / 3.5;
    let p = b + 1.75 * u + Vector2::new(-u.y, u.x);
    [p.x, p.y, 0.0]
}

fn curve(angles: impl Iterator<Item = f64>) -> Vec<Target> {
    angles
        .map(|t| Target {
            line: 0,
            position: coupler_point(t),
        })
        .collect()
}

#[test]
fn the_exact_drag_traces_the_coupler_curve_with_closed_loops() {
    let (model, frame, q) = four_bar();
    let angles: Vec<f64> = (0..=20).map(|k| 1.0 + 0.05 * k as f64).collect();
    let targets = curve(angles.iter().copied());
    let run = follow_exact(&model, &frame, &q, &targets, 1.0, &DragOptions::default()).unwrap();
    let crank = run
        .configuration_names
        .iter()
        .position(|n| n == "crank.q")
        .unwrap();
    for (row, t) in run.rows.iter().zip(&angles) {
        assert!(row.reached && row.distance <= 1e-12, "{row:?}");
        assert!(row.gap <= 1e-10, "loop residual {}", row.gap);
        assert!(
            (row.configuration[crank] - t).abs() <= 1e-9,
            "crank {} for {t}",
            row.configuration[crank]
        );
    }
}

#[test]
fn an_unreachable_target_is_reported_with_its_distance() {
    let (model, frame, q) = four_bar();
    let targets = [Target {
        line: 0,
        position: [10.0, 10.0, 0.0],
    }];
    let run = follow_exact(&model, &frame, &q, &targets, 1.0, &DragOptions::default()).unwrap();
    let row = &run.rows[0];
    assert!(!row.reached && row.distance > 1.0, "{row:?}");
    assert!(row.gap <= 1e-10, "the loops stay closed: {}", row.gap);
    assert_eq!(run.unreached().count(), 1);
}

#[test]
fn the_converged_penalty_drag_matches_the_exact_configurations() {
    let (model, frame, q) = four_bar();
    let angles: Vec<f64> = (0..=10).map(|k| 1.0 + 0.05 * k as f64).collect();
    let targets = curve(angles.iter().copied());
    let options = PenaltyOptions {
        stiffness: Stiffness {
            link: 1e6,
            mouse: 1.0,
        },
        iterations: Some(20),
        reach_tolerance: 1e-9,
    };
    let run = follow_penalty(&model, &planar(&model), &frame, &q, &targets, &options).unwrap();
    for (row, t) in run.rows.iter().zip(&angles) {
        // The crank's angle is its body's Θ (bar1.theta, the third number).
        assert!(
            (row.configuration[2] - t).abs() <= 1e-9,
            "theta {} for {t}",
            row.configuration[2]
        );
        assert!(row.gap <= 1e-12 && row.distance <= 1e-12, "{row:?}");
    }
}

/// Without a count of solves, the penalty method solves until the configuration stops moving:
/// the coupler curve, in moves of 0.05 rad of the crank that one solve each left short (the
/// default was one solve, and such a path was reported out of reach), is followed to round-off.
#[test]
fn the_penalty_drag_solves_until_the_configuration_stops_moving() {
    let (model, frame, q) = four_bar();
    let angles: Vec<f64> = (0..=10).map(|k| 1.0 + 0.05 * k as f64).collect();
    let targets = curve(angles.iter().copied());
    let options = |iterations| PenaltyOptions {
        stiffness: Stiffness {
            link: 1e6,
            mouse: 1.0,
        },
        iterations,
        reach_tolerance: 1e-9,
    };
    let one = follow_penalty(
        &model,
        &planar(&model),
        &frame,
        &q,
        &targets,
        &options(Some(1)),
    );
    assert!(
        one.unwrap().unreached().count() > 0,
        "one solve per move falls short"
    );
    let run = follow_penalty(
        &model,
        &planar(&model),
        &frame,
        &q,
        &targets,
        &options(None),
    );
    let run = run.unwrap();
    assert_eq!(run.unreached().count(), 0);
    for (row, t) in run.rows.iter().zip(&angles) {
        assert!((row.configuration[2] - t).abs() <= 1e-9, "{row:?}");
        assert!(row.iterations < 100, "{row:?}");
    }
    assert!(run.rows.iter().any(|row| row.iterations > 1));
}

#[test]
fn one_solve_per_move_follows_the_curve_to_second_order() {
    // The seed's one linearised solve per move: the gaps left are the linearisation's,
    // quadratic in the step, whatever K_L/K_M.
    let (model, frame, q) = four_bar();
    let gap_for = |step: f64| {
        let targets = curve((1..=4).map(|k| 1.0 + step * k as f64));
        let options = PenaltyOptions {
            stiffness: Stiffness {
                link: 1e6,
                mouse: 1.0,
            },
            iterations: Some(1),
            reach_tolerance: 1e-9,
        };
        let run = follow_penalty(&model, &planar(&model), &frame, &q, &targets, &options).unwrap();
        run.rows.iter().map(|r| r.gap).fold(0.0, f64::max)
    };
    let order = (gap_for(0.02) / gap_for(0.01)).log2();
    assert!((order - 2.0).abs() < 0.2, "order {order}");
}

#[test]
fn the_penalty_gaps_shrink_as_the_inverse_of_the_stiffness_ratio() {
    // A target just off the coupler curve: the mouse pulls, the pivots stretch by the force
    // over K_L, and the point stops where the exact method says, to K_M/K_L.
    let (model, frame, q) = four_bar();
    let targets = [Target {
        line: 0,
        position: [1.36, 2.68, 0.0],
    }];
    let exact = follow_exact(&model, &frame, &q, &targets, 1.0, &DragOptions::default()).unwrap();
    let mut gaps = Vec::new();
    for ratio in [1e2, 1e4, 1e6] {
        let options = PenaltyOptions {
            stiffness: Stiffness {
                link: ratio,
                mouse: 1.0,
            },
            iterations: Some(50),
            reach_tolerance: 1e-9,
        };
        let run = follow_penalty(&model, &planar(&model), &frame, &q, &targets, &options).unwrap();
        let row = &run.rows[0];
        assert!(
            (row.distance - exact.rows[0].distance).abs() < 10.0 / ratio,
            "{row:?}"
        );
        gaps.push(row.gap);
    }
    for pair in gaps.windows(2) {
        let order = (pair[0] / pair[1]).log10() / 2.0;
        assert!((order - 1.0).abs() < 0.02, "order {order}: gaps {gaps:?}");
    }
}

#[test]
fn the_penalty_system_is_symmetric_and_is_the_energy_hessian_at_rest() {
    let (model, frame, q) = four_bar();
    let planar = planar(&model);
    let point = penalty::planar_point(&frame);
    let stiffness = Stiffness {
        link: 1e3,
        mouse: 1.0,
    };
    // Away from rest: a state with gaps, the target elsewhere.
    let mut state = penalty::planar_state(&model, &q).unwrap();
    for (j, u) in state.iter_mut().enumerate() {
        u[0] += 0.01 * j as f64;
        u[2] -= 0.02 * (j + 1) as f64;
    }
    let (matrix, _) = planar.system(&state, &point, &Vector2::new(1.0, 2.0), stiffness);
    let asymmetry = (&matrix - matrix.transpose()).amax();
    assert!(asymmetry <= 1e-12 * matrix.amax(), "asymmetry {asymmetry}");
    // At rest (closed pivots, the target on the point), K is the energy's Hessian: the
    // linearisation drops only terms proportional to the gaps.
    let rest = penalty::planar_state(&model, &q).unwrap();
    let target = penalty::point_position(&planar, &rest, &point).xy();
    let (matrix, force) = planar.system(&rest, &point, &target, stiffness);
    assert!(force.amax() <= 1e-9, "no force at rest: {}", force.amax());
    let energy = |s: &penalty::PlanarState| planar.energy(s, &point, &target, stiffness);
    let h = 1e-5;
    let n = matrix.nrows();
    for i in 0..n {
        for j in 0..n {
            let shifted = |di: f64, dj: f64| {
                let mut s = rest.clone();
                s[i / 3][i % 3] += di;
                s[j / 3][j % 3] += dj;
                energy(&s)
            };
            let second =
                (shifted(h, h) - shifted(h, -h) - shifted(-h, h) + shifted(-h, -h)) / (4.0 * h * h);
            assert!(
                (second - matrix[(i, j)]).abs() <= 1e-4 * matrix.amax(),
                "K[{i},{j}] = {} against {second}",
                matrix[(i, j)]
            );
        }
    }
}

#[test]
fn a_spatial_mechanism_is_refused_by_the_penalty_method() {
    let mechanism = mechanism("heavy_top", &[]);
    let topology = lsdc::topology::build(&mechanism).unwrap();
    let (model, _, _) =
        lsdc::studies::analysis::assembled_model(&mechanism, topology, &AssemblyOptions::default())
            .unwrap();
    let error = penalty::planar_model(&model, Vec::new()).unwrap_err();
    assert!(error.contains("planar mechanisms of pivots"), "{error}");
}

#[test]
fn targets_are_read_with_located_errors() {
    let targets = parse_targets("x,y\n# a comment\n1,2\n3,4,5\n", "path.csv", 0.5).unwrap();
    assert_eq!(targets[0].position, [1.0, 2.0, 0.5]);
    assert_eq!(
        targets[1],
        Target {
            line: 4,
            position: [3.0, 4.0, 5.0]
        }
    );
    let error = parse_targets("1,2\n1,two\n", "path.csv", 0.0).unwrap_err();
    assert!(
        error.starts_with("path.csv:2: expected a target"),
        "{error}"
    );
}

#[test]
fn the_drag_command_writes_rows_and_reports_unreached_targets() {
    let dir = std::env::temp_dir().join(format!("lsdc-drag-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("path.csv");
    let [x, y, _] = coupler_point(1.1);
    std::fs::write(&path, format!("x,y\n{x},{y}\n10,10\n")).unwrap();
    let path = path.to_str().unwrap();
    let (code, out, err) = crate::common::lsdc(&[
        "drag",
        "examples/four_bar.lsd",
        "--point",
        "coupler_point",
        "--path",
        path,
    ]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("1 of 2 targets out of reach"), "{err}");
    let lines: Vec<&str> = out.lines().collect();
    assert!(
        lines[0].starts_with("target.x,target.y,target.z,point.x")
            && lines[0].ends_with("crank.q,rocker.q,coupler.q,c.q"),
        "{}",
        lines[0]
    );
    assert_eq!(lines.len(), 3);
    assert!(
        lines[1].contains(",true,") && lines[2].contains(",false,"),
        "{out}"
    );
    let (code, _, err) = crate::common::lsdc(&[
        "drag",
        "examples/four_bar.lsd",
        "--point",
        "coupler",
        "--path",
        path,
    ]);
    assert_eq!(code, 2);
    assert!(err.contains("no frame named `coupler`"), "{err}");
}

#[test]
fn drag_set_gives_unknowns_their_values_as_simulate_set_does() {
    let dir = std::env::temp_dir().join(format!("lsdc-drag-set-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("path.csv");
    let targets: String = (0..5)
        .map(|k| coupler_point(1.0 + 0.05 * k as f64))
        .map(|[x, y, _]| format!("{x},{y}\n"))
        .collect();
    std::fs::write(&path, targets).unwrap();
    // The crank's length an unknown, given a wrong value: `--set` puts back the example's.
    let text = std::fs::read_to_string("examples/four_bar.lsd")
        .unwrap()
        .replace("let l1 = 1.0 ;", "let l1 = ?s ; given l1 = 1.3 ;");
    let program = dir.join("four_bar_unknown.lsd");
    std::fs::write(&program, text).unwrap();
    let drag = |file: &str, sets: &[&str]| {
        let mut args = vec!["drag", file, "--point", "coupler_point", "--path"];
        args.push(path.to_str().unwrap());
        args.extend(sets);
        crate::common::lsdc(&args)
    };
    let (code, expected, err) = drag("examples/four_bar.lsd", &[]);
    assert_eq!(code, 0, "{err}");
    let program = program.to_str().unwrap();
    let (code, with_set, err) = drag(program, &["--set", "l1=1.0"]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(with_set, expected);
    // Without `--set`, the given 1.3 holds: the same targets are not traced the same way.
    let (_, with_given, _) = drag(program, &[]);
    assert_ne!(with_given, expected);
    let (code, _, err) = drag(program, &["--set", "l9=1"]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("E0811"), "{err}");
    std::fs::remove_dir_all(&dir).ok();
}
