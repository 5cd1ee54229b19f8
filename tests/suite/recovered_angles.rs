//! The angles of spherical and free joints, recovered from the quaternions the dynamics
//! integrates, keep every turn and stay continuous through a gimbal passage, whatever the
//! outputs' spacing: checked against the integral of their own rates, which no choice of
//! branch or turn enters, and against closed forms.

use lsdc::api::{run, Program, SettingsChanges, Simulation};

/// A run of `text` with `changes`, which must succeed.
fn simulate(text: &str, changes: SettingsChanges) -> Simulation {
    let program = Program::from_text("spun.lsd", text, None, &Default::default());
    let prepared = program.prepare(&[], &changes).expect("prepares");
    let simulation = run(&prepared, &mut |_| {});
    assert!(
        simulation.report.failure.is_none(),
        "{:?}",
        changes.integrator
    );
    simulation
}

fn every(output: f64) -> SettingsChanges {
    SettingsChanges {
        output: Some(output),
        ..Default::default()
    }
}

fn column(simulation: &Simulation, name: &str) -> usize {
    (simulation.coordinate_names.iter())
        .position(|n| n == name)
        .unwrap_or_else(|| panic!("no column {name}"))
}

/// Per sample, the coordinate `name` less its starting value plus the integral of its rate up
/// to the sample (trapezoidal rule over the samples): zero but for the rule's error when the
/// angle follows its rate.
fn departures_from_rate(simulation: &Simulation, name: &str) -> Vec<(f64, f64)> {
    // The rates are in the same columns as the coordinates.
    let (value, rate) = (column(simulation, name), column(simulation, name));
    let samples = &simulation.samples;
    let mut integral = samples[0].coordinates[value];
    let mut departures = vec![(samples[0].time, 0.0)];
    for pair in samples.windows(2) {
        let step = pair[1].time - pair[0].time;
        integral += 0.5 * step * (pair[0].rates[rate] + pair[1].rates[rate]);
        departures.push((pair[1].time, pair[1].coordinates[value] - integral));
    }
    departures
}

/// The largest difference of every coordinate between the samples of `coarse` and those of
/// `fine` at the same times.
fn largest_difference(coarse: &Simulation, fine: &Simulation) -> f64 {
    let mut largest = 0.0f64;
    for sample in &coarse.samples {
        let twin = (fine.samples.iter())
            .find(|s| (s.time - sample.time).abs() < 1e-9)
            .expect("a common output time");
        for (a, b) in sample.coordinates.iter().zip(&twin.coordinates) {
            largest = largest.max((a - b).abs());
        }
    }
    largest
}

/// A Lagrange top on classical Euler angles (precession ψ about the vertical, nutation θ, spin
/// φ), spun at 60 rad/s and nutating so that its spin rate reaches 72 rad/s: with outputs
/// every 0.05 s it turns more than π between two of them. Its spin was reported 8,118 rad
/// behind after 100 s (outputs every 0.05 s; −1,610.8 for 6,507.1), the angle recovered at
/// each output on the branch nearest the previous output. Now it follows its rate's
/// integral (from outputs every 0.001 s) to 1e-3 over the 100 s, and the angles at every 0.05 s
/// and every 0.01 s agree; ω3 = φ̇ + ψ̇ cos θ, conserved (the top's symmetry), checks the
/// rates themselves.
#[test]
fn a_fast_top_keeps_its_turns_whatever_the_outputs() {
    let top = "import joints ;\n\
        let euler = link(psi, theta, phi) dof1 = psi || [0, 0, 1], dof2 = theta || [1, 0, 0], \
        dof3 = phi || [0, 0, 1] end ;\n\
        let top = body mass = 1, iframe = [0, 0, 0.1] ++ 1, inertia = [0.01, 0.01, 0.015] end ;\n\
        join earth and top with euler as pivot ;\n\
        apply force value = [0, 0, -9.81 * top.mass], body = earth end on top.iframe ;\n\
        initial pivot.theta = 0.8, pivot.phi' = 60, pivot.psi' = 8 ;\n\
        simulate duration = 100, tolerance = 1e-10, integrator = dopri5 end ;\n";
    let fine = simulate(top, every(0.001));
    let coarse = simulate(top, every(0.05));
    let medium = simulate(top, every(0.01));
    for name in ["pivot.psi", "pivot.phi"] {
        let departures = departures_from_rate(&fine, name);
        let (time, worst) =
            (departures.iter()).fold((0.0, 0.0f64), |w, &(t, d)| match d.abs() > w.1 {
                true => (t, d.abs()),
                false => w,
            });
        assert!(
            worst < 1e-3,
            "{name} leaves its rate's integral by {worst} at t = {time}"
        );
    }
    let spin = column(&coarse, "pivot.phi");
    let end = coarse.samples.last().expect("samples");
    let fine_end = fine.samples.last().expect("samples");
    assert!((end.coordinates[spin] - fine_end.coordinates[spin]).abs() < 1e-9);
    assert!(end.coordinates[spin] > 6000.0, "{}", end.coordinates[spin]);
    assert!(largest_difference(&coarse, &fine) < 1e-9);
    assert!(largest_difference(&medium, &fine) < 1e-9);
    let [psi, theta, phi] = ["pivot.psi", "pivot.theta", "pivot.phi"].map(|n| column(&fine, n));
    let omega3 = 60.0 + 8.0 * 0.8f64.cos();
    for sample in &fine.samples {
        let (r, c) = (&sample.rates, &sample.coordinates);
        let axial = r[phi] + r[psi] * c[theta].cos();
        assert!(
            (axial - omega3).abs() < 1e-5,
            "t = {}: {axial}",
            sample.time
        );
    }
}

