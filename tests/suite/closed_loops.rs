//! Simulation of mechanisms with closed loops, against conservation laws, energy balances,
//! the momentum theorem, the Delta robot's holding torques (notes T11) and the agreement of two
//! models of one mechanism. The examples carry their own `simulate` settings; a test changes
//! them on the prepared simulation when it needs another integrator or tolerance.

use crate::common::programs::{
    column, constraints, example_text, parallelogram, prepared, run_text, simulated,
};
use lsdc::driver::compile_text;
use lsdc::dynamics::algorithms::{forward_kinematics, Data};
use lsdc::dynamics::loops::Stabilisation;
use lsdc::load::LoadOptions;
use lsdc::prepare::{prepare, Integrator, Prepared, Settings};
use lsdc::simulate::run::{run, Sample, Simulation};
use lsdc::studies::statics::holding_efforts;

#[test]
fn four_bar_and_slider_crank_conserve_energy_and_stay_closed() {
    // Both examples: 10 s under gravity, dopri5 at 1e-12.
    for name in ["four_bar", "slider_crank"] {
        let simulation = simulated(&prepared(name, &[]));
        let drift = simulation.report.energy_drift.expect("conservative");
        let c = constraints(&simulation);
        assert!(drift < 1e-8, "{name}: energy drift {drift:e}");
        assert!(
            c.position_residual < 1e-10,
            "{name}: position residual {:e}",
            c.position_residual
        );
        assert!(
            c.velocity_residual < 1e-10,
            "{name}: velocity residual {:e}",
            c.velocity_residual
        );
        // Something happened: the mechanism moved through a good part of its range.
        let crank = column(&simulation, "crank.q");
        let range = simulation
            .samples
            .iter()
            .map(|s| s.coordinates[crank])
            .fold(f64::NEG_INFINITY, f64::max)
            - simulation
                .samples
                .iter()
                .map(|s| s.coordinates[crank])
                .fold(f64::INFINITY, f64::min);
        assert!(range > 1.0, "{name}: the crank moved {range} rad");
    }
}

#[test]
fn every_integrator_keeps_the_four_bar_closed() {
    let cases = [
        (Integrator::Rk4, Some(1e-3), Stabilisation::Projection, 1e-7),
        (Integrator::Implicit, None, Stabilisation::Projection, 1e-6),
        (Integrator::Dop853, None, Stabilisation::Projection, 1e-7),
        (
            Integrator::Symplectic,
            Some(1e-3),
            Stabilisation::Projection,
            1e-4,
        ),
        (
            Integrator::DormandPrince,
            None,
            Stabilisation::Baumgarte(10.0),
            1e-6,
        ),
    ];
    for (integrator, step, stabilisation, energy_bound) in cases {
        let mut p = prepared("four_bar", &[]);
        p.settings = Settings {
            integrator: integrator.clone(),
            duration: 2.0,
            step,
            rtol: 1e-9,
            atol: 1e-9,
            stabilisation,
            ..p.settings
        };
        let simulation = simulated(&p);
        let c = constraints(&simulation);
        let drift = simulation.report.energy_drift.expect("conservative");
        assert!(
            drift < energy_bound,
            "{integrator:?}: energy drift {drift:e}"
        );
        let closure_bound = if stabilisation == Stabilisation::Projection {
            1e-12
        } else {
            1e-6
        };
        assert!(
            c.position_residual < closure_bound,
            "{integrator:?}: position residual {:e}",
            c.position_residual
        );
    }
}

