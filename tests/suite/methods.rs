//! The integrators on mechanisms: the variational integrator keeps the energy of a long
//! conservative run bounded, the implicit one agrees with Dormand–Prince, and an ill-posed
//! mechanism (a massless body that nothing holds) fails with the join named.

use crate::common::programs::{prepared, simulated};
use lsdc::driver::compile_text;
use lsdc::load::LoadOptions;
use lsdc::prepare::{prepare, Integrator, Settings};
use lsdc::simulate::run::{run, Simulation};

const DOUBLE_PENDULUM: &str = "import joints;\n\
    let upper = body mass = 1.0, iframe = [0, 0, -0.5] ++ 1, inertia = [0.02, 0.02, 0.001] end;\n\
    let lower = body mass = 0.7, iframe = [0, 0, -0.4] ++ 1, inertia = [0.01, 0.01, 0.001] end;\n\
    join earth and upper with revolute([1, 0, 0]) as shoulder;\n\
    join [0, 0, -1] ++ 1 @ upper and lower with revolute([1, 0, 0]) as elbow;\n\
    apply force value = [0, 0, -9.81 * upper.mass], body = earth end on upper.iframe;\n\
    apply force value = [0, 0, -9.81 * lower.mass], body = earth end on lower.iframe;\n\
    initial shoulder.q = 1.2, elbow.q = -0.5;\n";

fn simulate(text: &str, settings: Settings) -> Simulation {
    let options = LoadOptions {
        library_dirs: Vec::new(),
        use_environment: false,
        scene: None,
    };
    let compilation = compile_text("test.lsd", text, None, &options);
    assert!(!compilation.has_errors(), "{:?}", compilation.diagnostics);
    let prepared = prepare(&compilation.mechanism.expect("elaborates"), &[], &settings)
        .unwrap_or_else(|d| panic!("{d:?}"));
    run(&prepared, &mut |_| {})
}

#[test]
fn variational_integrator_keeps_the_energy_bounded_over_long_runs() {
    let settings = |duration| Settings {
        integrator: Integrator::Symplectic,
        duration,
        output: 0.5,
        step: Some(2e-3),
        ..Settings::default()
    };
    let short = simulate(DOUBLE_PENDULUM, settings(20.0));
    let long = simulate(DOUBLE_PENDULUM, settings(200.0));
    assert!(long.report.failure.is_none(), "{:?}", long.report.failure);
    let (short_drift, long_drift) = (
        short.report.energy_drift.expect("conservative"),
        long.report.energy_drift.expect("conservative"),
    );
    // A symplectic method's energy error oscillates without growing: ten times longer, not ten
    // times worse (a drifting method would be), and small for this step.
    assert!(long_drift < 1e-4, "energy error {long_drift:e}");
    assert!(
        long_drift < 3.0 * short_drift,
        "energy error grows: {short_drift:e} over 20 s, {long_drift:e} over 200 s"
    );
}

#[test]
fn implicit_and_explicit_integrators_agree() {
    let tight = Settings {
        integrator: Integrator::DormandPrince,
        duration: 2.0,
        output: 0.5,
        rtol: 1e-12,
        atol: 1e-12,
        ..Settings::default()
    };
    let implicit = Settings {
        integrator: Integrator::Implicit,
        rtol: 1e-9,
        atol: 1e-9,
        ..tight.clone()
    };
    let reference = simulate(DOUBLE_PENDULUM, tight);
    let stiff = simulate(DOUBLE_PENDULUM, implicit);
    assert!(stiff.report.failure.is_none(), "{:?}", stiff.report.failure);
    let (a, b) = (
        reference.samples.last().expect("samples"),
        stiff.samples.last().expect("samples"),
    );
    for k in 0..2 {
        assert!(
            (a.coordinates[k] - b.coordinates[k]).abs() < 1e-6,
            "{:?} vs {:?}",
            a.coordinates,
            b.coordinates
        );
    }
}

