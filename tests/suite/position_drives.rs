//! Position drives (`drive position(F) = [x, y, z]`): a frame's origin imposed along a path by
//! three rows of the constraint stack. A point mass on three slides against its closed form
//! (the force m (p̈ − g)); the Delta's nacelle along the harmonic path of
//! bench/delta_path_torques.py, on its path to round-off with every integrator that imposes
//! drives, its force at the nacelle turned into arm torques by virtual power (τ = Jᵀ F, J the
//! direct velocity model) and followed through the actuated arms (`lsdc inverse --actuate`),
//! both against the independent computation; the refusals.

use crate::common::programs::{output, refusal_codes};
use crate::rheonomic::run_with_every_integrator;
use crate::trajectory::inverse_run;
use lsdc::api::{Program, SettingsChanges};
use lsdc::integrators::{Feature, INTEGRATORS};
use lsdc::prepare::Settings;
use lsdc::simulate::run::Simulation;
use lsdc::studies::inverse::check_driven;
use lsdc::studies::kinematic_models::{actuation, models_at, Output, OutputKind};
use lsdc::studies::trajectory::follow_program_path;

fn settings(integrator: lsdc::prepare::Integrator, duration: f64) -> Settings {
    Settings {
        integrator,
        duration,
        output: 0.01,
        rtol: 1e-12,
        atol: 1e-12,
        step: Some(1e-3),
        ..Settings::default()
    }
}

/// A point mass on three slides, its position imposed along a helix under gravity.
const SLIDES: &str = "
let ball = body mass = 2, iframe = 1, inertia = [0, 0, 0] end;
join earth and ball with link(x, y, z) dof = [x, y, z] end as slides;
apply force value = [0, 0, -9.81 * ball.mass], body = earth end on ball;
drive position(ball) = [0.3 * cos(2 * time), 0.3 * sin(2 * time), 0.1 * time];
output p = position(ball);
";

/// The helix and its acceleration at t.
fn helix(t: f64) -> ([f64; 3], [f64; 3]) {
    let (c, s) = ((2.0 * t).cos(), (2.0 * t).sin());
    ([0.3 * c, 0.3 * s, 0.1 * t], [-1.2 * c, -1.2 * s, 0.0])
}

/// The largest distance of the output `p` to the path `path` over the samples.
fn off_path(simulation: &Simulation, path: impl Fn(f64) -> [f64; 3]) -> f64 {
    let first = output(simulation, "p.x");
    let mut largest: f64 = 0.0;
    for sample in &simulation.samples {
        let ours = &sample.outputs[first..first + 3];
        for (x, law) in ours.iter().zip(path(sample.time)) {
            largest = largest.max((x - law).abs());
        }
    }
    largest
}

/// The slides' ball along its helix: the force at the ball is m (p̈ − g) to 1e-9 of its
/// largest value, the ball on its path to 1e-12 m and the energy balance with the drive's work
/// closes to 1e-9, with every integrator that imposes drives (the others refuse).
#[test]
fn a_point_mass_on_slides_needs_the_force_of_its_closed_form_with_every_integrator() {
    let settings = |integrator| settings(integrator, 1.0);
    run_with_every_integrator(SLIDES, settings, |name, simulation| {
        let force = output(simulation, "ball.drive_force.x");
        let mut error: f64 = 0.0;
        for sample in &simulation.samples {
            let (_, acceleration) = helix(sample.time);
            let expected = [
                2.0 * acceleration[0],
                2.0 * acceleration[1],
                2.0 * (acceleration[2] + 9.81),
            ];
            let ours = &sample.outputs[force..force + 3];
            for (x, expected) in ours.iter().zip(expected) {
                error = error.max((x - expected).abs() / 19.62);
            }
        }
        assert!(error < 1e-9, "{name}: force {error:e}");
        let off = off_path(simulation, |t| helix(t).0);
        assert!(off < 1e-12, "{name}: off the path by {off:e}");
    });
}

/// The Delta with its nacelle's harmonic path in the program (examples/delta_isir88_path.lsd).
fn delta_path() -> Program {
    Program::from_file("examples/delta_isir88_path.lsd", &Default::default()).expect("loads")
}

