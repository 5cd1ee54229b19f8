//! Contacts of round bodies on planes (`rolling`, `sliding`) against the closed forms of Llibre
//! (2009, §2.2.10: the cylinder on an incline, rolling or sliding) and the conservation laws
//! of a ball rolling on a plane; γ (the rows' velocity-product term) against finite
//! differences of the rows along the motion.

use super::common::contact_rows::rows_along_motion;
use super::common::programs::{example_text, mechanism};
use lsdc::driver::compile_text;
use lsdc::load::LoadOptions;
use lsdc::prepare::{prepare, Prepared, Settings};
use lsdc::simulate::run::{run, Sample, Simulation};

/// Standard gravity, as the `gravity` library gives it.
const G: f64 = 9.80665;
const ALPHA: f64 = std::f64::consts::PI / 6.0;
const MASS: f64 = 2.0;
const RADIUS: f64 = 0.1;

fn prepared_with_reactions(name: &str, replacements: &[(&str, &str)]) -> Prepared {
    let settings = Settings {
        reactions: true,
        ..Settings::default()
    };
    prepare(&mechanism(name, replacements), &[], &settings)
        .unwrap_or_else(|d| panic!("{:?}", d.iter().map(|d| &d.message).collect::<Vec<_>>()))
}

fn completed(prepared: &Prepared) -> Simulation {
    let simulation = run(prepared, &mut |_| {});
    let failure = &simulation.report.failure;
    assert!(failure.is_none(), "{failure:?}");
    simulation
}

/// The contact's force on the cylinder along the slope's axes (x up the slope, z normal): the
/// last three reaction components (the contact's, after the planar joint's six).
fn contact_force(sample: &Sample) -> [f64; 3] {
    let r = &sample.reactions;
    [r[r.len() - 3], r[r.len() - 2], r[r.len() - 1]]
}

/// x, y, q and their rates of the cylinder example's planar joint.
fn cylinder_state(sample: &Sample) -> ([f64; 3], [f64; 3]) {
    let (c, r) = (&sample.coordinates, &sample.rates);
    ([c[0], c[1], c[2]], [r[0], r[1], r[2]])
}

#[test]
fn the_rolling_cylinder_matches_its_closed_form_with_every_integrator() {
    // ẍ = −(2/3) g sin α; R_x = (1/3) m g sin α up the slope, R_y = m g cos α.
    let acceleration = -2.0 / 3.0 * G * ALPHA.sin();
    let (along, normal) = (MASS * G * ALPHA.sin() / 3.0, MASS * G * ALPHA.cos());
    assert!((acceleration + 3.2688833333333).abs() < 1e-12);
    assert!((normal - 16.985616052045).abs() < 1e-11);
    for integrator in ["rk4", "dopri5", "dop853", "implicit"] {
        let replaced = format!("integrator = {integrator}");
        let prepared = prepared_with_reactions(
            "rolling_cylinder",
            &[("integrator = dopri5", replaced.as_str())],
        );
        let simulation = completed(&prepared);
        assert_eq!(simulation.samples.len(), 21);
        for sample in &simulation.samples {
            let t = sample.time;
            let ([x, y, q], [x_rate, y_rate, q_rate]) = cylinder_state(sample);
            let expected = [
                (x, 0.5 * acceleration * t * t),
                (x_rate, acceleration * t),
                (q, -0.5 * acceleration * t * t / RADIUS),
                (q_rate, -acceleration * t / RADIUS),
                (y, RADIUS),
                (y_rate, 0.0),
            ];
            for (k, (got, want)) in expected.into_iter().enumerate() {
                assert!(
                    (got - want).abs() < 1e-9,
                    "{integrator}, t = {t}, quantity {k}: {got} against {want}"
                );
            }
            // The contact point has no velocity: ẋ + r q̇ = 0 (q turns about −y).
            assert!(
                (x_rate + RADIUS * q_rate).abs() < 1e-9,
                "{integrator}: slip"
            );
            let [fx, fy, fz] = contact_force(sample);
            assert!((fx - along).abs() < 1e-9, "{integrator}: R_x = {fx}");
            assert!(
                fy.abs() < 1e-9 && (fz - normal).abs() < 1e-9,
                "{integrator}: R_y = {fz}"
            );
            // Rolling holds as long as tan φ exceeds |R_x / R_y| = tan α / 3 = 0.19245.
            assert!((fx / fz - ALPHA.tan() / 3.0).abs() < 1e-12);
            assert!((fx / fz - 0.19245).abs() < 1e-5);
        }
    }
}

