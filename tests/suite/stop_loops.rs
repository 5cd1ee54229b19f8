//! Stops in mechanisms with closed loops and with contacts: the stop's row joins the loops' or
//! the contacts' rows at impacts and while resting. Oracles: the energy an impact takes from the
//! reduced equation of the mechanism's degrees of freedom (all of it but e² for a four-bar's
//! only one; for a rolling cylinder carrying a pendulum, the part normal to the stop from the
//! 2 × 2 reduced mass matrix in closed form), the closure at round-off, a coordinate resting on
//! its bound, and the release where the held force changes sign.

use super::common::programs::{
    column, constraints, example_text, initial_state, prepared, prepared_text, run_text, simulated,
};
use lsdc::prepare::{Integrator, Settings};
use lsdc::simulate::run::Simulation;

/// A run with `settings`, which must not fail.
fn simulate(text: &str, settings: Settings) -> Simulation {
    let simulation = run_text(text, settings);
    let failure = &simulation.report.failure;
    assert!(
        failure.is_none(),
        "{:?}: {failure:?}",
        simulation.report.integrator
    );
    simulation
}

fn settings(integrator: Integrator, duration: f64, tolerance: f64) -> Settings {
    Settings {
        integrator,
        duration,
        output: 0.05,
        rtol: tolerance,
        atol: tolerance,
        step: Some(1e-3),
        ..Settings::default()
    }
}

/// `examples/limited_four_bar.lsd` with the restitution of its crank's stop [0.6, 2.5], and
/// without its `simulate` settings (the tests give theirs): released from rest at crank = 1,
/// gravity brings the crank down onto 0.6.
fn four_bar(restitution: &str) -> String {
    let stop = format!("0.6, 2.5, {restitution})");
    let own = "simulate duration = 2, output = 0.05, integrator = dopri5, tolerance = 1e-10 end ;";
    example_text("limited_four_bar", &[("0.6, 2.5, 0.5)", &stop), (own, "")])
}

/// The four-bar has one degree of freedom: all its velocities are the crank's rate times one
/// allowed motion, so an impact on the crank's stop keeps e² of the kinetic energy and reverses
/// every rate scaled by e; the loop stays closed at round-off through the impacts.
#[test]
fn a_four_bar_crank_bounces_on_its_stop_keeping_e_squared_of_its_energy() {
    let e = 0.5;
    let text = four_bar(&e.to_string());
    for integrator in [Integrator::DormandPrince, Integrator::Dop853] {
        let simulation = simulate(&text, settings(integrator.clone(), 1.5, 1e-11));
        let report = &simulation.report;
        assert!(report.impacts.len() >= 5, "{:?}", report.impacts);
        for impact in &report.impacts {
            let rate = impact.rate_after / impact.rate_before;
            assert!(
                (rate + e).abs() < 1e-12,
                "{integrator:?}: rate ratio {rate}"
            );
            let kept = impact.kinetic_after / impact.kinetic_before;
            // Between 1e-12 and 1e-6 of the first impact's energy, the loop's own round-off
            // (closed to 1e-13) weighs on the ratio: the kept share is checked where it is
            // above that.
            if impact.kinetic_before > 1e-6 * report.impacts[0].kinetic_before {
                assert!(
                    (kept - e * e).abs() < 1e-9,
                    "{integrator:?}: kept {kept} at t = {}",
                    impact.time
                );
            }
        }
        // The bounces shrink geometrically until the crank rests on its stop.
        assert!(report.impacts.last().expect("impacts").rests);
        let closure = constraints(&simulation).position_residual;
        assert!(closure < 1e-12, "{integrator:?}: closure {closure}");
        let crank = column(&simulation, "crank.q");
        let last = simulation.samples.last().expect("samples");
        assert!((last.coordinates[crank] - 0.6).abs() < 1e-12);
    }
}