/// A five-bar of the `loops` fuzz target (input `ev8QQP77XMs=`) started fast near a flat
/// configuration: rk4's steps of 1 ms are far too long for it (W0902), and one strays 0.24 m
/// from the loops.
const STRAYING_FIVE_BAR: &str = "import joints ;
import gravity ;
let bar(l) = body mass = l, iframe = [l / 2, 0, 0] ++ 1, inertia = [1e-4 * l, l * l * l / 12, l * l * l / 12] end ;
let b0 = bar(2.989) ;
let b1 = bar(0.375) ;
let b2 = bar(0.900) ;
let b3 = bar(2.978) ;
apply weight_in(b0, [0, -9.81, 0]) on b0.iframe ;
apply weight_in(b1, [0, -9.81, 0]) on b1.iframe ;
apply weight_in(b2, [0, -9.81, 0]) on b2.iframe ;
apply weight_in(b3, [0, -9.81, 0]) on b3.iframe ;
join earth and b0 with revolute([0, 0, 1]) as j0 ;
join [2.989, 0, 0] ++ 1 @ b0 and b1 with revolute([0, 0, 1]) as j1 ;
join [0.375, 0, 0] ++ 1 @ b1 and b2 with revolute([0, 0, 1]) as j2 ;
join [0.900, 0, 0] ++ 1 @ b2 and b3 with revolute([0, 0, 1]) as j3 ;
join [2.978, 0, 0] ++ 1 @ b3 and [2.941, 0, 0] ++ 1 @ earth with revolute([0, 0, 1]) as jn ;
initial j0.q = -0.900, j1.q = 1.875, j2.q = -3.200, j3.q = -3.200 ;
initial j0.q' = -5.000 ;
";

#[test]
fn a_step_far_off_the_loops_is_projected_back_to_round_off() {
    // The projection's aim is round-off whatever the step left: before, its chord steps (the
    // factor of the rows where it started, kept along) converged only about sixfold each from
    // 0.24 m, its eight steps ended at 2.0e-8 m, and the velocities, projected with that
    // factor, kept 6 % of their rows' residual (38 of 599).
    let settings = Settings {
        integrator: Integrator::Rk4,
        duration: 0.05,
        output: 0.01,
        step: Some(1e-3),
        rtol: 1e-8,
        atol: 1e-8,
        ..Settings::default()
    };
    let simulation = run_text(STRAYING_FIVE_BAR, settings);
    assert!(simulation.report.failure.is_none());
    let c = constraints(&simulation);
    assert!(
        c.position_residual_before_projection > 0.1,
        "the run no longer strays: {:e}",
        c.position_residual_before_projection
    );
    assert!(
        c.position_residual < 1e-12,
        "position residual {:e}",
        c.position_residual
    );
    let left = c.velocity_residual / c.velocity_residual_before_projection;
    assert!(
        left < 1e-6,
        "the velocities keep {left:e} of their residual"
    );
}

#[test]
fn the_implicit_integrator_takes_a_stiff_four_bar_on_its_loops() {
    // The four-bar's crank held by a stiff torsion spring and a strong damper (1e4 N m/rad,
    // 1e5 N m s/rad): a mode decaying at about 5e4 /s holds dopri5 at its stability boundary.
    // The implicit integrator goes over to the Rosenbrock-W method, whose Jacobian is formed
    // along the loop's allowed motions only, and keeps the energy balance and the closure.
    let stiff = |integrator: Integrator| {
        let mut p = prepared(
            "four_bar",
            &[
                ("import gravity ;", "import gravity ;\nimport forces ;"),
                (
                    "with revolute([0, 0, 1]) as crank",
                    "with revolute_spring_damper([0, 0, 1], 1e4, 1e5, 0) as crank",
                ),
            ],
        );
        p.settings = Settings {
            integrator,
            duration: 0.3,
            rtol: 1e-8,
            atol: 1e-8,
            ..p.settings
        };
        simulated(&p)
    };
    let implicit = stiff(Integrator::Implicit);
    let explicit = stiff(Integrator::DormandPrince);
    let (report, c) = (&implicit.report, constraints(&implicit));
    let stiff_steps = report
        .stiff_steps
        .expect("the implicit integrator counts them");
    eprintln!(
        "stiff four-bar: implicit {} steps ({stiff_steps} stiff), {} evaluations; dopri5 {} steps, {} evaluations",
        report.steps, report.function_evaluations, explicit.report.steps, explicit.report.function_evaluations
    );
    assert!(2 * stiff_steps > report.steps);
    assert!(10 * report.steps < explicit.report.steps);
    let balance = report.energy_balance.expect("a damper");
    assert!(balance < 1e-6, "energy balance {balance:e}");
    assert!(
        c.position_residual < 1e-12 && c.velocity_residual < 1e-12,
        "residuals {:e} {:e}",
        c.position_residual,
        c.velocity_residual
    );
    let crank = column(&implicit, "crank.q");
    let end = |s: &Simulation| s.samples.last().expect("samples").coordinates[crank];
    assert!(
        (end(&implicit) - end(&explicit)).abs() < 1e-6,
        "crank at the end: implicit {}, dopri5 {}",
        end(&implicit),
        end(&explicit)
    );
}