/// A wheel spinning at 70 rad/s about its axis turns 70 rad, eleven turns, in a second: with one
/// output a second its angle was reported as 0.885 (the branch nearest the previous output);
/// now 70 t with every integrator.
#[test]
fn a_wheel_keeps_its_turns_with_every_integrator() {
    let wheel = "import joints ;\n\
        let wheel = body mass = 1, iframe = 0, inertia = [0.5, 0.5, 1] end ;\n\
        join earth and wheel with spherical as hub ;\n\
        initial hub.c' = 70 ;\n\
        simulate duration = 2, output = 1, tolerance = 1e-10 end ;\n";
    let integrators = lsdc::integrators::INTEGRATORS.iter();
    for integrator in integrators.map(|entry| entry.integrator.clone()) {
        let name = format!("{integrator:?}");
        let changes = SettingsChanges {
            integrator: Some(integrator),
            ..Default::default()
        };
        let simulation = simulate(wheel, changes);
        let spin = column(&simulation, "hub.c");
        for sample in &simulation.samples {
            let got = sample.coordinates[spin];
            // A lost turn is 2π; what remains is each method's error at this tolerance.
            assert!(
                (got - 70.0 * sample.time).abs() < 1e-4,
                "{name} at t = {}: {got}",
                sample.time
            );
        }
    }
}

/// examples/rolling_ball.lsd passes near gimbal lock at t = 0.25: its Bryant middle angle b
/// comes within 0.082 rad of π/2 and turns back, while a and c swing by about π each at up to
/// 38 rad/s. Each output on the branch nearest the previous one (every 0.1 s) folded b to
/// π − b after the passage (1.875 at t = 0.3 instead of 1.267) and moved a and c by π against
/// their rates; chosen by nearness at each step, the mirror branch was taken inside the
/// passage. Now every angle follows its rate's integral through it (to 1e-3 at outputs every
/// 0.0005 s), b stays below π/2, and outputs every 0.1 s give the same angles.
#[test]
fn a_gimbal_passage_keeps_the_angles_continuous() {
    let text = std::fs::read_to_string("examples/rolling_ball.lsd").expect("the example");
    let changes = |output: f64| SettingsChanges {
        output: Some(output),
        duration: Some(0.6),
        ..Default::default()
    };
    let fine = simulate(&text, changes(0.0005));
    let coarse = simulate(&text, changes(0.1));
    for name in ["motion.a", "motion.b", "motion.c"] {
        for (time, departure) in departures_from_rate(&fine, name) {
            assert!(departure.abs() < 1e-3, "{name} at t = {time}: {departure}");
        }
    }
    let b = column(&fine, "motion.b");
    let highest = (fine.samples.iter())
        .map(|s| s.coordinates[b])
        .fold(f64::MIN, f64::max);
    assert!((1.48..1.50).contains(&highest), "{highest}");
    assert!(largest_difference(&coarse, &fine) < 1e-9);
}

/// The angles the outputs report are those the efforts see: an angle's spring pulls back by
/// k θ however many turns θ made, so a torsion spring on the spin of a spherical joint is a
/// harmonic oscillator in the spin angle (period 2π √(I/k)), here spun 12 turns out at its
/// start.
#[test]
fn efforts_see_the_same_turns() {
    let wheel = "import joints ;\n\
        let wound = link(a, b, c) dof1 = a || [1, 0, 0], dof2 = b || [0, 1, 0], \
        dof3 = c || [0, 0, 1], torque3 = [0, 0, -4 * c] end ;\n\
        let wheel = body mass = 1, iframe = 0, inertia = [0.5, 0.5, 1] end ;\n\
        join earth and wheel with wound as hub ;\n\
        initial hub.c' = 60 ;\n\
        simulate duration = 3, output = 0.25, tolerance = 1e-11, integrator = dop853 end ;\n";
    let simulation = simulate(wheel, SettingsChanges::default());
    let spin = column(&simulation, "hub.c");
    // c'' = −4 c with c(0) = 0, c'(0) = 60: c = 30 sin 2t, up to 30 rad.
    for sample in &simulation.samples {
        let expected = 30.0 * (2.0 * sample.time).sin();
        let got = sample.coordinates[spin];
        assert!((got - expected).abs() < 1e-6, "t = {}: {got}", sample.time);
    }
}