/// Stopped dead (e = 0) with gravity pushing it into its stop, the crank rests there for a long
/// run with every method: one impact, no chatter, no drift off the bound, the loop kept closed.
#[test]
fn a_four_bar_crank_stopped_dead_rests_on_its_stop_with_every_method() {
    let text = four_bar("0");
    let cases = [
        (Integrator::DormandPrince, 1e-10),
        (Integrator::Dop853, 1e-10),
        (Integrator::Rk4, 0.0),
        (Integrator::Implicit, 1e-8),
    ];
    for (integrator, tolerance) in cases {
        let simulation = simulate(&text, settings(integrator.clone(), 20.0, tolerance));
        let report = &simulation.report;
        assert_eq!(
            report.impacts.len(),
            1,
            "{integrator:?}: {:?}",
            report.impacts
        );
        let impact = &report.impacts[0];
        assert!(impact.rests && impact.rate_after.abs() < 1e-12);
        assert!(impact.kinetic_after < 1e-20 * impact.kinetic_before.max(1.0) + 1e-24);
        let crank = column(&simulation, "crank.q");
        let resting = simulation.samples.iter().filter(|s| s.time > impact.time);
        let mut count = 0;
        for sample in resting {
            count += 1;
            let off = (sample.coordinates[crank] - 0.6).abs();
            assert!(
                off < 1e-12,
                "{integrator:?}: {off} off at t = {}",
                sample.time
            );
            assert!(
                sample.rates.iter().all(|r| r.abs() < 1e-10),
                "{:?}",
                sample.rates
            );
        }
        assert!(count > 300, "{integrator:?}: {count} samples at rest");
        let closure = constraints(&simulation).position_residual;
        assert!(closure < 1e-12, "{integrator:?}: closure {closure}");
    }
}

/// A pendulum (tree) resting on its stop is lifted off by a torque growing with time: the stop
/// releases it where the torque balances the weight's, m g d sin(bound) = k t_r, and the
/// implicit method follows dopri5 through the resting phase and the release.
#[test]
fn the_implicit_method_follows_dopri5_through_a_resting_phase_and_its_release() {
    let (m, g, d, bound, k) = (1.2f64, 9.81f64, 0.5f64, 0.3f64, 2.0f64);
    let text = format!(
        "import joints;\n\
         let rod = body mass = {m}, iframe = [0, 0, -{d}] ++ 1, inertia = [0.1, 0.1, 0.001] end;\n\
         join earth and rod with limited_revolute([1, 0, 0], {bound}, pi, 0) as swing;\n\
         apply force value = [0, 0, -{g} * rod.mass], body = earth end on rod.iframe;\n\
         apply torque value = [{k} * time, 0, 0], body = earth end on rod;\n\
         initial swing.q = 0.6;\n"
    );
    let release = m * g * d * bound.sin() / k;
    let run = |integrator: Integrator, tolerance: f64| {
        let simulation = simulate(&text, settings(integrator, 1.5, tolerance));
        assert_eq!(simulation.report.impacts.len(), 1);
        assert!(simulation.report.impacts[0].rests);
        simulation
    };
    let reference = run(Integrator::DormandPrince, 1e-12);
    let implicit = run(Integrator::Implicit, 1e-10);
    for simulation in [&reference, &implicit] {
        for sample in &simulation.samples {
            let at_rest = sample.time > simulation.report.impacts[0].time && sample.time < release;
            if at_rest {
                assert!((sample.coordinates[0] - bound).abs() < 1e-12, "{sample:?}");
            }
        }
        // Released at the balance, the rod rises from the bound under the net torque k (t − t_r)
        // (the weight's torque changes with the angle at second order): q − bound ≈
        // k (t − t_r)³ / (6 I) about the pivot, within 3% 0.1 s to 0.15 s after the release.
        let inertia = 0.1 + m * d * d;
        let rising = simulation.samples.iter().filter(|s| {
            let after = s.time - release;
            after > 0.1 && after <= 0.15
        });
        let mut count = 0;
        for sample in rising {
            let after = sample.time - release;
            let expected = k * after.powi(3) / (6.0 * inertia);
            let risen = sample.coordinates[0] - bound;
            assert!(
                (risen / expected - 1.0).abs() < 0.03,
                "{risen} against {expected}"
            );
            count += 1;
        }
        assert_eq!(count, 1);
    }
    for (a, b) in reference.samples.iter().zip(&implicit.samples) {
        assert_eq!(a.time, b.time);
        let difference = (a.coordinates[0] - b.coordinates[0]).abs();
        assert!(difference < 1e-6, "{difference} at t = {}", a.time);
    }
}

