//! Constraint rows of every kind solved together (`dynamics::rows`): a mimic coupling on a
//! mechanism with a rolling contact, joint friction with a rolling or sliding contact, and a
//! stop in a mechanism with both a contact and a closed loop. Oracles: closed forms (the
//! cylinder on an incline of Llibre 2009, §2.2.10, with the seed's g = 9.81 and its numbers
//! −3.27, −5.7546, −4.0554 m/s²), the switching time of the joint's friction in closed form,
//! the energy an impact takes from the reduced equations (a (1 − e²) share of the kinetic
//! energy normal to the stop), and the same mechanism built without its redundant loop.

use super::common::programs::{column, constraints, mechanism, run_text};
use super::stop_loops::{assert_impacts_take_normal_energy, assert_rolling, rolling_pendulum_with};
use lsdc::dynamics::algorithms::{forward_kinematics, Data};
use lsdc::dynamics::contacts::contact_rows;
use lsdc::dynamics::driven_points::PointRows;
use lsdc::dynamics::rows::{HeldRow, Holder, RowStack};
use lsdc::prepare::{prepare, Integrator, Settings};
use lsdc::simulate::run::{Sample, Simulation};

/// The seed's gravity, and its incline.
const G: f64 = 9.81;
const ALPHA: f64 = std::f64::consts::PI / 6.0;
const RADIUS: f64 = 0.1;
/// The cylinder's mass and its moment of inertia about its axis, ½ m r².
const MASS: f64 = 2.0;
const INERTIA: f64 = 0.01;

fn settings(integrator: Integrator, duration: f64, reactions: bool) -> Settings {
    Settings {
        integrator,
        duration,
        output: 0.05,
        rtol: 1e-11,
        atol: 1e-11,
        step: Some(1e-3),
        reactions,
        ..Settings::default()
    }
}

/// A run that must not fail.
fn simulate(text: &str, settings: Settings) -> Simulation {
    let simulation = run_text(text, settings);
    let failure = &simulation.report.failure;
    assert!(failure.is_none(), "{failure:?}");
    simulation
}

/// The cylinder of the seed on the 30° incline, on an axle: a carriage (`carriage_mass`)
/// moving in the slope's plane (`motion.x` up the slope, `motion.y` along its normal) carries
/// the cylinder on a revolute joint `spin` about −y, written `spin_link`; the contact is
/// `contact_link`; `extra` adds bodies and joins. Gravity g = 9.81.
fn incline(carriage_mass: f64, spin_link: &str, contact_link: &str, extra: &str) -> String {
    format!(
        "import joints ;\nimport gravity ;\n\
         let r = {RADIUS} ;\n\
         let alpha = 30 * pi / 180 ;\n\
         let cylinder = body mass = {MASS}, iframe = 1, inertia = [0.0067, {INERTIA}, 0.0067] end ;\n\
         let carriage = body mass = {carriage_mass}, iframe = 1, inertia = [0, 0, 0] end ;\n\
         let slope = (-alpha || [0, 1, 0]) @ earth ;\n\
         join slope and carriage with link(x, y) dof = [x, 0, y] end as motion ;\n\
         join carriage and cylinder with {spin_link} as spin ;\n\
         join slope and cylinder with {contact_link} as contact ;\n\
         {extra}\
         apply uniform_field([0, 0, -{G}]) ;\n"
    )
}

/// The contact's force on the cylinder along the slope's axes (x up the slope, z normal).
fn contact_force(sample: &Sample) -> [f64; 3] {
    let r = &sample.reactions;
    [r[r.len() - 3], r[r.len() - 2], r[r.len() - 1]]
}