#[test]
fn without_stabilisation_the_loop_drifts_open() {
    // The control experiment for the test above: the same run with nothing keeping the loop
    // closed drifts by far more than the projection leaves.
    let mut p = prepared("four_bar", &[]);
    p.settings = Settings {
        duration: 10.0,
        rtol: 1e-6,
        atol: 1e-6,
        stabilisation: Stabilisation::None,
        ..p.settings
    };
    let simulation = simulated(&p);
    assert!(
        constraints(&simulation).position_residual > 1e-8,
        "{:e}",
        constraints(&simulation).position_residual
    );
}

#[test]
fn a_planar_loop_of_spatial_revolutes_reports_its_redundant_constraints() {
    let simulation = simulated(&prepared(
        "four_bar",
        &[("duration = 10", "duration = 0.5")],
    ));
    let c = constraints(&simulation);
    assert_eq!((c.rows, c.rank), (6, 3));
    assert_eq!(
        c.redundant,
        [
            "c: rotation about x",
            "c: rotation about y",
            "c: translation along z"
        ]
    );
}

#[test]
fn given_initial_rates_are_kept_and_the_others_close_the_loops() {
    let simulation = simulated(&prepared(
        "slider_crank",
        &[("duration = 10", "duration = 0.1")],
    ));
    let first = &simulation.samples[0];
    assert!((first.rates[column(&simulation, "crank.q")] - 3.0).abs() < 1e-12);
    // The slider moves as the closure says: x3 = λ1 cos α1 + λ2 cos(α1 + α12).
    let (a1, a12) = (
        first.coordinates[column(&simulation, "crank.q")],
        first.coordinates[column(&simulation, "coupler.q")],
    );
    let (r1, r12) = (
        first.rates[column(&simulation, "crank.q")],
        first.rates[column(&simulation, "coupler.q")],
    );
    let (lambda1, lambda2) = (1.0, 3.0);
    let slider_rate = -lambda1 * a1.sin() * r1 - lambda2 * (a1 + a12).sin() * (r1 + r12);
    assert!((first.rates[column(&simulation, "slider.q")] - slider_rate).abs() < 1e-12);
    assert!(constraints(&simulation).velocity_residual < 1e-12);
}

#[test]
fn incompatible_initial_rates_are_an_error() {
    let text = example_text(
        "four_bar",
        &[(
            "c.q = 1.15 guess ;",
            "c.q = 1.15 guess, crank.q' = 1, rocker.q' = 5 ;",
        )],
    );
    let options = LoadOptions {
        library_dirs: Vec::new(),
        use_environment: false,
        scene: None,
    };
    let mechanism = compile_text("four_bar.lsd", &text, None, &options)
        .mechanism
        .expect("elaborates");
    let errors = prepare(&mechanism, &[], &Settings::default())
        .err()
        .expect("refused");
    assert_eq!(errors[0].code, "E0815", "{:?}", errors[0].message);
    assert!(
        errors[0].message.contains("crank.q'") && errors[0].message.contains("rocker.q'"),
        "{}",
        errors[0].message
    );
}