/// A cylinder (m = 2, I = 0.01 about its axis, r = 0.1) rolling on level ground, its axle a
/// carriage (0.5 kg) moving along x, carries a pendulum (0.8 kg at d = 0.3, I = 0.006 about its
/// centre) limited to `range` with restitution `e`; launched at 1 m/s. `shadow`, when given,
/// is one more join (a link that closes a loop) with its `initial` guesses.
pub(super) fn rolling_pendulum_with(
    range: &str,
    e: f64,
    start: &str,
    shadow: Option<(&str, &str)>,
) -> String {
    let (join, guess) = shadow.unwrap_or(("", ""));
    format!(
        "import joints ;\nimport gravity ;\n\
         let cylinder = body mass = 2, iframe = 1, inertia = [0.0067, 0.01, 0.0067] end ;\n\
         let carriage = body mass = 0.5, iframe = 1, inertia = [0.001, 0.001, 0.001] end ;\n\
         let rod = body mass = 0.8, iframe = [0, 0, -0.3] ++ 1, inertia = [0.006, 0.006, 0.0002] end ;\n\
         join earth and carriage with link(x, y) dof = [x, 0, y] end as motion ;\n\
         {join}\
         join carriage and cylinder with revolute([0, -1, 0]) as spin ;\n\
         join earth and cylinder with rolling(0.1) as contact ;\n\
         join carriage and rod with limited_revolute([0, 1, 0], {range}, {e}) as swing ;\n\
         apply gravity_field ;\n\
         initial motion.y = 0.1, motion.x' = 1, spin.q' = 10{start}{guess} ;\n"
    )
}

/// `rolling_pendulum_with` on the tree alone.
fn rolling_pendulum(range: &str, e: f64, start: &str) -> String {
    rolling_pendulum_with(range, e, start, None)
}

/// The rolling rows and the normal row hold at round-off on every sample: the axle moves r
/// times the spin (about −y: x' = −r q'), and the cylinder stays on the ground.
pub(super) fn assert_rolling(simulation: &Simulation) {
    let (x, spin, y) = (
        column(simulation, "motion.x"),
        column(simulation, "spin.q"),
        column(simulation, "motion.y"),
    );
    for sample in &simulation.samples {
        let slip = sample.rates[x] + 0.1 * sample.rates[spin];
        assert!(slip.abs() < 1e-12, "slip {slip} at {}", sample.time);
        assert!((sample.coordinates[y] - 0.1).abs() < 1e-12);
    }
}

/// The rolling pendulum's motion has two degrees of freedom, x and the pendulum's θ, with the
/// reduced mass matrix [[M, −m d cos θ], [−m d cos θ, I + m d²]] (M the carriage's, cylinder's
/// and rod's masses plus the cylinder's I_c / r²): an impact on the pendulum's stop takes
/// (1 − e²) of ½ θ̇² / (M⁻¹)_θθ. The rolling rows stay at round-off through it.
#[test]
fn a_pendulum_on_a_rolling_cylinder_loses_the_energy_normal_to_its_stop() {
    let e = 0.5;
    let text = rolling_pendulum("-0.2, 0.25", e, "");
    for integrator in [Integrator::DormandPrince, Integrator::Rk4] {
        let simulation = simulate(&text, settings(integrator.clone(), 2.0, 1e-11));
        assert_impacts_take_normal_energy(&simulation, e, &format!("{integrator:?}"));
        assert_rolling(&simulation);
    }
}

/// Each impact of the rolling pendulum (restitution `e`) takes (1 − e²) of ½ θ̇² / (M⁻¹)_θθ,
/// the kinetic energy normal to its stop in the reduced mass matrix of x and θ, and reverses
/// the rate scaled by e.
pub(super) fn assert_impacts_take_normal_energy(simulation: &Simulation, e: f64, label: &str) {
    let (r, m_cylinder, i_cylinder, m_carriage) = (0.1f64, 2.0f64, 0.01f64, 0.5f64);
    let (m_rod, d, i_rod) = (0.8f64, 0.3f64, 0.006f64);
    let report = &simulation.report;
    assert!(report.impacts.len() >= 3, "{:?}", report.impacts);
    for impact in &report.impacts {
        let mass = m_carriage + m_cylinder + m_rod + i_cylinder / (r * r);
        let coupling = m_rod * d * impact.bound.cos();
        let swing = i_rod + m_rod * d * d;
        let inverse = mass / (mass * swing - coupling * coupling);
        let normal = 0.5 * impact.rate_before.powi(2) / inverse;
        let lost = impact.kinetic_before - impact.kinetic_after;
        assert!(
            (lost - (1.0 - e * e) * normal).abs() < 1e-9 * impact.kinetic_before,
            "{label}: lost {lost}, expected {}",
            (1.0 - e * e) * normal
        );
        assert!((impact.rate_after + e * impact.rate_before).abs() < 1e-12);
    }
}