/// A plate (0.4 kg, centred on the axle, J = 0.02 about it) hinged on the carriage follows the
/// rolling cylinder's spin, turn.q = n spin.q + 0.3: the coupling adds n² J to the inertia the
/// rolling brings to the axle, so it runs down the slope at
/// ẍ = −g sin α M / (M + (I + n² J) / r²), M the masses moved (carriage, cylinder, plate).
/// The coupling, the rolling and the gap hold at round-off, the energy is conserved.
#[test]
fn a_mimic_on_a_rolling_cylinder_adds_its_inertia_times_the_square_of_its_multiplier() {
    let (carriage, plate, plate_inertia) = (0.5, 0.4, 0.02);
    for multiplier in [1.0, -2.5] {
        let plate_body = format!(
            "let plate = body mass = {plate}, iframe = 1, inertia = [0.01, {plate_inertia}, 0.01] end ;\n\
             join carriage and plate with mimic_revolute([0, -1, 0], spin, {multiplier}, 0.3) as turn ;\n"
        );
        let text = incline(carriage, "revolute([0, -1, 0])", "rolling(r)", &plate_body)
            + "initial motion.y = r ;\n";
        let moved = carriage + MASS + plate;
        let rolling = (INERTIA + multiplier * multiplier * plate_inertia) / (RADIUS * RADIUS);
        let acceleration = -G * ALPHA.sin() * moved / (moved + rolling);
        for integrator in [
            Integrator::DormandPrince,
            Integrator::Dop853,
            Integrator::Rk4,
        ] {
            let simulation = simulate(&text, settings(integrator.clone(), 1.0, false));
            let (x, spin, turn) = (
                column(&simulation, "motion.x"),
                column(&simulation, "spin.q"),
                column(&simulation, "turn.q"),
            );
            for sample in &simulation.samples {
                let (t, c, r) = (sample.time, &sample.coordinates, &sample.rates);
                let want = 0.5 * acceleration * t * t;
                assert!(
                    (c[x] - want).abs() < 1e-9,
                    "{integrator:?}, n = {multiplier}, t = {t}: x = {} against {want}",
                    c[x]
                );
                assert!((r[x] - acceleration * t).abs() < 1e-9);
                let coupling = c[turn] - (multiplier * c[spin] + 0.3);
                assert!(coupling.abs() < 1e-12, "coupling {coupling}");
                assert!((r[turn] - multiplier * r[spin]).abs() < 1e-12);
            }
            assert_rolling(&simulation);
            let drift = simulation.report.energy_drift.expect("conservative");
            assert!(drift < 1e-10, "{integrator:?}: energy drift {drift:e}");
        }
    }
}

/// The rolling cylinder with dry friction F_c in its axle (the carriage massless): rolling
/// down, the friction takes F_c |θ̇| = F_c |ẋ| / r of the power, so
/// ẍ = (−m g sin α + F_c / r) / (3/2 m), and the contact holds the cylinder with
/// R_x = m ẍ + m g sin α along the slope, R_y = m g cos α = 16.9914 N. F_c = 0 gives the seed's
/// ẍ = −3.27 m/s² and R_x = 3.27 N.
#[test]
fn friction_in_the_axle_of_a_rolling_cylinder_slows_it_as_in_closed_form() {
    for dry in [0.0, 0.3] {
        let spin = format!("friction_revolute([0, -1, 0], {dry}, 0)");
        let text = incline(0.0, &spin, "rolling(r)", "") + "initial motion.y = r ;\n";
        let acceleration = (-MASS * G * ALPHA.sin() + dry / RADIUS) / (1.5 * MASS);
        if dry == 0.0 {
            assert!((acceleration + 3.27).abs() < 1e-12);
        }
        let along = MASS * acceleration + MASS * G * ALPHA.sin();
        let normal = MASS * G * ALPHA.cos();
        assert!((normal - 16.9914).abs() < 1e-4);
        for integrator in [Integrator::DormandPrince, Integrator::Rk4] {
            let simulation = simulate(&text, settings(integrator.clone(), 1.0, true));
            let x = column(&simulation, "motion.x");
            for sample in simulation.samples.iter().skip(1) {
                let (t, c, r) = (sample.time, &sample.coordinates, &sample.rates);
                assert!(
                    (c[x] - 0.5 * acceleration * t * t).abs() < 1e-9,
                    "{integrator:?}, F_c = {dry}, t = {t}: x = {}",
                    c[x]
                );
                assert!((r[x] - acceleration * t).abs() < 1e-9);
                let [fx, fy, fz] = contact_force(sample);
                assert!((fx - along).abs() < 1e-9, "R_x = {fx} against {along}");
                assert!(fy.abs() < 1e-9 && (fz - normal).abs() < 1e-9, "R_y = {fz}");
            }
            assert_rolling(&simulation);
            let report = &simulation.report;
            assert!(report.friction_switches.is_empty());
            if dry > 0.0 {
                let balance = report.energy_balance.expect("an energy balance");
                assert!(balance.abs() < 1e-10, "balance {balance}");
            }
        }
    }
}