#[test]
fn rk4_converges_at_fourth_order() {
    let error = |step: f64| {
        let reference = simulate(
            DOUBLE_PENDULUM,
            Settings {
                integrator: Integrator::DormandPrince,
                duration: 1.0,
                output: 1.0,
                rtol: 1e-13,
                atol: 1e-13,
                ..Settings::default()
            },
        );
        let fixed = simulate(
            DOUBLE_PENDULUM,
            Settings {
                integrator: Integrator::Rk4,
                duration: 1.0,
                output: 1.0,
                step: Some(step),
                ..Settings::default()
            },
        );
        (reference.samples.last().expect("").coordinates[1]
            - fixed.samples.last().expect("").coordinates[1])
            .abs()
    };
    let ratio = error(0.005) / error(0.0025);
    assert!(
        (12.0..20.0).contains(&ratio),
        "error ratio {ratio} for a halved step"
    );
}

#[test]
fn a_massless_body_with_nothing_to_move_stops_the_run_with_the_join_named() {
    let text = "import joints;\nlet arm = body mass = 1, iframe = 0, inertia = [1, 1, 1] end;\n\
        let ghost = body mass = 0, inertia = 0 end;\n\
        join earth and arm with revolute([0, 0, 1]) as hinge;\n\
        join [1, 0, 0] ++ 1 @ arm and ghost with revolute([0, 0, 1]) as flap;\n\
        initial hinge.q' = 1;\n";
    let simulation = simulate(
        text,
        Settings {
            duration: 1.0,
            ..Settings::default()
        },
    );
    let failure = simulation.report.failure.expect("the run fails");
    assert!(
        failure.message.contains("`flap`") && failure.message.contains("singular"),
        "{}",
        failure.message
    );
    assert_eq!(failure.time, 0.0);
}

#[test]
fn massless_arm_segments_carrying_a_mass_are_well_posed() {
    // The satellite's arms have no mass, but the reflector at their end gives every joint inertia.
    let text = std::fs::read_to_string("examples/satellite_fixed.lsd").expect("example");
    let simulation = simulate(
        &text,
        Settings {
            duration: 0.5,
            ..Settings::default()
        },
    );
    assert!(
        simulation.report.failure.is_none(),
        "{:?}",
        simulation.report.failure
    );
}

#[test]
fn an_effort_that_is_not_a_number_stops_the_run_when_and_where_it_happens() {
    // The spring force sqrt(1 - x) has no value once the slider passes x = 1.
    let text = "import joints;\nlet block = body mass = 1, iframe = 0, inertia = [1, 1, 1] end;\n\
        join earth and block with link(x) dof = [x, 0, 0], force = [sqrt(1 - x), 0, 0] end as slide;\n";
    let simulation = simulate(
        text,
        Settings {
            duration: 3.0,
            output: 0.1,
            ..Settings::default()
        },
    );
    let failure = simulation.report.failure.expect("the run fails");
    assert!(
        failure.message.contains("`slide`") && failure.message.contains("not a number"),
        "{}",
        failure.message
    );
    // x = t²/2 under a unit force: x reaches 1 at t = √2.
    assert!(failure.time > 1.2 && failure.time < 1.5, "{}", failure.time);
    let last = simulation
        .samples
        .last()
        .expect("outputs before the failure are kept");
    assert!(last.time <= failure.time && last.time > 1.2);
}

#[test]
fn gravity_from_the_standard_library_weighs_each_body() {
    let text = "import joints; import gravity;\n\
        let rod = body mass = 2, iframe = [0, 0, -0.5] ++ 1, inertia = [0.1, 0.1, 0.01] end;\n\
        join earth and rod with prismatic([0, 0, 1]) as drop;\n\
        apply weight(rod) on rod.iframe;\n";
    let simulation = simulate(
        text,
        Settings {
            duration: 1.0,
            output: 1.0,
            rtol: 1e-12,
            atol: 1e-12,
            ..Settings::default()
        },
    );
    let last = simulation.samples.last().expect("samples");
    // Free fall: z = -g t²/2.
    assert!(
        (last.coordinates[0] + 0.5 * 9.80665).abs() < 1e-10,
        "{:?}",
        last.coordinates
    );
}