/// A spatial six-revolute loop next to a singular configuration of its velocity map (found by
/// the loops fuzz target): the given `j0.q' = -5` is completed with `jn.q'` = 6.278e4, which
/// W0802 reports with the ratio of the two, at the `initial` that gives the rate. The four-bar,
/// its rates completed at the same order as the given one, has no such warning.
#[test]
fn rates_the_loops_make_far_larger_than_the_given_ones_are_reported() {
    let options = LoadOptions {
        library_dirs: Vec::new(),
        use_environment: false,
        scene: None,
    };
    let path = "tests/fixtures/amplified_initial_rates.lsd";
    let text = std::fs::read_to_string(path).expect("fixture");
    let mechanism = compile_text(path, &text, None, &options)
        .mechanism
        .expect("elaborates");
    let prepared = prepare(&mechanism, &[], &Settings::default()).expect("prepared");
    let closing = (prepared.coordinate_names.iter())
        .position(|n| n == "jn.q")
        .expect("jn.q");
    let ratio = prepared.rates[closing].abs() / 5.0;
    assert!(ratio > 1e4 && ratio < 2e4, "ratio {ratio}");
    let warnings: Vec<_> = prepared
        .warnings
        .iter()
        .filter(|w| w.code == "W0802")
        .collect();
    let [warning] = &warnings[..] else {
        panic!("{:?}", prepared.warnings);
    };
    let expected = format!(
        "{ratio:.1e} times larger: `jn.q'` = {:.3e} with `j0.q'` = -5",
        prepared.rates[closing]
    );
    assert!(
        warning.message.contains(&expected),
        "{} / {expected}",
        warning.message
    );
    let text = example_text(
        "four_bar",
        &[("c.q = 1.15 guess ;", "c.q = 1.15 guess, crank.q' = 1 ;")],
    );
    let mechanism = compile_text("four_bar.lsd", &text, None, &options)
        .mechanism
        .expect("elaborates");
    let four_bar = prepare(&mechanism, &[], &Settings::default()).expect("prepared");
    let largest = four_bar.rates.iter().fold(0.0f64, |m, r| m.max(r.abs()));
    assert!(largest > 0.1 && largest < 1e3, "{:?}", four_bar.rates);
    assert!(four_bar.warnings.iter().all(|w| w.code != "W0802"));
}

#[test]
fn reactions_at_the_ground_balance_the_change_of_momentum() {
    // Momentum theorem: the forces earth exerts through the crank and rocker joins plus the
    // weights equal the rate of change of the linear momentum (central differences of outputs).
    let mut p = prepared("four_bar", &[]);
    p.settings = Settings {
        duration: 0.5,
        output: 1e-3,
        rtol: 1e-13,
        atol: 1e-13,
        reactions: true,
        ..p.settings
    };
    let simulation = simulated(&p);
    let join = |name: &str| {
        6 * simulation
            .reaction_names
            .iter()
            .position(|n| n == name)
            .expect("join")
    };
    let (crank, rocker) = (join("crank"), join("rocker"));
    let weight = -9.81 * (1.0 + 3.5 + 3.0);
    let h = 1e-3;
    for k in (1..simulation.samples.len() - 1).step_by(25) {
        let (before, now, after) = (
            &simulation.samples[k - 1],
            &simulation.samples[k],
            &simulation.samples[k + 1],
        );
        for axis in 0..2 {
            let rate = (after.momentum[3 + axis] - before.momentum[3 + axis]) / (2.0 * h);
            let force = now.reactions[crank + 3 + axis]
                + now.reactions[rocker + 3 + axis]
                + if axis == 1 { weight } else { 0.0 };
            assert!(
                (rate - force).abs() < 1e-4 * weight.abs(),
                "t = {}, axis {axis}: dp/dt {rate} vs forces {force}",
                now.time
            );
        }
    }
}

/// The Delta's initial arm angles (degrees) in place of 40, 40, 40.
fn delta_at(name: &str, degrees: [f64; 3]) -> Prepared {
    let a = degrees.map(|d| format!("{d} * pi / 180 fixed"));
    prepared(
        name,
        &[
            ("A1.q = 40 * pi / 180 fixed", &format!("A1.q = {}", a[0])),
            ("A2.q = 40 * pi / 180 fixed", &format!("A2.q = {}", a[1])),
            ("A3.q = 40 * pi / 180 fixed", &format!("A3.q = {}", a[2])),
        ],
    )
}

/// The arm angle (degrees) that puts the nacelle at (0, 0, z): the elbow C at
/// (r + l1 cos α, −l1 sin α) in the chain's plane is at l2 from P (closed form, by bisection).
fn arm_angle_for_height(z: f64) -> f64 {
    let (r, l1, l2) = (0.126, 0.2, 0.3);
    let gap = |a: f64| (r + l1 * a.cos()).powi(2) + (z + l1 * a.sin()).powi(2) - l2 * l2;
    let (mut low, mut high) = (0.0f64, 1.2f64);
    assert!(gap(low) * gap(high) < 0.0);
    for _ in 0..200 {
        let middle = 0.5 * (low + high);
        if gap(low) * gap(middle) <= 0.0 {
            high = middle;
        } else {
            low = middle;
        }
    }
    low.to_degrees()
}