/// A rotor of 1e-13 kg m² on the rolling cylinder's carriage, held by its dry friction (nothing
/// turns it): its held row, of entries 1/J = 1e13, stands beside the contact's, of about 1/m.
/// Rows of such different units are solved as rows of one (each row scaled to its largest
/// entry before the dependent ones are found): the contact's is kept, and the cylinder rolls
/// down at the seed's ẍ = −3.27 m/s² on its normal force 16.9914 N. (Without the scaling the
/// contact's rows fell under the cutoff relative to the rotor's: no normal force, the
/// cylinder falling through the slope.)
#[test]
fn a_light_rotor_held_beside_a_rolling_contact_leaves_the_contact_s_rows_kept() {
    let rotor = "let rotor = body mass = 0, iframe = 1, inertia = [1e-13, 1e-13, 1e-13] end ;
                 join carriage and rotor with friction_revolute([0, -1, 0], 1, 0) as brake ;
";
    let text = incline(0.0, "revolute([0, -1, 0])", "rolling(r)", rotor)
        + "initial motion.y = r ;
";
    let acceleration = -G * ALPHA.sin() / 1.5;
    let normal = MASS * G * ALPHA.cos();
    let simulation = simulate(&text, settings(Integrator::DormandPrince, 1.0, true));
    let x = column(&simulation, "motion.x");
    let brake = column(&simulation, "brake.q");
    for sample in simulation.samples.iter().skip(1) {
        let (t, c) = (sample.time, &sample.coordinates);
        assert!(
            (c[x] - 0.5 * acceleration * t * t).abs() < 1e-9,
            "t = {t}: x = {}",
            c[x]
        );
        assert!(c[brake].abs() < 1e-12 && sample.rates[brake].abs() < 1e-12);
        let [_, _, fz] = contact_force(sample);
        assert!((fz - normal).abs() < 1e-9, "R_z = {fz} against {normal}");
    }
    assert_rolling(&simulation);
}

/// A slider of 1000 kg resting on its lower stop carries a rotor of 1e-10 kg m² held by its
/// dry friction: the stop's held row (entries 1/m = 1e-3) and the rotor's (1/J = 1e10) are
/// both kept, and the slider stays on its stop under its weight. (It fell through the stop,
/// 4.9 m in 1 s, while the stop's row was taken as dependent on the rotor's.)
#[test]
fn a_heavy_slider_resting_on_its_stop_beside_a_light_held_rotor_stays_there() {
    let text = "import joints ;
                let slider = body mass = 1000, iframe = 0, inertia = [1, 1, 1] end ;
                let rotor = body mass = 1e-6, iframe = 0, inertia = [1e-10, 1e-10, 1e-10] end ;
                join earth and slider with limited_prismatic([0, 0, 1], 0, 1, 0) as lift ;
                join slider and rotor with friction_revolute([0, 0, 1], 1, 0) as spin ;
                apply force value = [0, 0, -9.81 * slider.mass], body = earth end on slider.frame ;
";
    for integrator in [
        Integrator::DormandPrince,
        Integrator::Rk4,
        Integrator::Implicit,
    ] {
        let simulation = simulate(text, settings(integrator.clone(), 1.0, false));
        let lift = column(&simulation, "lift.q");
        for sample in &simulation.samples {
            let (q, rate) = (sample.coordinates[lift], sample.rates[lift]);
            assert!(
                q.abs() < 1e-12 && rate.abs() < 1e-12,
                "{integrator:?}, t = {}: lift.q = {q}, rate {rate}",
                sample.time
            );
        }
    }
}