#[test]
fn satellite_passes_through_the_euler_angle_singularity() {
    // The satellite's free link uses Z-X-Z Euler angles (ps, th, ph), singular at th = 0: start
    // there, with the nutation rate carrying it through, and the run goes on, reporting angles
    // that keep describing the same attitude.
    let text = std::fs::read_to_string("examples/satellite_springs.lsd")
        .expect("example")
        .replace("initial base.th = 0.5,", "initial base.th = 0,")
        .replace("base.th' = 0.01", "base.th' = -0.2");
    let simulation = simulate(
        &text,
        Settings {
            duration: 2.0,
            output: 0.01,
            rtol: 1e-10,
            atol: 1e-10,
            ..Settings::default()
        },
    );
    assert!(
        simulation.report.failure.is_none(),
        "{:?}",
        simulation.report.failure
    );
    let th = simulation
        .coordinate_names
        .iter()
        .position(|n| n == "base.th")
        .expect("th");
    assert_eq!(
        simulation.samples[0].coordinates[th], 0.0,
        "starts at the singularity"
    );
    let farthest = simulation
        .samples
        .iter()
        .map(|s| s.coordinates[th].abs())
        .fold(0.0, f64::max);
    assert!(
        farthest > 0.3,
        "th leaves the singularity: at most {farthest}"
    );
    assert!(
        simulation.samples.iter().all(|s| s
            .coordinates
            .iter()
            .chain(&s.rates)
            .all(|x| x.is_finite())),
        "finite outputs"
    );
    assert!(
        simulation.report.momentum_drift.expect("free").angular < 1e-8,
        "{:?}",
        simulation.report.momentum_drift
    );
}

/// The flyball governor's state at t = 1 s (`examples/governor.lsd`): coordinates then rates, in
/// its declaration order (spin, hinge1, hinge2, collar). Computed by lsdc's DOP853 at
/// rtol = atol = 1e-14 (77,432 steps, at commit bacbbb4); dopri5 at 1e-12 (87,360 steps) and
/// DOP853 at 1e-13 agree with it to 4e-13 in every component.
const GOVERNOR_AT_ONE_SECOND: [f64; 8] = [
    7.612368864679464,
    -0.7194106848370982,
    0.7194106848370982,
    0.3403406705758196,
    6.454663133803737,
    0.19815403521743435,
    -0.19815403521743435,
    -0.36495469273499875,
];

#[test]
fn the_implicit_integrator_takes_the_stiff_governor_to_its_tolerance() {
    // The governor's springs and dampers hold dopri5 at its stability boundary (17,000 steps
    // over 1 s at any tolerance); the implicit integrator goes over to Radau IIA. Its global
    // error at t = 1 measured: positions 1.6e-7 and 5.9e-10, rates 9.1e-7 and 2.4e-9 at 1e-6
    // and 1e-8, in 205 and 394 steps. At 1e-8 dopri5's first 64 steps resolve the start of
    // the initial transient, Radau IIA the rest in 330: at least a third of the steps are
    // stiff, and all take a fifth of dopri5's or less.
    for tolerance in [1e-6, 1e-8] {
        let mut governor = prepared("governor", &[]);
        governor.settings = Settings {
            integrator: Integrator::Implicit,
            duration: 1.0,
            output: 0.5,
            rtol: tolerance,
            atol: tolerance,
            ..governor.settings
        };
        let simulation = simulated(&governor);
        let last = simulation.samples.last().expect("samples");
        assert!((last.time - 1.0).abs() < 1e-12);
        let state = [&last.coordinates[..], &last.rates[..]].concat();
        let error = |range: std::ops::Range<usize>| {
            range
                .map(|i| (state[i] - GOVERNOR_AT_ONE_SECOND[i]).abs())
                .fold(0.0, f64::max)
        };
        let (positions, rates) = (error(0..4), error(4..8));
        eprintln!(
            "governor at {tolerance:e}: errors {positions:.1e} (positions), {rates:.1e} (rates), {:?} steps, {:?} stiff",
            simulation.report.steps, simulation.report.stiff_steps
        );
        assert!(positions < 5.0 * tolerance, "positions: {positions:e}");
        assert!(rates < 50.0 * tolerance, "rates: {rates:e}");
        let stiff = simulation.report.stiff_steps.expect("counted");
        assert!(
            3 * stiff > simulation.report.steps && 5 * simulation.report.steps < 17_000,
            "{} steps, {stiff} stiff",
            simulation.report.steps
        );
    }
}

