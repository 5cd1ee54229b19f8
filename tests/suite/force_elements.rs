//! Force elements of the standard library (`import forces;`) against closed forms: two bodies on
//! prismatic links joined by a spring (and a damper), and the elastic pendulum's energy.

use lsdc::driver::compile_text;
use lsdc::load::LoadOptions;
use lsdc::prepare::{prepare, Settings};
use lsdc::simulate::run::{run, Simulation};

fn simulate(text: &str) -> Simulation {
    let options = LoadOptions {
        library_dirs: Vec::new(),
        use_environment: false,
        scene: None,
    };
    let compilation = compile_text("elements.lsd", text, None, &options);
    assert!(!compilation.has_errors(), "{:?}", compilation.diagnostics);
    let mechanism = compilation.mechanism.expect("a mechanism");
    let prepared = prepare(&mechanism, &[], &Settings::default()).expect("prepares");
    let simulation = run(&prepared, &mut |_| {});
    assert!(
        simulation.report.failure.is_none(),
        "{:?}",
        simulation.report.failure
    );
    simulation
}

/// Bodies of masses 2 and 3 on parallel slides, 1 m apart at rest, joined by `elements`.
fn two_bodies(elements: &str) -> String {
    format!(
        "import forces ;
        let b1 = body mass = 2, iframe = 0, inertia = [1, 1, 1] end ;
        let b2 = body mass = 3, iframe = 0, inertia = [1, 1, 1] end ;
        join earth and b1.frame with link(x) dof = [x, 0, 0] end as s1 ;
        join [1, 0, 0] ++ 1 @ earth and b2.frame with link(x) dof = [x, 0, 0] end as s2 ;
        {elements}
        initial s1.x = 0, s2.x = 0.1 ;
        simulate duration = 3, output = 0.05, tolerance = 1e-13 end ;"
    )
}

/// The gap s = 1 + x2 − x1 against `expected(t)`, and the centre of mass at rest.
fn check_relative_motion(simulation: &Simulation, expected: impl Fn(f64) -> f64) {
    let mut worst = 0.0f64;
    for sample in &simulation.samples {
        let (x1, x2) = (sample.coordinates[0], sample.coordinates[1]);
        let gap = 1.0 + x2 - x1;
        worst = worst.max((gap - expected(sample.time)).abs());
        assert!(
            (gap - expected(sample.time)).abs() < 1e-10,
            "t = {}: s = {gap}, closed form {}",
            sample.time,
            expected(sample.time)
        );
        assert!(
            (2.0 * x1 + 3.0 * x2 - 0.3).abs() < 1e-10,
            "the centre of mass moved"
        );
    }
    println!("largest gap from the closed form: {worst:.1e}");
}

#[test]
fn a_spring_between_two_bodies_oscillates_as_the_closed_form() {
    let simulation = simulate(&two_bodies(
        "apply spring(b1, b2, 150, 0.8) between b1 and b2 ;",
    ));
    // Relative motion: reduced mass 1.2, ω² = k / μ; s(0) = 1.1, at rest.
    let omega = (150.0f64 / 1.2).sqrt();
    check_relative_motion(&simulation, |t| 0.8 + 0.3 * (omega * t).cos());
    let drift = simulation
        .report
        .energy_drift
        .expect("conservative: the spring declares its potential");
    println!("energy drift {drift:.1e}");
    assert!(drift < 1e-10, "energy drift {drift:e}");
}

#[test]
fn a_damped_spring_decays_as_the_closed_form() {
    let simulation = simulate(&two_bodies("apply spring(b1, b2, 150, 0.8) between b1 and b2 ;\n apply damper(b1, b2, 4) between b1 and b2 ;"));
    // μ s̈ = −k (s − l0) − c ṡ, underdamped.
    let (mu, k, c) = (1.2f64, 150.0, 4.0);
    let omega = (k / mu).sqrt();
    let zeta = c / (2.0 * (k * mu).sqrt());
    let damped = omega * (1.0 - zeta * zeta).sqrt();
    check_relative_motion(&simulation, |t| {
        0.8 + 0.3
            * (-zeta * omega * t).exp()
            * ((damped * t).cos() + zeta * omega / damped * (damped * t).sin())
    });
    assert!(
        simulation.report.energy_drift.is_none(),
        "a damper has no potential: no drift to report"
    );
}

#[test]
fn the_elastic_pendulum_keeps_its_energy() {
    let simulation = simulate(
        "import forces ; import gravity ;
        let rod = body mass = 0, inertia = 0 end ;
        let bob = body mass = 1.5, iframe = 0, inertia = [0.01, 0.02, 0.03] end ;
        join earth and rod.frame with link(a) dof = a || [0,1,0] end as swing ;
        join rod.frame and bob.frame with link(r) dof = [0,0,-r] end as stretch ;
        apply spring(earth, bob, 200, 0.5) between earth and bob ;
        apply weight(bob) on bob.iframe ;
        initial swing.a = 0.6, stretch.r = 0.7, swing.a' = 0.4, stretch.r' = -0.1 ;
        simulate duration = 10, output = 0.1, tolerance = 1e-13 end ;",
    );
    let drift = simulation.report.energy_drift.expect("conservative");
    println!("elastic pendulum: energy drift {drift:.1e} over 10 s");
    assert!(drift < 1e-10, "energy drift {drift:e} over 10 s");
}