#[test]
fn the_symplectic_integrator_refuses_contacts() {
    let prepared = prepared_with_reactions(
        "rolling_cylinder",
        &[("integrator = dopri5", "integrator = symplectic")],
    );
    let simulation = run(&prepared, &mut |_| {});
    let failure = simulation.report.failure.expect("refused");
    assert!(
        failure
            .message
            .contains("symplectic integrator does not handle contacts"),
        "{}",
        failure.message
    );
    assert!(simulation.samples.is_empty());
}

#[test]
fn the_sliding_cylinder_follows_coulomb_with_both_signs_of_the_slip() {
    // s = sign(ẋ + r θ̇): ẍ = −g sin α − s f g cos α, r θ̈ = −2 s f g cos α (Llibre's treatment 5,
    // with the sign of L1606 corrected); here q = θ.
    let friction = 0.1;
    for (start, sign) in [(1.0, 1.0), (-1.0, -1.0)] {
        let initial = format!("initial motion.y = r, motion.x' = {start} ;");
        let prepared = prepared_with_reactions(
            "rolling_cylinder",
            &[
                ("rolling(r)", "sliding(r, 0.1)"),
                ("initial motion.y = r ;", initial.as_str()),
                ("duration = 1,", "duration = 0.1,"),
                ("output = 0.05", "output = 0.01"),
            ],
        );
        let simulation = completed(&prepared);
        let acceleration = -G * ALPHA.sin() - sign * friction * G * ALPHA.cos();
        let spin = -2.0 * sign * friction * G * ALPHA.cos() / RADIUS;
        // The seed's numbers, with its g = 9.81.
        let seed = -9.81 * ALPHA.sin() - sign * friction * 9.81 * ALPHA.cos();
        assert!((seed - if sign > 0.0 { -5.7546 } else { -4.0554 }).abs() < 1e-4);
        for sample in &simulation.samples {
            let t = sample.time;
            let ([x, y, q], [x_rate, _, q_rate]) = cylinder_state(sample);
            let slip = x_rate + RADIUS * q_rate;
            assert!(slip * sign > 0.0, "the slip keeps its sign over the run");
            let expected = [
                (x, start * t + 0.5 * acceleration * t * t),
                (x_rate, start + acceleration * t),
                (q, 0.5 * spin * t * t),
                (q_rate, spin * t),
                (y, RADIUS),
            ];
            for (k, (got, want)) in expected.into_iter().enumerate() {
                assert!(
                    (got - want).abs() < 1e-9,
                    "s = {sign}, t = {t}, quantity {k}: {got} against {want}"
                );
            }
            let [fx, _, fz] = contact_force(sample);
            assert!((fz - MASS * G * ALPHA.cos()).abs() < 1e-9);
            assert!(
                (fx + sign * friction * fz).abs() < 1e-9,
                "s = {sign}: R_x = {fx}"
            );
        }
        // The friction's work balances the energy.
        let report = &simulation.report;
        let balance = report.energy_balance.expect("an energy balance");
        assert!(balance.abs() < 1e-10, "balance {balance}");
    }
}

/// The ball example's state: centre (x, y, z), angles and their rates, at a sample.
fn ball_contact_velocity(sample: &Sample, radius: f64) -> [f64; 2] {
    let (c, r) = (&sample.coordinates, &sample.rates);
    let (a, b) = (c[3], c[4]);
    // Bryant angles x, y, z: ω = R_x(a) R_y(b) ... in fixed axes, from the rates.
    let omega = [
        r[3] + r[5] * b.sin(),
        r[4] * a.cos() - r[5] * a.sin() * b.cos(),
        r[4] * a.sin() + r[5] * a.cos() * b.cos(),
    ];
    // v_C + ω × (−r e_z): its horizontal components.
    [r[0] - radius * omega[1], r[1] + radius * omega[0]]
}