#[test]
fn delta_holding_torques_match_the_thesis_lumped_model() {
    // Notes T11 (g = 9.81, arm and wheel with Δα = 3.73°, half the rods at the elbows, the
    // nacelle and the other halves at P): holding torque per arm, N·m, to the table's 5 digits.
    // α is positive downwards, so the torque that holds an arm up is negative.
    let below = arm_angle_for_height(-0.3);
    let poses: [([f64; 3], [f64; 3]); 3] = [
        ([40.0; 3], [0.23101; 3]),
        ([below; 3], [0.20545; 3]),
        ([20.0, 40.0, 60.0], [0.23861, 0.22646, 0.18285]),
    ];
    for name in ["delta_isir88", "delta_isir88_reduced"] {
        for (angles, expected) in poses {
            let p = delta_at(name, angles);
            let holding = holding_efforts(
                &p,
                &["A1.q".to_string(), "A2.q".to_string(), "A3.q".to_string()],
            )
            .expect("holds");
            assert!(
                holding.unbalanced < 1e-12,
                "{name}: unbalanced {:e}",
                holding.unbalanced
            );
            for (held, want) in holding.efforts.iter().zip(expected) {
                assert!(
                    (held.effort + want).abs() < 6e-6,
                    "{name} at {angles:?}: {} holds with {} N·m, the thesis {want}",
                    held.name,
                    held.effort
                );
            }
        }
    }
}

/// The nacelle's position at every output.
fn nacelle_path(p: &Prepared, simulation: &Simulation) -> Vec<[f64; 3]> {
    let model = &p.model;
    let nacelle = 1 + model
        .body_names
        .iter()
        .position(|n| n == "nacelle")
        .expect("nacelle");
    let mut data = Data::new(model);
    simulation
        .samples
        .iter()
        .map(|s| {
            let (q, v) = model
                .state_from_declared(&s.coordinates, &s.rates)
                .expect("state");
            forward_kinematics(model, &mut data, &q, &v).expect("poses");
            let t = data.world[nacelle].translation.vector;
            [t.x, t.y, t.z]
        })
        .collect()
}

#[test]
fn delta_braked_by_its_shorted_motors_stays_closed_and_both_models_agree() {
    let (full, reduced) = (
        prepared("delta_isir88", &[]),
        prepared("delta_isir88_reduced", &[]),
    );
    let (full_run, reduced_run) = (simulated(&full), simulated(&reduced));
    for run in [&full_run, &reduced_run] {
        assert!(
            constraints(run).position_residual < 1e-12,
            "{:e}",
            constraints(run).position_residual
        );
        // Kinetic plus potential energy less the brakes' work.
        assert!(run.report.energy_balance.expect("braked") < 1e-8);
    }
    let (a, b) = (
        nacelle_path(&full, &full_run),
        nacelle_path(&reduced, &reduced_run),
    );
    assert_eq!(a.len(), b.len());
    let fall = a.last().expect("outputs")[2] - a[0][2];
    assert!(fall < -0.05, "the nacelle fell {fall} m");
    for (k, (p, q)) in a.iter().zip(&b).enumerate() {
        for i in 0..3 {
            assert!(
                (p[i] - q[i]).abs() < 1e-8,
                "output {k}: nacelle at {p:?} (full) and {q:?} (reduced)"
            );
        }
    }
}

/// The shorted motors' brake, c = 12² K_i K_e / R (lib/delta_masses.lsd), N·m·s/rad.
const SHORTED_MOTOR_BRAKE: f64 = 144.0 * 0.119 * 0.1194 / 1.35;