#[test]
fn the_implicit_integrators_outputs_between_steps_are_as_accurate_as_its_steps() {
    // Radau IIA's collocation polynomial is of order 3 inside a step, where its steps' ends are
    // of order 5: on the governor at 1e-9 (0.5 s, outputs every 0.01 s) the coordinates at the
    // outputs were off by 7.6e-11 with it, against a reference by DOP853 at 1e-12. The quintic
    // through the last three step ends, on the components whose slopes are not stiff (the
    // coordinates), measured: 1.3e-11, and the rates (still from the collocation polynomial)
    // 3.2e-9; the quintic on the rates too made theirs twice as large (5.9e-9 over 1 s). Since
    // the first Newton iteration after dopri5 hands over is judged on its correction: 5.8e-13
    // and 1.7e-9.
    let (positions, rates) = implicit_governor_errors(1e-9, 0.5);
    eprintln!("governor at 1e-9 between steps: {positions:.1e} (positions), {rates:.1e} (rates)");
    assert!(positions < 3e-11, "positions: {positions:e}");
    assert!(rates < 5e-9, "rates: {rates:e}");
}

#[test]
fn the_implicit_integrator_reaches_dopri5s_position_error_on_the_governor_at_3e_9() {
    // dopri5 at 1e-6, held at its stability limit, is accurate to 3.0e-11 in the governor's
    // coordinates over 1 s (`BENCHMARKS.md`); the implicit integrator reaches that at 3e-9,
    // for 0.08 of dopri5's CPU time. Measured: 1.4e-11. Before Radau IIA's first Newton
    // iteration after dopri5 handed over was judged on its correction (its first iterate was
    // taken as converged), 6.3e-11: the transient's error stayed in the slow motion.
    let (positions, _) = implicit_governor_errors(3e-9, 1.0);
    eprintln!("governor at 3e-9 over 1 s: {positions:.1e} (positions)");
    assert!(positions < 3e-11, "positions: {positions:e}");
}

/// The largest errors of the governor's coordinates and rates at its outputs (every 0.01 s over
/// `duration`) with the implicit integrator at `tolerance`, against DOP853 at 1e-12.
fn implicit_governor_errors(tolerance: f64, duration: f64) -> (f64, f64) {
    let run = |integrator: Integrator, tolerance: f64| {
        let mut governor = prepared("governor", &[]);
        governor.settings = Settings {
            integrator,
            duration,
            output: 0.01,
            rtol: tolerance,
            atol: tolerance,
            ..governor.settings
        };
        simulated(&governor)
    };
    let reference = run(Integrator::Dop853, 1e-12);
    let implicit = run(Integrator::Implicit, tolerance);
    assert_eq!(reference.samples.len(), implicit.samples.len());
    let (mut positions, mut rates) = (0.0f64, 0.0f64);
    for (exact, sample) in reference.samples.iter().zip(&implicit.samples) {
        assert!((exact.time - sample.time).abs() < 1e-12);
        let largest = |a: &[f64], b: &[f64]| {
            a.iter()
                .zip(b)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max)
        };
        positions = positions.max(largest(&exact.coordinates, &sample.coordinates));
        rates = rates.max(largest(&exact.rates, &sample.rates));
    }
    (positions, rates)
}