/// Launched up the slope at 0.5 m/s (rolling: its spin −5 rad/s) with F_c = 1.2 N m in the axle, more than the r m g sin α
/// = 0.981 N m that holds the cylinder on the slope: it slows at
/// ẍ = −(m g sin α + F_c / r) / (3/2 m), stops at t* = 0.5 / |ẍ|, where the axle sticks (its
/// rate located at zero), and then stays there, at rest on the slope.
#[test]
fn a_rolling_cylinder_whose_axle_friction_exceeds_its_weight_sticks_where_it_stops() {
    let dry = 1.2;
    let spin = format!("friction_revolute([0, -1, 0], {dry}, 0)");
    let text = incline(0.0, &spin, "rolling(r)", "")
        + "initial motion.y = r, motion.x' = 0.5, spin.q' = -5 ;\n";
    let deceleration = (MASS * G * ALPHA.sin() + dry / RADIUS) / (1.5 * MASS);
    let stop = 0.5 / deceleration;
    let rest = 0.5 * stop - 0.5 * deceleration * stop * stop;
    for integrator in [Integrator::DormandPrince, Integrator::Dop853] {
        let simulation = simulate(&text, settings(integrator.clone(), 1.0, false));
        let switches = &simulation.report.friction_switches;
        let [sticking] = &switches[..] else {
            panic!("{switches:?}");
        };
        assert_eq!(sticking.phase, lsdc::dynamics::friction::Phase::Sticking);
        assert!(
            (sticking.time - stop).abs() < 1e-9,
            "{integrator:?}: sticks at {} against {stop}",
            sticking.time
        );
        assert!((sticking.position + rest / RADIUS).abs() < 1e-9);
        let x = column(&simulation, "motion.x");
        for sample in simulation.samples.iter().filter(|s| s.time > stop) {
            assert!(
                (sample.coordinates[x] - rest).abs() < 1e-12,
                "{}",
                sample.time
            );
            assert!(sample.rates[x].abs() < 1e-12, "rate {}", sample.rates[x]);
        }
        assert_rolling(&simulation);
    }
}

/// The seed's sliding cylinder (f = 0.1) with dry friction F_c = 0.05 N m in its axle: the
/// axle's friction acts inside the body it turns, so the slide keeps the seed's
/// ẍ = −g sin α − s f g cos α (−5.7546 for s = +1, −4.0554 for s = −1), and the spin, driven by
/// the contact's friction torque ∓ f m g cos α r (more than F_c, so the axle slips), turns at
/// θ̈ = (−s f m g cos α r + s F_c) / I. Both signs of the slip velocity.
#[test]
fn a_sliding_cylinder_with_friction_in_its_axle_follows_both_coulomb_laws() {
    let (friction, dry) = (0.1, 0.05);
    let spin = format!("friction_revolute([0, -1, 0], {dry}, 0)");
    for (start, sign, seed) in [(1.0, 1.0, -5.7546), (-1.0, -1.0, -4.0554)] {
        let initial = format!("initial motion.y = r, motion.x' = {start} ;\n");
        let text = incline(0.0, &spin, "sliding(r, 0.1)", "") + &initial;
        let acceleration = -G * ALPHA.sin() - sign * friction * G * ALPHA.cos();
        assert!((acceleration - seed).abs() < 1e-4);
        let torque = -sign * friction * MASS * G * ALPHA.cos() * RADIUS;
        assert!(torque.abs() > dry);
        let spin_acceleration = (torque + sign * dry) / INERTIA;
        let simulation = simulate(&text, settings(Integrator::DormandPrince, 0.1, false));
        let (x, q) = (
            column(&simulation, "motion.x"),
            column(&simulation, "spin.q"),
        );
        for sample in simulation.samples.iter().skip(1) {
            let (t, c, r) = (sample.time, &sample.coordinates, &sample.rates);
            let slip = r[x] + RADIUS * r[q];
            assert!(slip * sign > 0.0, "the slip keeps its sign");
            assert!((c[x] - (start * t + 0.5 * acceleration * t * t)).abs() < 1e-9);
            assert!(
                (c[q] - 0.5 * spin_acceleration * t * t).abs() < 1e-9,
                "s = {sign}, t = {t}: q = {}",
                c[q]
            );
            assert!((r[q] - spin_acceleration * t).abs() < 1e-9);
        }
        let balance = simulation.report.energy_balance.expect("a balance");
        assert!(balance.abs() < 1e-10, "balance {balance}");
    }
}