/// The full Delta held at a sample's configuration: its arm angles fixed, its ball joints'
/// starting guesses the sample's values (so that the assembly finds that configuration).
fn delta_at_sample(run: &Simulation, sample: &Sample) -> Prepared {
    let text = example_text("delta_isir88", &[]);
    let mut replacements = Vec::new();
    for (name, value) in run.coordinate_names.iter().zip(&sample.coordinates) {
        let start = text.find(&format!("{name} = ")).expect("an initial value");
        let end = start + text[start..].find([',', ';']).unwrap();
        let kind = if name.starts_with('A') {
            "fixed"
        } else {
            "guess"
        };
        replacements.push((
            text[start..end].to_string(),
            format!("{name} = {value:e} {kind}"),
        ));
    }
    let pairs: Vec<(&str, &str)> = (replacements.iter())
        .map(|(from, to)| (from.as_str(), to.as_str()))
        .collect();
    prepared("delta_isir88", &pairs)
}

/// Braked by its shorted motors, the Delta sinks slowly, nearly in static balance: each arm's
/// brake torque c α' nearly matches the torque that holds the arm at rest at that pose (the
/// statics of the same mechanism, an independent computation). What is left is the inertia of
/// the slow motion (J α'' ~ 1e-4 of the holding torque) and the short start (J1 / c = 5 ms).
#[test]
fn the_braked_delta_sinks_in_near_static_balance() {
    let run = simulated(&prepared("delta_isir88", &[]));
    let actuated = ["A1.q", "A2.q", "A3.q"].map(String::from);
    let mut checked = 0;
    // Every half second from 0.5 s (outputs every 0.05 s).
    for sample in run.samples.iter().skip(10).step_by(10) {
        let holding = holding_efforts(&delta_at_sample(&run, sample), &actuated).expect("holds");
        for (k, held) in holding.efforts.iter().enumerate() {
            let braking = SHORTED_MOTOR_BRAKE * sample.rates[column(&run, &actuated[k])];
            assert!(
                (braking + held.effort).abs() < 2e-3 * held.effort.abs(),
                "t = {}: brake {braking} N·m, holding {} N·m",
                sample.time,
                -held.effort
            );
        }
        checked += 1;
    }
    assert_eq!(checked, 20);
}

#[test]
fn meshes_deploy_under_a_driving_torque_and_stay_closed() {
    for name in ["maille1", "maille2"] {
        let simulation = simulated(&prepared(name, &[]));
        let c = constraints(&simulation);
        assert!(
            c.position_residual < 1e-12,
            "{name}: {:e}",
            c.position_residual
        );
        assert!(
            c.velocity_residual < 1e-12,
            "{name}: {:e}",
            c.velocity_residual
        );
        let j10 = column(&simulation, "j10.q");
        let moved = simulation.samples.last().expect("outputs").coordinates[j10]
            - simulation.samples[0].coordinates[j10];
        assert!(moved < -0.3, "{name}: j10 moved {moved} rad");
    }
}

#[test]
fn saliere_is_driven_through_its_crossing() {
    let simulation = simulated(&prepared("saliere", &[]));
    let (a1, a2, a3) = (
        column(&simulation, "l1.q"),
        column(&simulation, "l2.q"),
        column(&simulation, "l4.q"),
    );
    let first = &simulation.samples[0];
    for s in &simulation.samples {
        // Branch (a): α1 = 0 and α2 = α3, on both sides of the crossing (0, 0, 0).
        assert!(
            s.coordinates[a1].abs() < 1e-9 && (s.coordinates[a2] - s.coordinates[a3]).abs() < 1e-9,
            "t = {}",
            s.time
        );
        // Energy balance: the motor's work −0.5 N·m × Δα3 is the kinetic energy gained.
        let work = -0.5 * (s.coordinates[a3] - first.coordinates[a3]);
        assert!(
            (s.kinetic_energy - first.kinetic_energy - work).abs()
                < 1e-8 * (1.0 + s.kinetic_energy),
            "t = {}",
            s.time
        );
    }
    assert!(
        first.coordinates[a2] > 0.5
            && simulation.samples.last().expect("outputs").coordinates[a2] < -0.5
    );
    let c = constraints(&simulation);
    let closest = c.closest.as_ref().expect("measured");
    assert!(
        closest.ratio < 1e-2 && (0.5..0.7).contains(&closest.time),
        "{closest:?}"
    );
    assert!(c.position_residual < 1e-12);
}