/// Stopped dead on its stop at 0.2 rad, where its weight pushes it, the pendulum then rests
/// there while the cylinder rolls on: the angle stays at the bound, the rolling rows hold, and
/// the energy left after the impact is kept (the resting stop does no work).
#[test]
fn a_pendulum_on_a_rolling_cylinder_rests_on_its_stop() {
    let text = rolling_pendulum("0.2, 1.0", 0.0, ", swing.q = 0.35");
    for integrator in [Integrator::DormandPrince, Integrator::Rk4] {
        let simulation = simulate(&text, settings(integrator.clone(), 5.0, 1e-11));
        let report = &simulation.report;
        assert_eq!(report.impacts.len(), 1, "{:?}", report.impacts);
        let impact = &report.impacts[0];
        assert!(impact.rests);
        let swing = column(&simulation, "swing.q");
        let resting: Vec<_> = (simulation.samples.iter())
            .filter(|s| s.time > impact.time)
            .collect();
        assert!(resting.len() > 90);
        let energy = |s: &lsdc::simulate::run::Sample| {
            s.kinetic_energy + s.potential_energy.expect("potential")
        };
        let after = energy(resting[0]);
        for sample in &resting {
            let off = sample.coordinates[swing] - 0.2;
            assert!(
                off.abs() < 1e-12,
                "{integrator:?}: {off} at {}",
                sample.time
            );
            let drift = energy(sample) - after;
            assert!(
                drift.abs() < 1e-10 * after,
                "{integrator:?}: energy {drift}"
            );
        }
        assert_rolling(&simulation);
    }
}

/// The implicit method's stiff steps on a mechanism with loops (Rosenbrock-W) move along the
/// tangent directions of the loops that leave a resting coordinate at rest: on the four-bar
/// resting on its crank's stop there are none, and the steps keep the crank on its bound, the
/// loop closed and every rate zero, as dopri5's do.
/// The outputs see the stops resting as the steps left them: the first output after the crank
/// of `examples/limited_four_bar.lsd` came to rest on its bound (t = 0.85, after the impacts
/// that end at 0.8114) is held there like every later one, its rate zero to round-off of a
/// velocity at rest (below 1e-30 rad/s). When the outputs' evaluations copied the resting flags
/// from the steps' at each output's description, after its projection, that output was
/// projected as if the crank still moved and kept 5.6e-17 rad/s.
#[test]
fn the_first_output_after_a_four_bar_comes_to_rest_is_held_on_its_stop() {
    let simulation = simulated(&prepared("limited_four_bar", &[]));
    let rest = simulation.report.impacts.iter().find(|i| i.rests);
    let rest = rest.expect("the crank comes to rest");
    let crank = column(&simulation, "crank.q");
    let after: Vec<_> = (simulation.samples.iter())
        .filter(|s| s.time > rest.time)
        .collect();
    assert!(after.len() > 10, "outputs after the rest: {}", after.len());
    for sample in after {
        assert_eq!(sample.coordinates[crank], rest.bound, "t = {}", sample.time);
        let rate = sample.rates[crank];
        assert!(rate.abs() < 1e-30, "t = {}: rate {rate:e}", sample.time);
    }
}