/// The bench's samples: one turn, every 0.01 s, with `integrator` (the example's own if
/// `None`) at the tolerance 1e-12.
fn bench_samples(integrator: Option<lsdc::prepare::Integrator>) -> SettingsChanges {
    SettingsChanges {
        duration: Some(1.0),
        output: Some(0.01),
        integrator,
        step: Some(1e-3),
        tolerance: Some(1e-12),
        ..Default::default()
    }
}

/// The nacelle's path at t.
fn nacelle_path(t: f64) -> [f64; 3] {
    let w = 2.0 * std::f64::consts::PI;
    let (c, s) = ((w * t).cos(), (w * t).sin());
    [0.05 * c, 0.05 * s, -0.3 + 0.02 * s]
}

/// The torques of bench/delta_path_torques.py: per row, time then the three arm torques.
fn reference_torques() -> Vec<[f64; 4]> {
    let text = std::fs::read_to_string("tests/fixtures/delta_path/torques.csv").unwrap();
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let header: Vec<&str> = lines.next().expect("header").split(',').collect();
    let at = |name: &str| header.iter().position(|h| *h == name).expect(name);
    let columns = [
        0,
        at("A1.drive_effort"),
        at("A2.drive_effort"),
        at("A3.drive_effort"),
    ];
    lines
        .map(|l| {
            let row: Vec<f64> = l.split(',').map(|x| x.parse().unwrap()).collect();
            columns.map(|c| row[c])
        })
        .collect()
}

/// The largest of `ours` (per row: time, three torques) against the reference, relative to
/// each torque's largest value, over the rows both have.
fn torque_error(ours: &[[f64; 4]]) -> f64 {
    let reference = reference_torques();
    assert_eq!(ours.len(), reference.len());
    let mut error: f64 = 0.0;
    for k in 1..4 {
        let largest = reference.iter().map(|r| r[k].abs()).fold(0.0, f64::max);
        for (a, b) in ours.iter().zip(&reference) {
            assert!((a[0] - b[0]).abs() < 1e-12);
            error = error.max((a[k] - b[k]).abs() / largest);
        }
    }
    error
}

/// `lsdc inverse` on the Delta with the nacelle's path in the program: its force at the
/// nacelle (the path's rows), turned into arm torques by virtual power, τ = Jᵀ F with J the
/// direct velocity model at each sample (ẋ = J q̇ₐ), agrees with the numpy computation to 1e-8
/// of each torque's largest value; the nacelle stays on its path to 1e-12 m and the energy
/// balance closes to 1e-9; with every integrator that imposes drives.
#[test]
fn the_delta_driven_by_its_nacelle_path_needs_the_torques_of_virtual_power() {
    for entry in INTEGRATORS {
        if entry.unsupported.contains(&Feature::Drives) {
            continue;
        }
        let changes = bench_samples(Some(entry.integrator.clone()));
        let (torques, off, balance) = delta_by_its_path(&changes);
        let error = torque_error(&torques);
        assert!(error < 1e-8, "{}: torques {error:e}", entry.name);
        assert!(off < 1e-12, "{}: off the path by {off:e}", entry.name);
        assert!(balance < 1e-9, "{}: energy balance {balance:e}", entry.name);
    }
}