#[test]
fn homocinetic_joint_turns_both_shafts_at_one_speed() {
    let simulation = simulated(&prepared("homocinetic", &[]));
    let (input, output) = (column(&simulation, "l1.q"), column(&simulation, "l4.q"));
    let first = &simulation.samples[0];
    for s in &simulation.samples {
        assert!(
            (s.rates[input] - s.rates[output]).abs() < 1e-9 * (1.0 + s.rates[input].abs()),
            "t = {}",
            s.time
        );
        let work = 0.2 * (s.coordinates[input] - first.coordinates[input]);
        assert!(
            (s.kinetic_energy - first.kinetic_energy - work).abs()
                < 1e-8 * (1.0 + s.kinetic_energy),
            "t = {}",
            s.time
        );
    }
    let turns = (simulation.samples.last().expect("outputs").coordinates[input]
        - first.coordinates[input])
        / std::f64::consts::TAU;
    assert!(turns > 10.0, "{turns} turns");
}

#[test]
fn a_driven_motion_without_mass_is_an_error() {
    // maille1 with massless rods: the motor torque would give an infinite acceleration.
    let mut p = prepared(
        "maille1",
        &[
            ("body mass = L, iframe = [0, L / 2, 0] ++ 1, inertia = [L * L * L / 12, 1e-4, L * L * L / 12] end", "body mass = 0, inertia = 0 end"),
            ("body mass = 1, iframe = 0, inertia = [0.01, 0.01, 0.01] end", "body mass = 0, inertia = 0 end"),
        ],
    );
    p.settings.duration = 0.1;
    let simulation = run(&p, &mut |_| {});
    let failure = simulation.report.failure.as_ref().expect("fails");
    assert!(
        failure.message.contains("moves no mass"),
        "{}",
        failure.message
    );
}

#[test]
fn a_torque_on_a_complementary_ball_angle_is_an_error() {
    // The Delta with a torque in one of its closing ball joints: the ball's angles move no mass
    // and no kept row (they are left out of the solve), so a force on them cannot be balanced.
    let mut p = prepared(
        "delta_isir88",
        &[(
            "[0, 0, -l2] ++ 1 @ rod1m with spherical as P1m",
            "[0, 0, -l2] ++ 1 @ rod1m with link(a, b, c) dof1 = a || [1,0,0], dof2 = b || [0,1,0], dof3 = c || [0,0,1], torque3 = [0, 0, 0.1] end as P1m",
        )],
    );
    p.settings.duration = 0.01;
    let simulation = run(&p, &mut |_| {});
    let failure = simulation.report.failure.as_ref().expect("fails");
    assert!(
        failure.message.contains("moves no mass") && failure.message.contains("P1m"),
        "{}",
        failure.message
    );
}

#[test]
fn a_parallelogram_runs_through_its_flat_configurations() {
    // The four-bar with opposite bars equal: at every flat configuration the constraints lose
    // rank (where the parallelogram and anti-parallelogram branches meet). Momentum carries it
    // through on its branch (crank and rocker parallel); the report names each passage that a
    // step's end or an output comes near (conditioning below 1e-3, a few 1e-4 s about each flat
    // configuration at this speed): with outputs every 1e-3 s, all of them, two per turn.
    let p = parallelogram();
    let simulation = simulated(&p);
    let (crank, rocker) = (
        column(&simulation, "crank.q"),
        column(&simulation, "rocker.q"),
    );
    for s in &simulation.samples {
        assert!(
            (s.coordinates[crank] - s.coordinates[rocker]).abs() < 1e-9,
            "t = {}: off the parallelogram branch",
            s.time
        );
    }
    let turns = (simulation.samples.last().expect("outputs").coordinates[crank] - 1.0)
        / std::f64::consts::TAU;
    assert!(turns > 3.0, "{turns} turns");
    let c = constraints(&simulation);
    assert!(
        c.singular.len() as f64 >= (2.0 * turns).floor(),
        "{turns} turns: {:?}",
        c.singular
    );
    assert!(simulation.report.energy_drift.expect("conservative") < 1e-9);
    assert!(c.position_residual < 1e-12);
}