#[test]
fn the_rolling_ball_keeps_its_contact_point_at_rest_and_its_energy() {
    let radius = 0.05;
    let prepared = prepared_with_reactions(
        "rolling_ball",
        &[
            ("duration = 4,", "duration = 20,"),
            ("output = 0.1", "output = 0.5"),
        ],
    );
    let simulation = completed(&prepared);
    let first = &simulation.samples[0];
    let energy = |s: &Sample| s.kinetic_energy + s.potential_energy.expect("conservative");
    let mut largest_height = 0.0f64;
    for sample in &simulation.samples {
        let [vx, vy] = ball_contact_velocity(sample, radius);
        assert!(vx.abs() < 1e-9 && vy.abs() < 1e-9, "slip ({vx}, {vy})");
        largest_height = largest_height.max((sample.coordinates[2] - radius).abs());
        let drift = (energy(sample) - energy(first)) / energy(first);
        assert!(
            drift.abs() < 1e-9,
            "t = {}: energy drift {drift}",
            sample.time
        );
        // The normal force carries the weight; the rolling forces move the centre.
        let [_, _, fz] = contact_force(sample);
        assert!(fz > 0.0);
    }
    assert!(
        largest_height < 1e-12,
        "the centre left its plane by {largest_height}"
    );
    // The ball travelled (it is not a trivial rest).
    let last = simulation.samples.last().expect("samples");
    assert!(last.coordinates[0].hypot(last.coordinates[1]) > 1.0);
}

#[test]
fn the_rolling_ball_has_five_position_and_three_velocity_dof() {
    let report = lsdc::studies::analysis::tree(&mechanism("rolling_ball", &[])).expect("a tree");
    let contacts = report.contacts.expect("contacts");
    assert_eq!((contacts.position_dof, contacts.velocity_dof), (5, 3));
    let report =
        lsdc::studies::analysis::tree(&mechanism("rolling_cylinder", &[])).expect("a tree");
    let contacts = report.contacts.expect("contacts");
    assert_eq!((contacts.position_dof, contacts.velocity_dof), (2, 1));
}

#[test]
fn the_contact_bias_is_the_rate_of_the_rows_along_the_motion() {
    // At a state off the rolling motion (the ball slips and spins), γ = d/dt (G v) at fixed
    // velocities, by central differences of the rows along q̇.
    let prepared = prepared_with_reactions("rolling_ball", &[]);
    let model = &prepared.model;
    let q: Vec<f64> = (0..model.nq)
        .map(|i| [0.3, -0.2, 0.07, 0.5, -0.1, 0.3, 0.8][i % 7])
        .collect();
    let mut q = q;
    let norm = q[3..7].iter().map(|x| x * x).sum::<f64>().sqrt();
    q[3..7].iter_mut().for_each(|x| *x /= norm);
    let v = vec![0.4, -1.1, 0.3, 2.0, -3.0, 1.5];
    let rows = rows_along_motion(model, &q, &v, 1e-5);
    rows.assert_bias_is_the_rate();
}

fn diagnostics_of(text: &str) -> Vec<String> {
    let options = LoadOptions {
        library_dirs: Vec::new(),
        use_environment: false,
        scene: None,
    };
    let compilation = compile_text("contact.lsd", text, None, &options);
    let mechanism = compilation.mechanism.expect("elaborates");
    match prepare(&mechanism, &[], &Settings::default()) {
        Ok(_) => Vec::new(),
        Err(d) => d.into_iter().map(|d| d.code.to_string()).collect(),
    }
}