/// A chain of ten links under `weights`, simulated for 1 s.
fn chain(weights: &str) -> Simulation {
    let mut text = String::from("import joints ; import gravity ;\n");
    for i in 1..=10 {
        text += &format!("let b{i} = body mass = {}, iframe = [0.15, 0, 0] ++ 1, inertia = [0.01, 0.02, 0.02] end ;\n", 0.5 + 0.1 * i as f64);
        let parent = if i == 1 {
            "earth".to_string()
        } else {
            format!("[0.3, 0, 0] ++ 1 @ b{}", i - 1)
        };
        text += &format!(
            "join {parent} and b{i} with revolute([0, {}, 1]) as j{i} ;\n",
            i % 3
        );
    }
    text += weights;
    text += "initial j1.q = 0.4, j5.q = -0.3 ;\nsimulate duration = 1, output = 0.1 end ;";
    simulate(&text)
}

#[test]
fn a_gravity_field_equals_the_weights_applied_one_by_one_to_the_last_bit() {
    let field = chain("apply gravity_field ;\n");
    let explicit: String = (1..=10)
        .map(|i| format!("apply weight(b{i}) on b{i}.iframe ;\n"))
        .collect();
    let one_by_one = chain(&explicit);
    assert_eq!(field.samples.len(), one_by_one.samples.len());
    for (a, b) in field.samples.iter().zip(&one_by_one.samples) {
        assert_eq!(a.coordinates, b.coordinates, "t = {}", a.time);
        assert_eq!(a.rates, b.rates, "t = {}", a.time);
        assert_eq!(a.potential_energy, b.potential_energy);
    }
    assert!(
        field.report.energy_drift.is_some(),
        "a gravity field is conservative"
    );
}

#[test]
fn link_elements_act_as_written() {
    // A torsion spring alone: a harmonic oscillator of frequency sqrt(k / I) about q0.
    let spring = simulate(
        "import forces ;
        let wheel = body mass = 1, iframe = 0, inertia = [1, 1, 2] end ;
        join earth and wheel with revolute_spring([0, 0, 1], 8, 0.2) as hub ;
        initial hub.q = 0.5 ;
        simulate duration = 3, output = 0.1, tolerance = 1e-13 end ;",
    );
    let omega = (8.0f64 / 2.0).sqrt();
    for s in &spring.samples {
        let expected = 0.2 + 0.3 * (omega * s.time).cos();
        assert!(
            (s.coordinates[0] - expected).abs() < 1e-10,
            "t = {}: {} ≠ {expected}",
            s.time,
            s.coordinates[0]
        );
    }
    assert!(
        spring.report.energy_drift.is_some_and(|d| d < 1e-10),
        "the spring declares its potential"
    );
    // A geared motor with a constant torque: q = ratio τ t² / (2 I).
    let motor = simulate(
        "import forces ;
        let wheel = body mass = 1, iframe = 0, inertia = [1, 1, 2] end ;
        join earth and wheel with geared_motor([0, 0, 1], 0.25, 12) as hub ;
        simulate duration = 2, output = 0.1, tolerance = 1e-13 end ;",
    );
    for s in &motor.samples {
        let expected = 12.0 * 0.25 * s.time * s.time / (2.0 * 2.0);
        assert!(
            (s.coordinates[0] - expected).abs() < 1e-10 * (1.0 + expected),
            "t = {}",
            s.time
        );
    }
}

/// A light mass (10 g) held to a heavy pendulum by a spring-damper of k = 1e8 N/m whose damping
/// makes the fast mode heavily damped (ζ = 10), run with `integrator`.
fn stiff_chain(integrator: &str, tolerance: f64) -> (Simulation, Option<lsdc::diag::Diagnostic>) {
    let text = format!(
        "import forces ; import gravity ;
        let arm = body mass = 10, iframe = [0, 0, -0.5] ++ 1, inertia = [0.8, 0.8, 0.05] end ;
        let tip = body mass = 0.01, iframe = 0, inertia = [1e-6, 1e-6, 1e-6] end ;
        let end_of_arm = [0, 0, -1] ++ 1 @ arm ;
        join earth and arm with link(a) dof = a || [0, 1, 0] end as swing ;
        join end_of_arm and tip with link(s) dof = [0, 0, -s] end as slide ;
        apply spring(end_of_arm, tip, 1e8, 0.05) between end_of_arm and tip ;
        apply damper(end_of_arm, tip, 2e4) between end_of_arm and tip ;
        apply gravity_field ;
        initial swing.a = 0.5, slide.s = 0.05 ;
        simulate duration = 0.01, output = 0.001, integrator = {integrator}, tolerance = {tolerance:e} end ;"
    );
    let options = LoadOptions {
        library_dirs: Vec::new(),
        use_environment: false,
        scene: None,
    };
    let compilation = compile_text("stiff.lsd", &text, None, &options);
    assert!(!compilation.has_errors(), "{:?}", compilation.diagnostics);
    let mechanism = compilation.mechanism.expect("a mechanism");
    let prepared = prepare(&mechanism, &[], &Settings::default()).expect("prepares");
    let simulation = run(&prepared, &mut |_| {});
    let warning = lsdc::simulate::run::stiffness_warning(&simulation.report);
    (simulation, warning)
}