#[test]
fn a_loop_closed_by_a_prismatic_link_conserves_energy() {
    // The oscillating slotted lever of quick-return mechanisms: a crank turns about O, a block
    // pivots at the crank's end A and slides along a lever that turns about D = (−2, 0, 0). The
    // prismatic link closes the loop, so the constraint rows involve a translation coordinate.
    let text = "import joints; import gravity;\n\
        let crank = body mass = 1, iframe = [0.5, 0, 0] ++ 1, inertia = [0.01, 0.1, 0.1] end;\n\
        let lever = body mass = 3, iframe = [2, 0, 0] ++ 1, inertia = [0.01, 4, 4] end;\n\
        let block = body mass = 0.5, iframe = 0, inertia = [0.01, 0.01, 0.02] end;\n\
        join earth and crank with revolute([0, 0, 1]) as turn;\n\
        join [-2, 0, 0] ++ 1 @ earth and lever with revolute([0, 0, 1]) as rock;\n\
        join [1, 0, 0] ++ 1 @ crank and block with revolute([0, 0, 1]) as pin;\n\
        join lever and block with prismatic([1, 0, 0]) as slide;\n\
        apply weight_in(crank, [0, -9.81, 0]) on crank.iframe;\n\
        apply weight_in(lever, [0, -9.81, 0]) on lever.iframe;\n\
        apply weight_in(block, [0, -9.81, 0]) on block.iframe;\n\
        simulate duration = 5, output = 0.01, tolerance = 1e-12 end;\n\
        initial turn.q = 1.2 fixed, rock.q = 0.4, pin.q = -0.8, slide.q = 2.5, turn.q' = 4;\n";
    let options = LoadOptions {
        library_dirs: Vec::new(),
        use_environment: false,
        scene: None,
    };
    let mechanism = compile_text("lever.lsd", text, None, &options)
        .mechanism
        .expect("elaborates");
    let p = prepare(&mechanism, &[], &Settings::default())
        .unwrap_or_else(|d| panic!("{:?}", d[0].message));
    let simulation = simulated(&p);
    assert_eq!(p.model.loops.len(), 1);
    assert_eq!(p.model.loops[0].name, "slide");
    let c = constraints(&simulation);
    assert_eq!((c.rows, c.rank), (6, 3));
    assert!(c.position_residual < 1e-12, "{:e}", c.position_residual);
    assert!(simulation.report.energy_drift.expect("conservative") < 1e-9);
    // Closed form: the lever points from D to the crank's end A, and the block is |A − D| from D.
    let (turn, rock, slide) = (
        column(&simulation, "turn.q"),
        column(&simulation, "rock.q"),
        column(&simulation, "slide.q"),
    );
    for s in &simulation.samples {
        let a = s.coordinates[turn];
        let (x, y) = (a.cos() + 2.0, a.sin());
        assert!(
            (s.coordinates[rock] - y.atan2(x)).sin().abs() < 1e-10,
            "t = {}",
            s.time
        );
        assert!(
            (s.coordinates[slide] - x.hypot(y)).abs() < 1e-10,
            "t = {}",
            s.time
        );
    }
    let turns = (simulation.samples.last().expect("outputs").coordinates[turn] - 1.2)
        / std::f64::consts::TAU;
    assert!(turns.abs() > 1.0, "the crank turns: {turns}");
}

#[test]
fn a_force_on_a_motion_without_mass_is_caught_after_the_start() {
    // The Delta with a torque that grows from zero about a rod's own axis (the third angle of its
    // ball joint): that spin moves no mass. At the start the torque is zero and the choice of the
    // motions solved on passes; the check after each step must stop the run once it acts.
    let mut p = prepared(
        "delta_isir88",
        &[(
            "join [l1, w, 0] ++ 1 @ arm1 and rod1p with spherical as C1p",
            "join [l1, w, 0] ++ 1 @ arm1 and rod1p with link(a, b, c) dof1 = a || [1,0,0], dof2 = b || [0,1,0], dof3 = c || [0,0,1], torque3 = [0, 0, 10 * time] end as C1p",
        )],
    );
    p.settings.duration = 0.05;
    let simulation = run(&p, &mut |_| {});
    let failure = simulation.report.failure.as_ref().expect("fails");
    assert!(
        failure.message.contains("moves no mass") && failure.time > 0.0,
        "{} at {}",
        failure.message,
        failure.time
    );
}