/// The rolling pendulum of `stop_loops.rs` (a cylinder rolling on level ground, its axle a
/// carriage carrying a pendulum limited to `range` with restitution `e`), with the carriage
/// also joined to the ground by `shadow`, a second planar link that closes a loop whose rows
/// repeat the first's, when `loop_closed`.
pub(super) fn rolling_pendulum(range: &str, e: f64, start: &str, loop_closed: bool) -> String {
    let shadow = (
        "join earth and carriage with link(x, y) dof = [x, 0, y] end as shadow ;\n",
        ", shadow.y = 0.1 guess",
    );
    rolling_pendulum_with(range, e, start, loop_closed.then_some(shadow))
}

/// The loop's rows at round-off on every state the run continued from and every output.
fn assert_closed(simulation: &Simulation) {
    let report = constraints(simulation);
    assert!(report.position_residual < 1e-12, "{report:?}");
    assert!(report.velocity_residual < 1e-12, "{report:?}");
}

/// With the loop and the contact, the motion keeps two degrees of freedom, x and the
/// pendulum's θ, with the reduced mass matrix [[M, −m d cos θ], [−m d cos θ, I + m d²]]: an
/// impact on the pendulum's stop takes (1 − e²) of the kinetic energy normal to it,
/// ½ θ̇² / (M⁻¹)_θθ, and reverses the rate scaled by e. The rolling rows, the gap and the
/// loop's rows hold at round-off through the impacts, and the motion is that of the same
/// mechanism without the loop.
#[test]
fn a_stop_with_a_contact_and_a_loop_takes_e_squared_of_the_normal_energy() {
    let e = 0.5;
    let looped = rolling_pendulum("-0.2, 0.25", e, "", true);
    let tree = rolling_pendulum("-0.2, 0.25", e, "", false);
    for integrator in [Integrator::DormandPrince, Integrator::Rk4] {
        let simulation = simulate(&looped, settings(integrator.clone(), 2.0, false));
        assert_impacts_take_normal_energy(&simulation, e, &format!("{integrator:?}"));
        assert_closed(&simulation);
        assert_rolling(&simulation);
        let without = simulate(&tree, settings(integrator.clone(), 2.0, false));
        for (a, b) in simulation.samples.iter().zip(&without.samples) {
            for name in ["motion.x", "swing.q"] {
                let (i, j) = (column(&simulation, name), column(&without, name));
                let difference = (a.coordinates[i] - b.coordinates[j]).abs();
                assert!(difference < 1e-7, "{name}: {difference} at t = {}", a.time);
            }
        }
    }
}

/// Stopped dead on its stop at 0.2 rad, where its weight pushes it, the pendulum rests there
/// while the cylinder rolls on with the loop closed: the angle stays at the bound, the loop's
/// and the contact's rows hold, and the energy left after the impact is kept.
#[test]
fn a_stop_with_a_contact_and_a_loop_holds_its_resting_coordinate() {
    let text = rolling_pendulum("0.2, 1.0", 0.0, ", swing.q = 0.35", true);
    let simulation = simulate(&text, settings(Integrator::DormandPrince, 3.0, false));
    let report = &simulation.report;
    assert_eq!(report.impacts.len(), 1, "{:?}", report.impacts);
    let impact = &report.impacts[0];
    assert!(impact.rests);
    let swing = column(&simulation, "swing.q");
    let energy = |s: &Sample| s.kinetic_energy + s.potential_energy.expect("potential");
    let resting: Vec<_> = (simulation.samples.iter())
        .filter(|s| s.time > impact.time)
        .collect();
    assert!(resting.len() > 50);
    let after = energy(resting[0]);
    for sample in &resting {
        let off = sample.coordinates[swing] - 0.2;
        assert!(off.abs() < 1e-12, "{off} at {}", sample.time);
        let drift = energy(sample) - after;
        assert!(drift.abs() < 1e-10 * after, "energy {drift}");
    }
    assert_closed(&simulation);
}