/// The rolling cylinder carrying a closed loop: a second planar link between the slope and the
/// cylinder (`shadow`, a complementary link whose rows repeat the first's) closes a loop that
/// shares the cylinder's velocities with the contact's rows. Solved together, the motion and
/// the contact's force are those of the closed form, the rolling row and the gap stay at
/// round-off, and so do the loop's rows; the shadow follows the cylinder.
#[test]
fn the_rolling_cylinder_carrying_a_loop_matches_its_closed_form() {
    let acceleration = -2.0 / 3.0 * G * ALPHA.sin();
    let (along, normal) = (MASS * G * ALPHA.sin() / 3.0, MASS * G * ALPHA.cos());
    let shadow = "join slope and cylinder with link(x, y, q) dof1 = [x, 0, y], \
                  dof2 = q || [0, -1, 0] end as shadow ;\n\
                  join slope and cylinder with rolling(r) as contact ;";
    for integrator in ["rk4", "dopri5", "dop853", "implicit"] {
        let replaced = format!("integrator = {integrator}");
        let prepared = prepared_with_reactions(
            "rolling_cylinder",
            &[
                ("integrator = dopri5", replaced.as_str()),
                (
                    "join slope and cylinder with rolling(r) as contact ;",
                    shadow,
                ),
                (
                    "initial motion.y = r ;",
                    "initial motion.y = r, shadow.y = r guess ;",
                ),
            ],
        );
        let simulation = completed(&prepared);
        let residual = simulation.report.constraints.as_ref().expect("loops");
        assert!(residual.position_residual < 1e-13, "{integrator}");
        assert!(residual.velocity_residual < 1e-13, "{integrator}");
        for sample in &simulation.samples {
            let t = sample.time;
            let ([x, y, q], [x_rate, _, q_rate]) = cylinder_state(sample);
            assert!(
                (x - 0.5 * acceleration * t * t).abs() < 1e-9,
                "{integrator}, t = {t}: x = {x}"
            );
            assert!((x_rate - acceleration * t).abs() < 1e-9, "{integrator}");
            let turned = -0.5 * acceleration * t * t / RADIUS;
            assert!((q - turned).abs() < 1e-9, "{integrator}: q = {q}");
            // No drift off the contact: the gap and the rolling row at round-off.
            assert!(
                (y - RADIUS).abs() < 1e-14,
                "{integrator}: gap {}",
                y - RADIUS
            );
            assert!(
                (x_rate + RADIUS * q_rate).abs() < 1e-12,
                "{integrator}: slip {}",
                x_rate + RADIUS * q_rate
            );
            let shadow_x = sample.coordinates[3];
            assert!((shadow_x - x).abs() < 1e-12, "{integrator}: shadow");
            let [fx, fy, fz] = contact_force(sample);
            assert!((fx - along).abs() < 1e-9, "{integrator}: R_x = {fx}");
            assert!(
                fy.abs() < 1e-9 && (fz - normal).abs() < 1e-9,
                "{integrator}"
            );
        }
    }
}

#[test]
fn stops_with_contacts_are_accepted() {
    let bob =
        "let bob = body mass = 1, iframe = [0, 0, -0.1] ++ 1, inertia = [0.1, 0.1, 0.1] end ;\n";
    let stop = example_text("rolling_cylinder", &[])
        + bob
        + "join cylinder and bob with limited_revolute([0, 1, 0], -1, 1, 0.5) ;\n";
    // Simulated with the contacts' rows (tests/suite/stop_loops.rs).
    assert!(diagnostics_of(&stop).is_empty());
}

#[test]
fn a_geared_rotor_on_a_rolling_cylinder_keeps_its_energy() {
    // A pendulum hangs from the cylinder's axis, driven through a gear whose rotor the cylinder
    // carries: the rotor's spin ε·ω_cylinder + n q̇ couples the two, the contact does no work
    // while it rolls, and the kinetic energy (the rotor's included) plus the weights' potential
    // is conserved.
    let hanging = "let bob = body mass = 1, iframe = [0, 0, -0.1] ++ 1, \
                   inertia = [0.1, 0.1, 0.1] end ;\n\
                   join cylinder and bob with geared_revolute([0, 1, 0], 10, 0.001) as hang ;\n\
                   initial motion.y = r, hang.q' = 2 ;";
    let prepared = prepare(
        &mechanism("rolling_cylinder", &[("initial motion.y = r ;", hanging)]),
        &[],
        &Settings::default(),
    )
    .unwrap_or_else(|d| panic!("{:?}", d.iter().map(|d| &d.message).collect::<Vec<_>>()));
    let simulation = completed(&prepared);
    let total = |s: &Sample| s.kinetic_energy + s.potential_energy.unwrap();
    let first = total(&simulation.samples[0]);
    let drift = (simulation.samples.iter())
        .map(|s| (total(s) - first).abs())
        .fold(0.0, f64::max);
    assert!(drift < 1e-8, "energy drift {drift:e}");
}