#[test]
fn the_implicit_integrator_takes_the_stiff_method_early_in_the_governors_transient() {
    // Dormand–Prince starts, and its steps resolve the damped modes' initial transient. Once
    // its stage estimate h |λ| has been above 1 for 15 steps in a row, Radau IIA takes over.
    // Waiting for h |λ| above its stability boundary (3.25) instead took the switch to
    // t = 0.018 at 1e-8 and t = 0.56 at 1e-10. Measured: at t = 5.9e-4 (1e-6) and 4.7e-4 (1e-10).
    use lsdc::dynamics::loops::Stabilisation;
    use lsdc::integrate::{integrate, Method, Settings as Tolerances};
    use lsdc::simulate::system::MechanicalSystem;

    let governor = prepared("governor", &[]);
    let (q, v) = governor
        .model
        .state_from_declared(&governor.coordinates, &governor.rates)
        .expect("state");
    let y0 = [q, v].concat();
    for tolerance in [1e-6, 1e-10] {
        let reference = governor.coordinates.clone();
        let mut system =
            MechanicalSystem::new(&governor.model, reference, Stabilisation::Projection);
        let settings = Tolerances {
            rtol: tolerance,
            atol: tolerance,
            ..Tolerances::default()
        };
        let (_, stats) = integrate(
            &Method::Automatic,
            &mut system,
            0.0,
            &y0,
            1.0,
            &[],
            &settings,
            &mut |_, _| Ok(()),
        )
        .expect("integrated");
        let from = stats.stiff_from.expect("the stiff method taken");
        eprintln!(
            "governor at {tolerance:e}: stiff from t = {from:.2e}, {} of {} steps, {} switches",
            stats.stiff_steps, stats.steps, stats.method_switches
        );
        assert!(from < 2e-3, "switched at t = {from}");
    }
}

/// A pendulum whose bob hangs on a stiff damped spring (8e5 N/m, 4e4 N s/m: a mode at 3.3e4
/// /s), released onto a stop with restitution 0.5. Dormand–Prince is held by that mode to
/// steps of 1e-4 s over the whole run; the implicit integrator takes Radau IIA, leaves it just
/// after each impact (its first steps there are short enough for the explicit method) and must
/// take it again: it went on with the explicit method for the rest of the run, at its
/// stability limit (96,761 steps over 10 s at 1e-10). The impacts are those of dopri5.
#[test]
fn the_implicit_integrator_takes_radau_again_after_an_impact_on_a_stiff_pendulum() {
    let text = "import joints ;\n\
        let rod = body mass = 0, inertia = 0 end ;\n\
        let bob = body mass = 1.2, iframe = 0, inertia = [0.01, 0.01, 0.001] end ;\n\
        join earth and rod.frame with limited_revolute([1, 0, 0], 0, pi, 0.5) as swing ;\n\
        join rod.frame and bob.frame with link(r) dof = [0, 0, -r] end as stretch ;\n\
        apply force value = (8e5 * (0.5 - stretch.r) - 4e4 * stretch.r') * [0, 0, -1], body = rod end on bob.frame ;\n\
        apply force value = [0, 0, -9.81 * bob.mass], body = earth end on bob.frame ;\n\
        initial swing.q = pi / 2, stretch.r = 0.5 ;\n";
    let run_with = |integrator| {
        let settings = Settings {
            integrator,
            duration: 3.0,
            output: 0.5,
            rtol: 1e-10,
            atol: 1e-10,
            ..Settings::default()
        };
        let simulation = simulate(text, settings);
        assert!(
            simulation.report.failure.is_none(),
            "{:?}",
            simulation.report.failure
        );
        simulation.report
    };
    let implicit = run_with(Integrator::Implicit);
    let explicit = run_with(Integrator::DormandPrince);
    eprintln!(
        "stiff pendulum on its stop: implicit {} steps ({:?} stiff), dopri5 {}",
        implicit.steps, implicit.stiff_steps, explicit.steps
    );
    assert_eq!(implicit.impacts.len(), 4);
    assert_eq!(explicit.impacts.len(), 4);
    for (a, b) in implicit.impacts.iter().zip(&explicit.impacts) {
        assert!((a.time - b.time).abs() < 1e-9, "{} / {}", a.time, b.time);
    }
    let stiff = implicit.stiff_steps.expect("counted");
    assert!(
        10 * implicit.steps < explicit.steps && 5 * stiff > 4 * implicit.steps,
        "{} steps, {stiff} stiff",
        implicit.steps
    );
}