#[test]
fn the_implicit_integrator_handles_a_stiff_chain_with_a_hundredth_of_the_evaluations() {
    let (reference, _) = stiff_chain("implicit", 1e-10);
    let (explicit, warning) = stiff_chain("dopri5", 1e-6);
    let (implicit, no_warning) = stiff_chain("implicit", 1e-6);
    let angle = |s: &Simulation| s.samples.last().expect("samples").coordinates[0];
    let (e, i) = (
        (angle(&explicit) - angle(&reference)).abs(),
        (angle(&implicit) - angle(&reference)).abs(),
    );
    let (fe, fi) = (
        explicit.report.function_evaluations,
        implicit.report.function_evaluations,
    );
    println!(
        "swing angle error: dopri5 {e:.1e} ({fe} evaluations), implicit {i:.1e} ({fi} evaluations)"
    );
    assert!(
        e < 1e-6 && i < 1e-6,
        "both reach the tolerance on the slow motion: {e:e}, {i:e}"
    );
    assert!(100 * fi < fe, "implicit {fi} evaluations, explicit {fe}");
    let warning = warning.expect("the explicit run is warned");
    assert_eq!(warning.code, "W0901");
    assert!(warning.message.contains("stiff"), "{}", warning.message);
    assert!(!warning.labels.is_empty(), "the stiffest element is named");
    assert!(
        no_warning.is_none(),
        "no warning for the implicit integrator"
    );
}

#[test]
fn the_energy_balance_holds_on_a_driven_damped_mechanism() {
    // A double pendulum driven at its shoulder by a geared motor following a law in time, with a
    // torsion spring-damper at its elbow and a spring-damper from earth to its tip.
    let simulation = simulate(
        "import forces ; import gravity ;
        let upper = body mass = 2, iframe = [0, 0, -0.25] ++ 1, inertia = [0.05, 0.05, 0.01] end ;
        let lower = body mass = 1, iframe = [0, 0, -0.25] ++ 1, inertia = [0.02, 0.02, 0.005] end ;
        let tip = [0, 0, -0.5] ++ 1 @ lower ;
        join earth and upper with geared_motor([0, 1, 0], 0.4 * sin(3 * time), 12) as shoulder ;
        join [0, 0, -0.5] ++ 1 @ upper and lower with revolute_spring_damper([0, 1, 0], 3, 0.2, 0) as elbow ;
        apply spring([0.3, 0, -0.8] ++ 1 @ earth, tip, 40, 0.2) between [0.3, 0, -0.8] ++ 1 @ earth and tip ;
        apply damper([0.3, 0, -0.8] ++ 1 @ earth, tip, 1.5) between [0.3, 0, -0.8] ++ 1 @ earth and tip ;
        apply gravity_field ;
        initial shoulder.q = 0.3, elbow.q = -0.2 ;
        simulate duration = 5, output = 0.05, tolerance = 1e-11 end ;",
    );
    assert!(simulation.report.energy_drift.is_none(), "not conservative");
    let balance = simulation
        .report
        .energy_balance
        .expect("the work of the motor and dampers is integrated");
    let [kinetic, potential, work] = simulation.report.final_energies.expect("energies");
    println!("energy balance {balance:.1e}; at the end kinetic {kinetic:.3}, potential {potential:.3}, work {work:.3}");
    assert!(work.abs() > 0.1, "the motor and dampers do work");
    assert!(balance < 1e-8, "energy balance {balance:e}");
}

#[test]
fn a_target_spring_pulls_towards_a_moving_point() {
    // m x'' = k (0.1 t − x), at rest at 0: x = 0.1 t − 0.1 sin(ω t) / ω, ω² = k / m.
    let simulation = simulate(
        "import forces ;
        let cursor = body mass = 0.5, iframe = 0, inertia = [1, 1, 1] end ;
        join earth and cursor with link(x) dof = [x, 0, 0] end as slide ;
        apply target_spring(cursor, [0.1 * time, 0, 0], 18) on cursor ;
        simulate duration = 2, output = 0.05, tolerance = 1e-13 end ;",
    );
    let omega = (18.0f64 / 0.5).sqrt();
    for s in &simulation.samples {
        let expected = 0.1 * s.time - 0.1 * (omega * s.time).sin() / omega;
        assert!(
            (s.coordinates[0] - expected).abs() < 1e-10,
            "t = {}: {} ≠ {expected}",
            s.time,
            s.coordinates[0]
        );
    }
}