/// The Delta run along its nacelle's path with `changes`: per sample the time and the arm
/// torques Jᵀ F, the nacelle's largest distance to its path, the energy balance.
fn delta_by_its_path(changes: &SettingsChanges) -> (Vec<[f64; 4]>, f64, f64) {
    let program = delta_path();
    let prepared = program.prepare(&[], changes).expect("prepares");
    check_driven(&prepared).expect("the path drives every degree of freedom");
    let (simulation, inverse) = inverse_run(&prepared);
    assert_eq!(inverse.driven, ["nacelle.x", "nacelle.y", "nacelle.z"]);
    let names: Vec<String> = ["A1.q", "A2.q", "A3.q"].map(String::from).to_vec();
    let actuated = actuation(&prepared, &names).expect("actuated");
    let mechanism = program.mechanism().expect("mechanism");
    let frame = lsdc::kinematics::frames::resolve(mechanism, &prepared.kinematics, "nacelle")
        .expect("frame");
    let point = Output {
        frame,
        kind: OutputKind::Point,
    };
    let model = &prepared.model;
    let mut torques = Vec::new();
    let mut off: f64 = 0.0;
    for (sample, run) in inverse.samples.iter().zip(&simulation.samples) {
        let configuration =
            lsdc::kinematics::forward::forward(&prepared.kinematics, &run.coordinates)
                .expect("configuration");
        let origin = point.frame.pose(&configuration).translation.vector;
        let path = nacelle_path(sample.time);
        for axis in 0..3 {
            off = off.max((origin[axis] - path[axis]).abs());
        }
        let (q, _) = model
            .state_from_declared(&run.coordinates, &run.rates)
            .expect("state");
        let models = models_at(model, &actuated, &point, &q, &[0.0; 3], 1e-6).expect("models");
        let force = &sample.efforts;
        let tau = [0, 1, 2].map(|k| (0..3).map(|r| models.direct[r][k] * force[r]).sum());
        torques.push([sample.time, tau[0], tau[1], tau[2]]);
    }
    let balance = simulation.report.energy_balance.expect("work tracked");
    (torques, off, balance)
}

/// The same path followed through the actuated arms (`lsdc inverse --actuate`: the inverse
/// geometric model at each sample, the laws' exact rates and accelerations): the arm torques
/// agree with the numpy computation to 1e-8 of their largest values, as the same path read
/// from the fixture's CSV file does (tests/suite/trajectory.rs).
#[test]
fn the_delta_path_in_the_program_followed_by_its_arms_needs_the_torques_of_virtual_power() {
    let program = delta_path();
    let mut prepared = program
        .prepare(&[], &bench_samples(None))
        .expect("prepares");
    let actuated = ["A1.q", "A2.q", "A3.q"].map(String::from);
    follow_program_path(&mut prepared, &actuated)
        .expect("a position drive")
        .expect("followed");
    let (_, inverse) = inverse_run(&prepared);
    assert_eq!(inverse.driven, ["A1.q", "A2.q", "A3.q"]);
    let torques: Vec<[f64; 4]> = (inverse.samples.iter())
        .map(|s| [s.time, s.efforts[0], s.efforts[1], s.efforts[2]])
        .collect();
    let error = torque_error(&torques);
    assert!(error < 1e-8, "torques {error:e}");
}

/// What a position drive cannot impose: a path of more motions than the mechanism can make
/// (E0494: a pendulum's tip in three directions), a path that starts out of reach (E0499: an
/// arm of 1.5 m asked to start 3 m away; from its bent start it reaches 1.2 m).
#[test]
fn position_drives_that_cannot_be_imposed_are_refused() {
    let pendulum = "import joints;
let rod = body mass = 1, iframe = [0, 0, -0.5] ++ 1, inertia = [0.1, 0.1, 0.001] end;
let tip = [0, 0, -1] ++ 1 @ rod;
join earth and rod with revolute([1, 0, 0]) as swing;
drive position(tip) = [0, sin(time), -cos(time)];
";
    assert_eq!(refusal_codes(pendulum), ["E0494"]);
    let arm = "import joints;
let upper = body mass = 1, iframe = [0.5, 0, 0] ++ 1, inertia = [0.01, 0.1, 0.1] end;
let lower = body mass = 1, iframe = [0.25, 0, 0] ++ 1, inertia = [0.01, 0.05, 0.05] end;
let hand = [0.5, 0, 0] ++ 1 @ lower;
join earth and upper with link(a, b) dof1 = a || [0, 0, 1], dof2 = b || [0, 1, 0] end;
join [1, 0, 0] ++ 1 @ upper and lower with revolute([0, 1, 0]) as elbow;
initial elbow.q = 1;
";
    let reach = |x: f64| {
        refusal_codes(&format!(
            "{arm}drive position(hand) = [{x}, 0, 0.1 * time];"
        ))
    };
    assert_eq!(reach(3.0), ["E0499"]);
    assert_eq!(reach(1.2), Vec::<String>::new());
}
