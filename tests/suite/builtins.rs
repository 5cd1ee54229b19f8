//! The built-in functions `floor` and `mod` against closed forms: on numbers (folded where they
//! are written) and on quantities known only during a run (time, a coordinate), where the
//! floored modulo is checked by its defining properties rather than by its formula. `aim(u)`
//! and `aim(u, v)` against direct constructions: the frame's rotated axes (as the run reports
//! them, `orientation`) against u / |u|, the Gram–Schmidt of v and the normal z × u that a
//! minimal rotation keeps.

use crate::common::programs::{example_text, simulated};

use lsdc::driver::compile_text;
use lsdc::load::LoadOptions;
use lsdc::prepare::{prepare, Settings};
use lsdc::simulate::run::Simulation;
use nalgebra::{Matrix3, Vector3};

/// The pendulum of `examples/pendulum.lsd` run with extra lines (outputs).
fn pendulum_with(lines: &str) -> Simulation {
    let text = example_text("pendulum", &[]) + lines;
    let options = LoadOptions {
        library_dirs: Vec::new(),
        use_environment: false,
        scene: None,
    };
    let compilation = compile_text(
        "program.lsd",
        &text,
        Some(std::path::Path::new("examples")),
        &options,
    );
    assert!(!compilation.has_errors(), "{:?}", compilation.diagnostics);
    let mechanism = compilation.mechanism.expect("elaborates");
    let prepared = prepare(&mechanism, &[], &Settings::default()).expect("prepares");
    simulated(&prepared)
}

fn column(simulation: &Simulation, name: &str) -> Vec<f64> {
    let k = (simulation.output_names.iter())
        .position(|n| n == name)
        .unwrap_or_else(|| panic!("no output {name} in {:?}", simulation.output_names));
    simulation.samples.iter().map(|s| s.outputs[k]).collect()
}

#[test]
fn floor_and_mod_of_numbers_are_their_closed_forms() {
    let simulation = pendulum_with(
        "output f = floor(-2.5) ; output g = floor(3) ; output wrap = mod(-1, 3) ;
         output negative = mod(7.5, -2) ; output exact = mod(6, 3) ;",
    );
    let first = |name| column(&simulation, name)[0];
    assert_eq!(first("f"), -3.0);
    assert_eq!(first("g"), 3.0);
    // The sign of a floored modulo is the divisor's: −1 wraps to the last of 3 indices.
    assert_eq!(first("wrap"), 2.0);
    assert_eq!(first("negative"), -0.5);
    assert_eq!(first("exact"), 0.0);
}

#[test]
fn floor_and_mod_of_run_quantities_keep_their_defining_properties() {
    let simulation = pendulum_with(
        "output steps = floor(10 * time - 0.5) ; output phase = mod(time, 0.3) ;
         output turned = mod(swing.q, -0.25) ;",
    );
    let (steps, phase, turned) = (
        column(&simulation, "steps"),
        column(&simulation, "phase"),
        column(&simulation, "turned"),
    );
    for (k, sample) in simulation.samples.iter().enumerate() {
        let (t, q) = (sample.time, sample.coordinates[0]);
        // floor: an integer n with n ≤ x < n + 1.
        let x = 10.0 * t - 0.5;
        assert_eq!(steps[k].fract(), 0.0, "t = {t}");
        assert!(steps[k] <= x && x < steps[k] + 1.0, "t = {t}: {}", steps[k]);
        // mod(a, b): in [0, b) for b > 0, in (b, 0] for b < 0, and a − mod(a, b) a multiple of b.
        let multiple = |a: f64, b: f64, r: f64| {
            let n = (a - r) / b;
            (n - n.round()).abs() < 1e-9
        };
        assert!((0.0..0.3).contains(&phase[k]), "t = {t}: {}", phase[k]);
        assert!(multiple(t, 0.3, phase[k]), "t = {t}: {}", phase[k]);
        assert!(
            turned[k] <= 0.0 && turned[k] > -0.25,
            "q = {q}: {}",
            turned[k]
        );
        assert!(multiple(q, -0.25, turned[k]), "q = {q}: {}", turned[k]);
    }
    // The run crosses several periods, so the wrap is exercised.
    assert!(phase.iter().any(|&p| p > 0.2) && phase.iter().any(|&p| p < 0.1));
}

/// The directions `aim` is tested with: general ones, ±z exactly (−z also with negative zeros,
/// whose azimuth atan2(−0, −0) is −π: the half turn about −y, the same), 1e-9 off them, and
/// directions whose squares overflow or vanish.
const DIRECTIONS: [[f64; 3]; 12] = [
    [1.0, 2.0, 3.0],
    [-0.3, 0.4, -12.0],
    [5.0, 0.0, 0.0],
    [0.0, 0.0, 1.0],
    [0.0, 0.0, -2.0],
    [-0.0, -0.0, -1.0],
    [1e-9, 0.0, 1.0],
    [0.0, -1e-9, 1.0],
    [1e-9, 1e-9, -1.0],
    [-1e-9, 0.0, -1.0],
    [1e200, -1e200, 3e200],
    [1e-300, 0.0, -1e-300],
];