/// `lsdc tree` counts the mimic coupling with the contact's rows: the carriage's x and y, the
/// spin and the plate's turn (4 tree dof) keep 2 positions (the coupling, the gap) and one
/// velocity (the rolling row ties the spin to x).
#[test]
fn a_mimic_with_a_contact_is_counted_in_both_degrees_of_freedom() {
    let plate = "let plate = body mass = 0.4, iframe = 1, inertia = [0.01, 0.02, 0.01] end ;\n\
                 join carriage and plate with mimic_revolute([0, -1, 0], spin, 2, 0.3) as turn ;\n";
    let text =
        incline(0.5, "revolute([0, -1, 0])", "rolling(r)", plate) + "initial motion.y = r ;\n";
    let options = lsdc::load::LoadOptions {
        library_dirs: Vec::new(),
        use_environment: false,
        scene: None,
    };
    let compilation = lsdc::driver::compile_text("test.lsd", &text, None, &options);
    let mechanism = compilation.mechanism.expect("elaborates");
    let report = lsdc::studies::analysis::tree(&mechanism).expect("a tree report");
    let contacts = report.contacts.expect("contacts");
    assert_eq!((contacts.position_dof, contacts.velocity_dof), (2, 1));
    assert_eq!(report.mobility.expect("mobility").mobility, 3);
}

/// `examples/rolling_axle_friction.lsd`: launched up the slope, the cylinder whose axle has
/// F_c = 0.3 N m of dry friction rolls up at −(m g sin α + F_c / r) / (3/2 m), stops at
/// t* = 0.5 / 4.27 s, where the holding torque (0.981 N m) exceeds F_c, so that the axle slips
/// back, and rolls down at −(m g sin α − F_c / r) / (3/2 m), each phase in closed form.
#[test]
fn the_rolling_axle_friction_example_switches_at_its_closed_form_time() {
    let (dry, v0) = (0.3, 0.5);
    let up = -(MASS * G * ALPHA.sin() + dry / RADIUS) / (1.5 * MASS);
    let down = -(MASS * G * ALPHA.sin() - dry / RADIUS) / (1.5 * MASS);
    let stop = -v0 / up;
    let top = v0 * stop + 0.5 * up * stop * stop;
    let text = super::common::programs::example_text("rolling_axle_friction", &[]);
    let simulation = simulate(&text, settings(Integrator::DormandPrince, 1.0, false));
    let switches = &simulation.report.friction_switches;
    let [back] = &switches[..] else {
        panic!("{switches:?}");
    };
    assert!(
        (back.time - stop).abs() < 1e-9,
        "{} against {stop}",
        back.time
    );
    assert_eq!(back.phase, lsdc::dynamics::friction::Phase::Slipping(1.0));
    let x = column(&simulation, "motion.x");
    for sample in &simulation.samples {
        let t = sample.time;
        let want = match t <= stop {
            true => v0 * t + 0.5 * up * t * t,
            false => top + 0.5 * down * (t - stop).powi(2),
        };
        assert!((sample.coordinates[x] - want).abs() < 1e-9, "t = {t}");
    }
    assert_rolling(&simulation);
    let balance = simulation.report.energy_balance.expect("a balance");
    assert!(balance.abs() < 1e-10, "balance {balance}");
}

