//! A simulation stepped from Rust (`api::Simulator`): its steps are the run's, efforts held
//! between steps move a slider along the closed form of piecewise constant forces, a feedback
//! law evaluated at every stage gives the motion of the same law written in LSD, a reset starts
//! the same run again, and a wrong input says what it should have been.

use lsdc::api::{run, Integrator, Prepared, Program, SettingsChanges, Simulator, Start};

const SLIDER: &str = "
    import joints;
    let block = body mass = 2, iframe = 0, inertia = [1, 1, 1] end;
    join earth and block with prismatic([1, 0, 0]) as slide;
    initial slide.q = 0.25, slide.q' = -0.5;
    simulate duration = 1, output = 0.1, integrator = dopri5, tolerance = 1e-10 end;";

const PD_IN_LSD: &str = "
    import joints;
    let rod = body mass = 1.2, iframe = [0, 0, -0.5] ++ 1, inertia = [0.1, 0.1, 0.001] end;
    let pd = link(q) dof = q || [1, 0, 0], torque = [-20 * (q - 0.5) - 3 * q', 0, 0] end;
    join earth and rod with pd as swing;
    apply force value = [0, 0, -9.81 * rod.mass], body = earth end on rod.iframe;
    initial swing.q = pi / 3;
    simulate duration = 2, output = 0.05, integrator = dopri5, tolerance = 1e-10 end;";

fn prepared(text: &str, changes: &SettingsChanges) -> Prepared {
    let program = Program::from_text("test.lsd", text, None, &Default::default());
    assert!(!program.has_errors(), "{}", program.render());
    program.prepare(&[], changes).expect("prepares")
}

fn pendulum(changes: &SettingsChanges) -> Prepared {
    let program = Program::from_file("examples/pendulum.lsd", &Default::default()).expect("loads");
    program.prepare(&[], changes).expect("prepares")
}

fn with_integrator(integrator: Integrator) -> SettingsChanges {
    SettingsChanges {
        integrator: Some(integrator.clone()),
        duration: Some(1.0),
        ..Default::default()
    }
}

/// The samples of a simulator stepped to the end of its duration, then finished.
fn stepped_to_the_end(simulator: &mut Simulator<'_>) -> Vec<lsdc::api::Sample> {
    let mut samples = Vec::new();
    while simulator.step().is_ok() {
        samples.extend(simulator.take_samples());
    }
    samples
}

#[test]
fn stepping_to_the_end_gives_the_runs_samples_with_every_integrator() {
    for integrator in [
        Integrator::Rk4,
        Integrator::DormandPrince,
        Integrator::Dop853,
        Integrator::Implicit,
        Integrator::Symplectic,
    ] {
        let changes = with_integrator(integrator.clone());
        for prepared in [pendulum(&changes), {
            let program = Program::from_file("examples/four_bar.lsd", &Default::default());
            program
                .expect("loads")
                .prepare(&[], &changes)
                .expect("prepares")
        }] {
            let whole = run(&prepared, &mut |_| {});
            let mut simulator = Simulator::new(&prepared, &[]).expect("starts");
            let mut samples = stepped_to_the_end(&mut simulator);
            assert_eq!(simulator.time(), 1.0, "{integrator:?}");
            let (rest, report) = simulator.finish();
            samples.extend(rest);
            assert_eq!(samples.len(), whole.samples.len(), "{integrator:?}");
            for (stepped, ran) in samples.iter().zip(&whole.samples) {
                assert_eq!(stepped.time, ran.time);
                assert_eq!(stepped.coordinates, ran.coordinates, "{integrator:?}");
                assert_eq!(stepped.rates, ran.rates, "{integrator:?}");
            }
            assert_eq!(report.steps, whole.report.steps);
            assert_eq!(
                report.function_evaluations,
                whole.report.function_evaluations
            );
            assert!(report.failure.is_none() && whole.report.failure.is_none());
        }
    }
}

/// Forces held over periods of 0.1 s on a free slider of mass 2: x and v follow the closed form
/// of constant accelerations, which RK4, Dormand–Prince and the implicit method integrate
/// exactly, and the work of the inputs equals the kinetic energy gained.
#[test]
fn stepping_held_forces_move_a_slider_along_the_closed_form() {
    let forces = [1.0, -3.0, 0.5, 2.0, 0.0, -1.5, 4.0, -2.0, 1.0, 3.0];
    for integrator in [
        Integrator::Rk4,
        Integrator::DormandPrince,
        Integrator::Implicit,
    ] {
        let prepared = prepared(SLIDER, &with_integrator(integrator.clone()));
        let mut simulator = Simulator::new(&prepared, &["slide.q"]).expect("starts");
        assert_eq!(simulator.input_names(), ["slide.q"]);
        let (mass, period) = (2.0, 0.1);
        let (mut x, mut v) = (0.25, -0.5);
        for (k, force) in forces.iter().enumerate() {
            simulator.set_inputs(&[*force]).expect("one input");
            let end = (k + 1) as f64 * period;
            simulator.advance_to(end).expect("steps");
            // Each period is landed on exactly.
            assert_eq!(simulator.time(), end);
            let a = force / mass;
            x += v * period + 0.5 * a * period * period;
            v += a * period;
            let (coordinates, rates) = simulator.coordinates().expect("state");
            assert!(
                (coordinates[0] - x).abs() <= 1e-12,
                "{integrator:?}: {} {x}",
                coordinates[0]
            );
            assert!(
                (rates[0] - v).abs() <= 1e-12,
                "{integrator:?}: {} {v}",
                rates[0]
            );
        }
        let sample = simulator.sample().expect("sample");
        let gained = 0.5 * mass * (v * v - 0.25);
        let work = sample.work.expect("the inputs' work is integrated");
        assert!(
            (work - gained).abs() <= 1e-12,
            "{integrator:?}: {work} {gained}"
        );
        let (_, report) = simulator.finish();
        assert!(report.failure.is_none());
        assert!(report.energy_balance.expect("a balance") <= 1e-12);
    }
}

/// A PD law on the pendulum, in Rust through the law of its input and in LSD as its joint's
/// torque: the same motion to round-off with each integrator.
#[test]
fn stepping_a_law_in_rust_gives_the_motion_of_the_same_law_in_lsd() {
    for integrator in [
        Integrator::Rk4,
        Integrator::DormandPrince,
        Integrator::Implicit,
    ] {
        let changes = SettingsChanges {
            integrator: Some(integrator.clone()),
            duration: Some(2.0),
            ..Default::default()
        };
        let plant = pendulum(&changes);
        let mut simulator = Simulator::new(&plant, &["swing.q"]).expect("starts");
        simulator.set_law(|_, q, v, torque| torque[0] = -20.0 * (q[0] - 0.5) - 3.0 * v[0]);
        simulator.advance_to(2.0).expect("steps");
        let (from_rust, _) = simulator.finish();
        let in_lsd = run(&prepared(PD_IN_LSD, &changes), &mut |_| {});
        assert_eq!(from_rust.len(), in_lsd.samples.len());
        let mut largest: f64 = 0.0;
        for (rust, lsd) in from_rust.iter().zip(&in_lsd.samples) {
            largest = largest.max((rust.coordinates[0] - lsd.coordinates[0]).abs());
            largest = largest.max((rust.rates[0] - lsd.rates[0]).abs());
            assert!((rust.work.unwrap() - lsd.work.unwrap()).abs() <= 1e-12);
        }
        assert!(largest <= 1e-12, "{integrator:?}: {largest:e}");
        // Without the law, the pendulum swings far from the target.
        let free = run(&plant, &mut |_| {});
        let last = free.samples.last().unwrap().coordinates[0];
        assert!((last - from_rust.last().unwrap().coordinates[0]).abs() > 0.1);
    }
}

#[test]
fn stepping_again_after_a_reset_repeats_the_run() {
    let prepared = prepared(SLIDER, &with_integrator(Integrator::DormandPrince));
    let first = {
        let mut simulator = Simulator::new(&prepared, &["slide.q"]).expect("starts");
        simulator.set_inputs(&[1.5]).expect("one input");
        stepped_to_the_end(&mut simulator)
    };
    let mut simulator = Simulator::new(&prepared, &["slide.q"]).expect("starts");
    simulator.set_inputs(&[1.5]).expect("one input");
    simulator.advance_to(0.35).expect("steps");
    let start = Start {
        coordinates: &prepared.coordinates,
        rates: &prepared.rates,
    };
    simulator.reset(&start).expect("resets");
    assert_eq!(simulator.time(), 0.0);
    simulator.take_samples();
    // The held input is kept across the reset.
    let again = stepped_to_the_end(&mut simulator);
    assert_eq!(first.len(), again.len());
    for (a, b) in first.iter().zip(&again) {
        assert_eq!(
            (a.time, &a.coordinates, &a.rates),
            (b.time, &b.coordinates, &b.rates)
        );
    }
}

#[test]
fn stepping_says_what_it_cannot_do() {
    let plant = pendulum(&SettingsChanges::default());
    let unknown = Simulator::new(&plant, &["swing.qq"])
        .err()
        .expect("refused");
    assert!(
        unknown.message.contains("no velocity `swing.qq`")
            && unknown.message.contains("did you mean `swing.q`?"),
        "{}",
        unknown.message
    );
    let mut simulator = Simulator::new(&plant, &["swing.q"]).expect("starts");
    let wrong = simulator.set_inputs(&[1.0, 2.0]).expect_err("refused");
    assert_eq!(wrong.message, "2 input efforts given for 1 inputs");
    simulator.advance_to(5.0).expect("steps");
    let past = simulator.step().expect_err("at the end");
    assert!(
        past.message.contains("advance it with `advance_to`"),
        "{}",
        past.message
    );
    simulator.advance_to(5.5).expect("steps past the duration");
    assert_eq!(simulator.time(), 5.5);
    let symplectic = pendulum(&with_integrator(Integrator::Symplectic));
    let refused = Simulator::new(&symplectic, &["swing.q"])
        .err()
        .expect("refused");
    assert!(
        refused.message.contains("does not apply inputs"),
        "{}",
        refused.message
    );
}