/// The rotation of the frame `[0, 0, 0] ++ rotation @ earth`, as `orientation` reports it.
fn orientations(rotations: &[String]) -> Vec<Matrix3<f64>> {
    let mut lines = String::new();
    for (k, rotation) in rotations.iter().enumerate() {
        lines += &format!(
            "let aimed{k} = [0, 0, 0] ++ {rotation} @ earth ; output r{k} = orientation(aimed{k}) ;\n"
        );
    }
    let simulation = pendulum_with(&lines);
    (0..rotations.len())
        .map(|k| {
            let entry = |axes: &str| column(&simulation, &format!("r{k}.{axes}"))[0];
            Matrix3::from_fn(|i, j| {
                let names = ["x", "y", "z"];
                entry(&format!("{}{}", names[i], names[j]))
            })
        })
        .collect()
}

/// The direction u scaled by its largest component, so that its norm neither overflows nor
/// vanishes (a relative 1e-16 on each component).
fn unit_scale(u: [f64; 3]) -> Vector3<f64> {
    let u = Vector3::from(u);
    u / u.amax()
}

fn vector(v: [f64; 3]) -> String {
    format!("[{:e}, {:e}, {:e}]", v[0], v[1], v[2])
}

/// Orthonormal to 1e-15, and proper.
fn assert_rotation(r: &Matrix3<f64>, what: &str) {
    let defect = (r.transpose() * r - Matrix3::identity()).abs().max();
    assert!(defect <= 1e-15, "{what}: RᵀR − I is {defect:e}");
    // Orthonormal, its determinant is ±1 to the defect: the sign tells a rotation from a
    // reflection.
    assert!(r.determinant() > 0.0, "{what}: det {}", r.determinant());
}

fn assert_close(a: Vector3<f64>, b: Vector3<f64>, what: &str) {
    let error = (a - b).abs().max();
    assert!(
        error <= 1e-15,
        "{what}: {a:?} against {b:?}, error {error:e}"
    );
}

#[test]
fn aim_turns_z_to_u_by_the_minimal_rotation_at_and_near_z() {
    let rotations: Vec<String> = DIRECTIONS
        .iter()
        .map(|u| format!("aim({})", vector(*u)))
        .collect();
    for (r, u) in orientations(&rotations).iter().zip(DIRECTIONS) {
        let u = unit_scale(u);
        let what = format!("aim({u:?})");
        assert_rotation(r, &what);
        assert_close(r.column(2).into(), u.normalize(), &what);
        // The minimal rotation turns in the plane of z and u: it keeps their normal z × u,
        // written (−u_y, u_x, 0) / ρ without cancellation. At u = ±z exactly: the identity, and
        // at −z aim's documented choice, the half turn about y.
        let rho = u.xy().norm();
        let expected = if rho > 0.0 {
            let normal = Vector3::new(-u.y, u.x, 0.0) / rho;
            assert_close(r * normal, normal, &format!("{what}, its normal z × u"));
            continue;
        } else if u.z > 0.0 {
            Matrix3::identity()
        } else {
            Matrix3::from_diagonal(&Vector3::new(-1.0, 1.0, -1.0))
        };
        let error = (expected - r).abs().max();
        assert!(error <= 1e-15, "{what}: {error:e} from {expected:?}");
    }
}

#[test]
fn aim_with_v_turns_x_to_the_gram_schmidt_of_v() {
    let others = [[1.0, 1.0, 0.0], [0.0, 0.0, 1.0], [-2.0, 0.5, 7.0]];
    let mut pairs = Vec::new();
    for u in DIRECTIONS {
        for v in others {
            // Not parallel: v along u is refused (E0611, a golden file).
            if unit_scale(u).normalize().cross(&Vector3::from(v)).norm() > 1e-3 {
                pairs.push((u, v));
            }
        }
    }
    let rotations: Vec<String> = pairs
        .iter()
        .map(|(u, v)| format!("aim({}, {})", vector(*u), vector(*v)))
        .collect();
    for (r, (u, v)) in orientations(&rotations).iter().zip(&pairs) {
        let (u, v) = (unit_scale(*u), Vector3::from(*v));
        let what = format!("aim({u:?}, {v:?})");
        assert_rotation(r, &what);
        let z = u.normalize();
        // Gram–Schmidt twice ("twice is enough", Giraud, Langou, Rozložník, 2005): once leaves
        // the round-off of v·z, amplified by the cancellation when v is nearly along u.
        let once = v - v.dot(&z) * z;
        let x = (once - once.dot(&z) * z).normalize();
        assert_close(r.column(2).into(), z, &what);
        assert_close(r.column(0).into(), x, &what);
        assert_close(r.column(1).into(), z.cross(&x), &what);
    }
}

#[test]
fn aim_of_unknowns_is_aim_of_their_given_values() {
    let simulation = pendulum_with(
        "let a = ?s ; let b = ?s ; given a = -1e-9, b = 3 ;
         output known = aim([0, a, -1], [1, b, 0]) * [1, 0, 0] ;
         output written = aim([0, -1e-9, -1], [1, 3, 0]) * [1, 0, 0] ;
         output known_z = aim([2, b, a]) * [0, 0, 1] ;",
    );
    for axis in ["x", "y", "z"] {
        let known = column(&simulation, &format!("known.{axis}"))[0];
        let written = column(&simulation, &format!("written.{axis}"))[0];
        assert_eq!(known, written, "axis {axis}");
    }
    let z = Vector3::new(2.0, 3.0, -1e-9).normalize();
    let known_z =
        Vector3::from_fn(|i, _| column(&simulation, &format!("known_z.{}", ["x", "y", "z"][i]))[0]);
    assert_close(known_z, z, "aim([2, b, a])");
}