/// Every kind at once: the mimic plate and the rolling contact of the test above, dry friction
/// in the axle, and a second planar link `shadow` from the slope to the carriage that closes a
/// loop repeating the first's rows. The couplings', the contact's and the loop's rows are
/// solved together, so the motion keeps the closed form of the added inertia with the
/// friction's torque, ẍ = (−g sin α M + F_c / r) / (M + (I + n² J) / r²), and every row holds
/// at round-off.
#[test]
fn a_mimic_a_contact_friction_and_a_loop_are_solved_together() {
    let (carriage, plate, plate_inertia, multiplier, dry) = (0.5, 0.4, 0.02, -2.5, 0.3);
    let extra = format!(
        "let plate = body mass = {plate}, iframe = 1, inertia = [0.01, {plate_inertia}, 0.01] end ;\n\
         join carriage and plate with mimic_revolute([0, -1, 0], spin, {multiplier}, 0.3) as turn ;\n\
         join slope and carriage with link(x, y) dof = [x, 0, y] end as shadow ;\n"
    );
    let spin = format!("friction_revolute([0, -1, 0], {dry}, 0)");
    let text = incline(carriage, &spin, "rolling(r)", &extra)
        + "initial motion.y = r, shadow.y = r guess ;\n";
    let moved = carriage + MASS + plate;
    let rolling = (INERTIA + multiplier * multiplier * plate_inertia) / (RADIUS * RADIUS);
    let acceleration = (-G * ALPHA.sin() * moved + dry / RADIUS) / (moved + rolling);
    for integrator in [Integrator::DormandPrince, Integrator::Rk4] {
        let simulation = simulate(&text, settings(integrator.clone(), 1.0, false));
        let (x, spin, turn) = (
            column(&simulation, "motion.x"),
            column(&simulation, "spin.q"),
            column(&simulation, "turn.q"),
        );
        for sample in simulation.samples.iter().skip(1) {
            let (t, c) = (sample.time, &sample.coordinates);
            let want = 0.5 * acceleration * t * t;
            assert!(
                (c[x] - want).abs() < 1e-9,
                "{integrator:?}, t = {t}: x = {} against {want}",
                c[x]
            );
            let coupling = c[turn] - (multiplier * c[spin] + 0.3);
            assert!(coupling.abs() < 1e-12, "coupling {coupling}");
        }
        assert_rolling(&simulation);
        assert_closed(&simulation);
        assert!(simulation.report.friction_switches.is_empty());
    }
}

#[test]
fn the_stack_values_are_its_rows_at_the_state() {
    // The ball of `rolling_ball` (radius 0.05 on the plane z = 0) with its three contact rows,
    // a coordinate held on a stop at 0.1 and one held by friction: the velocity values of each
    // kind are its rows applied to the velocities (G v), and the position values the closed
    // forms: the gap z − r, the held coordinate's distance to its bound, nothing for friction.
    let prepared = prepare(&mechanism("rolling_ball", &[]), &[], &Settings::default())
        .unwrap_or_else(|d| panic!("{:?}", d.iter().map(|d| &d.message).collect::<Vec<_>>()));
    let model = &prepared.model;
    let mut q = vec![0.3, -0.2, 0.08, 0.5, -0.1, 0.3, 0.8];
    let norm = q[3..7].iter().map(|x| x * x).sum::<f64>().sqrt();
    q[3..7].iter_mut().for_each(|x| *x /= norm);
    let v = vec![0.4, -1.1, 0.3, 2.0, -3.0, 1.5];
    let mut data = Data::new(model);
    forward_kinematics(model, &mut data, &q, &v).expect("kinematics");
    let all = contact_rows(model, &mut data, &v, false);
    let held = [
        HeldRow {
            velocity: 0,
            holder: Holder::Stop {
                index: 0,
                position: 0,
                bound: 0.1,
            },
        },
        HeldRow {
            velocity: 4,
            holder: Holder::Friction { index: 0 },
        },
    ];
    let mut stack = RowStack::new(model);
    let points = PointRows::default();
    stack.arrange(&[0, 1, 2], 0, &points, &held);
    stack.gather(&all, &model.mimics, &points);
    assert!(stack.velocity_values(&all, &model.mimics, &points, &v));
    let applied = stack.rows() * nalgebra::DVector::from_column_slice(&v);
    let values = stack.values_mut().clone();
    assert!(
        (&values - &applied).amax() <= 1e-15 * applied.amax(),
        "values {values} against G v {applied}"
    );
    stack.arrange(&[2], 0, &points, &held);
    stack.gather(&all, &model.mimics, &points);
    assert!(stack.position_values(model, &all, &points, &q));
    let values = stack.values_mut();
    assert!(
        (values[0] - (0.08 - 0.05)).abs() <= 1e-15,
        "gap {}",
        values[0]
    );
    assert_eq!((values[1], values[2]), (0.3 - 0.1, 0.0));
}