#[test]
fn rosenbrock_steps_keep_a_resting_four_bar_on_its_stop() {
    use lsdc::integrate::{integrate, Method, Settings as Steps};
    use lsdc::simulate::system::MechanicalSystem;
    let text = four_bar("0").replace("crank.q = 1.0", "crank.q = 0.6");
    let prepared = prepared_text(&text);
    let model = &prepared.model;
    let y0 = initial_state(&prepared);
    let reference = prepared.coordinates.clone();
    let steps = Steps {
        rtol: 1e-8,
        atol: 1e-8,
        ..Steps::default()
    };
    for method in [Method::Rosenbrock, Method::DormandPrince] {
        let stabilisation = prepared.settings.stabilisation;
        let mut system = MechanicalSystem::new(model, reference.clone(), stabilisation);
        let mut y = y0.clone();
        system.start_loops(&mut y).expect("closes");
        system.state.resting[0] = true;
        let basis = system
            .tangent_basis(0.0, &y)
            .expect("basis")
            .expect("loops");
        assert_eq!(
            basis.ncols(),
            0,
            "{method:?}: no motion leaves the crank at rest"
        );
        let mut observer = |_: f64, _: &[f64]| Ok(());
        let (end, _) = integrate(
            &method,
            &mut system,
            0.0,
            &y,
            10.0,
            &[],
            &steps,
            &mut observer,
        )
        .expect("integrates");
        let crank = 0;
        assert!((end[crank] - 0.6).abs() < 1e-12, "{method:?}: {end:?}");
        let positions = model.positions();
        assert!(end[positions..].iter().all(|r| r.abs() < 1e-12), "{end:?}");
        for (a, b) in end.iter().zip(&y) {
            assert!(
                (a - b).abs() < 1e-12,
                "{method:?}: moved from {y:?} to {end:?}"
            );
        }
        assert!(system.scratch.contact[0] > 0.0, "the stop pushes");
    }
}

/// The four-bar's rocker pivoted on a sled that a drive moves along x, d(t) = 0.05 (1 − cos 2t),
/// and its crank stopped dead on its lower stop: two degrees of freedom, one driven, one at
/// rest once the crank rests, so the loop moves with the sled alone. The positions brought back
/// onto the bound after each step must keep the sled on its law: when the resting stops' bound
/// was closed by its own Gauss–Newton steps, which ignored the drives, the sled left its law by
/// 1.2e-9 m at a tolerance of 1e-6 (the steps' minimum-norm corrections moved it with the
/// crank); through the stack's one corrector, every row kind together, it stays within the
/// law's round-off (1e-13 relative to 1 + |d|; 3.8e-16 measured).
#[test]
fn a_driven_sled_stays_on_its_law_while_the_crank_rests_on_its_stop() {
    let rocker = "join [l0, 0, 0] ++ 1 @ earth and bar3 with revolute([0, 0, 1]) as rocker ;";
    let sled = "let sled = body mass = 1, iframe = 0, inertia = [0.1, 0.1, 0.1] end ;
join [l0, 0, 0] ++ 1 @ earth and sled with prismatic([1, 0, 0]) as base ;
join sled and bar3 with revolute([0, 0, 1]) as rocker ;
drive base.q = 0.05 * (1 - cos(2 * time)) ;";
    let text = four_bar("0").replace(rocker, sled);
    let simulation = simulate(&text, settings(Integrator::DormandPrince, 3.0, 1e-6));
    let report = &simulation.report;
    assert_eq!(report.impacts.len(), 1, "{:?}", report.impacts);
    let rest = &report.impacts[0];
    assert!(rest.rests, "the crank comes to rest: {rest:?}");
    let (crank, base) = (
        column(&simulation, "crank.q"),
        column(&simulation, "base.q"),
    );
    let after: Vec<_> = (simulation.samples.iter())
        .filter(|s| s.time > rest.time)
        .collect();
    assert!(after.len() > 40, "outputs after the rest: {}", after.len());
    for sample in after {
        let t = sample.time;
        let (law, rate) = (0.05 * (1.0 - (2.0 * t).cos()), 0.1 * (2.0 * t).sin());
        let off = (sample.coordinates[base] - law).abs();
        assert!(
            off < 1e-13 * (1.0 + law),
            "t = {t}: the sled {off:e} m off its law"
        );
        let off_rate = (sample.rates[base] - rate).abs();
        assert!(off_rate < 1e-13, "t = {t}: its rate {off_rate:e} m/s off");
        assert_eq!(sample.coordinates[crank], rest.bound, "t = {t}");
    }
    let closure = constraints(&simulation).position_residual;
    assert!(closure < 1e-12, "closure {closure}");
}
