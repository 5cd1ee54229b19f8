//! A thin disc's contact (`rolling_disc`, `sliding_disc`) against closed forms: the coin of
//! `examples/rolling_coin.lsd` in its steady precession (O'Reilly 2008, §9.5: for a tilt θ from
//! lying flat, a precession rate Ω and a spin n about the axis, (I_a + m r²) n Ω sin θ =
//! I_d Ω² sin θ cos θ − m g r cos θ, the centre on a circle of radius r |n| / Ω at the height
//! r sin θ), its fall from rest (a compound pendulum about its contact point when it rolls,
//! with its centre's horizontal position kept when it slides without friction), γ against
//! finite differences of the rows, and the warning for a sphere's contact on a disc (W0820).

use nalgebra::{Matrix3, Rotation3, Vector3};

use super::common::contact_rows::rows_along_motion;
use super::common::programs::{example_text, mechanism};
use lsdc::integrators::{Feature, INTEGRATORS};
use lsdc::prepare::{prepare, Prepared, Settings};
use lsdc::simulate::run::{run, Sample, Simulation};

/// Standard gravity, as the `gravity` library gives it.
const G: f64 = 9.80665;
/// The coin of the example.
const MASS: f64 = 0.0085;
const RADIUS: f64 = 0.01275;
const AXIAL: f64 = MASS * RADIUS * RADIUS / 2.0;
const DIAMETRAL: f64 = MASS * RADIUS * RADIUS / 4.0;

fn prepared(replacements: &[(&str, &str)]) -> Prepared {
    prepare(
        &mechanism("rolling_coin", replacements),
        &[],
        &Settings::default(),
    )
    .unwrap_or_else(|d| panic!("{:?}", d.iter().map(|d| &d.message).collect::<Vec<_>>()))
}

/// The coin's orientation from its Bryant angles (the free joint's a, b, c about x, y, z).
fn orientation(sample: &Sample) -> Matrix3<f64> {
    let c = &sample.coordinates;
    let about = |axis: Vector3<f64>, angle: f64| {
        Rotation3::from_axis_angle(&nalgebra::Unit::new_normalize(axis), angle).into_inner()
    };
    about(Vector3::x(), c[3]) * about(Vector3::y(), c[4]) * about(Vector3::z(), c[5])
}

/// The coin's angular velocity in fixed axes, from the Bryant angles' rates.
fn spin(sample: &Sample) -> Vector3<f64> {
    let (c, r) = (&sample.coordinates, &sample.rates);
    let (a, b) = (c[3], c[4]);
    Vector3::new(
        r[3] + r[5] * b.sin(),
        r[4] * a.cos() - r[5] * a.sin() * b.cos(),
        r[4] * a.sin() + r[5] * a.cos() * b.cos(),
    )
}

fn centre(sample: &Sample) -> Vector3<f64> {
    Vector3::new(
        sample.coordinates[0],
        sample.coordinates[1],
        sample.coordinates[2],
    )
}

fn centre_velocity(sample: &Sample) -> Vector3<f64> {
    Vector3::new(sample.rates[0], sample.rates[1], sample.rates[2])
}

/// The unit vector from the lowest point of the rim to the centre, for the coin's axis a:
/// w = (e_z − (e_z·a) a) / |…|.
fn up_the_disc(axis: &Vector3<f64>) -> Vector3<f64> {
    (Vector3::z() - axis.z * axis).normalize()
}

/// The velocity of the coin's material point at the lowest point of its rim.
fn slip(sample: &Sample) -> Vector3<f64> {
    let axis = orientation(sample) * Vector3::z();
    centre_velocity(sample) - RADIUS * spin(sample).cross(&up_the_disc(&axis))
}

fn total_energy(sample: &Sample) -> f64 {
    sample.kinetic_energy + sample.potential_energy.expect("conservative")
}

/// The integrators that run contacts, from the registry.
fn contact_integrators() -> impl Iterator<Item = &'static str> {
    (INTEGRATORS.iter())
        .filter(|entry| !entry.unsupported.contains(&Feature::Contacts))
        .map(|entry| entry.name)
}

/// The largest of each of the quantities `errors` gives at each sample.
fn largest_over<const N: usize>(
    samples: &[Sample],
    errors: impl Fn(&Sample) -> [f64; N],
) -> [f64; N] {
    let mut largest = [0.0f64; N];
    for sample in samples {
        for (k, error) in errors(sample).into_iter().enumerate() {
            largest[k] = largest[k].max(error);
        }
    }
    largest
}

fn completed(prepared: &Prepared) -> Simulation {
    let simulation = run(prepared, &mut |_| {});
    let failure = &simulation.report.failure;
    assert!(failure.is_none(), "{failure:?}");
    simulation
}

#[test]
fn the_coin_precesses_steadily_as_its_closed_form_says_with_every_integrator() {
    let (tilt, precession) = (70f64.to_radians(), 2.0);
    let (sin, cos) = tilt.sin_cos();
    let spin_rate = (DIAMETRAL * precession * precession * sin * cos - MASS * G * RADIUS * cos)
        / ((AXIAL + MASS * RADIUS * RADIUS) * precession * sin);
    // The example's numbers: n = −93.20 rad/s, the centre at 1.188 m/s on a 0.5942 m circle.
    assert!((spin_rate + 93.201776).abs() < 1e-6, "n = {spin_rate}");
    let circle = RADIUS * spin_rate / precession;
    assert!((circle + 0.594161).abs() < 1e-6, "{circle}");
    let mut integrators = 0;
    for integrator in contact_integrators() {
        integrators += 1;
        let settings = match integrator {
            "rk4" => "integrator = rk4, step = 2e-4".to_string(),
            _ => format!("integrator = {integrator}, tolerance = 1e-11"),
        };
        // A whole turn of the circle (Ω t = 6.4 rad).
        let prepared = prepared(&[
            (
                "duration = 10, output = 0.05",
                "duration = 3.2, output = 0.2",
            ),
            ("integrator = dopri5, tolerance = 1e-11", settings.as_str()),
        ]);
        let simulation = completed(&prepared);
        assert_eq!(simulation.samples.len(), 17, "{integrator}");
        let first = total_energy(&simulation.samples[0]);
        let largest = largest_over(&simulation.samples, |sample| {
            let heading = precession * sample.time;
            let across = Vector3::new(heading.cos(), heading.sin(), 0.0);
            // The centre turns about (−x_c, 0) at the rate Ω, at the height r sin θ.
            let expected_centre = Vector3::new(-circle, 0.0, RADIUS * sin) + circle * across;
            let axis = orientation(sample) * Vector3::z();
            let expected_axis = -sin * across + cos * Vector3::z();
            let expected_spin = precession * Vector3::z() + (spin_rate - precession * cos) * axis;
            [
                (centre(sample) - expected_centre).norm(),
                (axis - expected_axis).norm(),
                (spin(sample) - expected_spin).norm() / spin_rate.abs(),
                (spin(sample).dot(&axis) - spin_rate).abs() / spin_rate.abs(),
                slip(sample).norm(),
                ((total_energy(sample) - first) / first).abs(),
            ]
        });
        let names = [
            "centre (m)",
            "axis",
            "ω (relative)",
            "n (relative)",
            "slip (m/s)",
            "energy",
        ];
        let bounds = [1e-7, 1e-6, 1e-6, 1e-7, 1e-9, 1e-8];
        assert_below(integrator, names, largest, bounds);
    }
    assert_eq!(
        integrators, 4,
        "rk4, dopri5, dop853 and implicit run contacts"
    );
}

/// θ̇² of a thin disc falling from rest at the tilt `start` (from lying flat), at the tilt θ:
/// rolling, it turns about the tangent to its rim at the contact point, which stays at rest,
/// 2 m g r (sin θ₀ − sin θ) / (I_d + m r²); sliding without friction its centre falls
/// straight down, 2 m g r (sin θ₀ − sin θ) / (I_d + m r² cos² θ).
fn fall_rate_squared(start: f64, tilt: f64, rolling: bool) -> f64 {
    let lever = match rolling {
        true => 1.0,
        false => tilt.cos().powi(2),
    };
    2.0 * MASS * G * RADIUS * (start.sin() - tilt.sin())
        / (DIAMETRAL + MASS * RADIUS * RADIUS * lever)
}

/// The time the disc takes to fall flat from rest at `start`: ∫ dθ/θ̇ from 0 to θ₀, with
/// θ = θ₀ − u² taking out the square root at the start (Simpson's rule on u).
fn fall_time(start: f64, rolling: bool) -> f64 {
    let integrand = |u: f64| {
        if u == 0.0 {
            // θ̇² ≈ K cos θ₀ u² near the start.
            let k = fall_rate_squared(start, start - 1e-8, rolling) / 1e-8;
            return 2.0 / k.sqrt();
        }
        2.0 * u / fall_rate_squared(start, start - u * u, rolling).sqrt()
    };
    let (end, intervals) = (start.sqrt(), 20_000);
    let h = end / intervals as f64;
    let sum: f64 = (0..=intervals)
        .map(|i| {
            let weight = match i {
                0 => 1.0,
                i if i == intervals => 1.0,
                i if i % 2 == 1 => 4.0,
                _ => 2.0,
            };
            weight * integrand(i as f64 * h)
        })
        .sum();
    sum * h / 3.0
}

/// Each of the `largest` errors below its bound, printed with its name.
fn assert_below<const N: usize>(run: &str, names: [&str; N], largest: [f64; N], bounds: [f64; N]) {
    let shown: Vec<String> = (names.iter().zip(&largest))
        .map(|(name, error)| format!("{name} {error:.1e}"))
        .collect();
    println!("{run}: {}", shown.join(", "));
    for ((name, error), bound) in names.iter().zip(largest).zip(bounds) {
        assert!(
            error < bound,
            "{run}: {name} off by {error:e} (bound {bound:e})"
        );
    }
}

/// The run stopped where the coin fell flat, where the contact has no point: it says so, at
/// the closed form's time `expected` (within a step).
fn assert_fell_flat(simulation: &Simulation, expected: f64, integrator: &str) {
    let failure = (simulation.report.failure.as_ref()).expect("the coin fell flat");
    let message = &failure.message;
    assert!(
        message.contains("the disc of the contact `contact` fell flat"),
        "{message}"
    );
    println!(
        "{integrator}: flat at t = {} against {expected}",
        failure.time
    );
    assert!(
        (failure.time - expected).abs() < 2e-3,
        "{integrator}: flat at t = {} against {expected}",
        failure.time
    );
}

/// The coin started at rest at the tilt `start`, with `law` its contact.
fn falling(law: &str, start: f64, integrator: &str) -> Simulation {
    let initial = format!(
        "initial motion.z = r * sin({start}), motion.b = -{start} ;\n\
         simulate duration = 0.5, output = 0.01, {integrator} end ;"
    );
    let text = example_text("rolling_coin", &[("rolling_disc(r)", law)]);
    let at = text.find("initial motion.z").expect("initial values");
    let program = format!("{}{initial}\n", &text[..at]);
    let compilation = lsdc::driver::compile_text(
        "falling_coin.lsd",
        &program,
        Some(std::path::Path::new("examples")),
        &lsdc::load::LoadOptions {
            library_dirs: Vec::new(),
            use_environment: false,
            scene: None,
        },
    );
    assert!(!compilation.has_errors(), "{:?}", compilation.diagnostics);
    let mechanism = compilation.mechanism.expect("elaborates");
    let prepared = prepare(&mechanism, &[], &Settings::default()).expect("prepared");
    run(&prepared, &mut |_| {})
}

#[test]
fn the_rolling_coin_falls_as_a_compound_pendulum_about_its_contact_point_then_stops_flat() {
    let start = 80f64.to_radians();
    for integrator in contact_integrators() {
        let settings = match integrator {
            "rk4" => "integrator = rk4, step = 1e-4".to_string(),
            _ => format!("integrator = {integrator}, tolerance = 1e-11"),
        };
        let simulation = falling("rolling_disc(r)", start, &settings);
        let first = &simulation.samples[0];
        let contact_start =
            centre(first) - RADIUS * up_the_disc(&(orientation(first) * Vector3::z()));
        let largest = largest_over(&simulation.samples, |sample| {
            let axis = orientation(sample) * Vector3::z();
            let tilt = axis.z.acos();
            // The axis turns about the tangent y: θ̇ = −ω_y.
            let rate = -spin(sample).y;
            let contact = centre(sample) - RADIUS * up_the_disc(&axis);
            [
                (rate * rate - fall_rate_squared(start, tilt, true)).abs(),
                (sample.coordinates[2] - RADIUS * tilt.sin()).abs(),
                (contact - contact_start).norm(),
                slip(sample).norm(),
                ((total_energy(sample) - total_energy(first)) / total_energy(first)).abs(),
            ]
        });
        // θ̇² relative to its value at the end of the fall (1,212 s⁻²).
        let [rate, rest @ ..] = largest;
        let largest = [
            rate / fall_rate_squared(start, 0.0, true),
            rest[0],
            rest[1],
            rest[2],
            rest[3],
        ];
        let names = [
            "θ̇²",
            "height (m)",
            "contact point moved (m)",
            "slip (m/s)",
            "energy",
        ];
        assert_below(integrator, names, largest, [1e-9, 1e-12, 1e-9, 1e-9, 1e-8]);
        assert_fell_flat(&simulation, fall_time(start, true), integrator);
    }
}

#[test]
fn the_coin_sliding_without_friction_falls_with_its_centre_straight_down() {
    let start = 80f64.to_radians();
    let simulation = falling(
        "sliding_disc(r, 0)",
        start,
        "integrator = dopri5, tolerance = 1e-11",
    );
    let first = &simulation.samples[0];
    let largest = largest_over(&simulation.samples, |sample| {
        let axis = orientation(sample) * Vector3::z();
        let tilt = axis.z.acos();
        let rate = -spin(sample).y;
        [
            (rate * rate - fall_rate_squared(start, tilt, false)).abs(),
            (centre(sample).xy() - centre(first).xy()).norm(),
            ((total_energy(sample) - total_energy(first)) / total_energy(first)).abs(),
        ]
    });
    let [rate, moved, energy] = largest;
    let largest = [rate / fall_rate_squared(start, 0.0, false), moved, energy];
    let names = ["θ̇²", "centre moved sideways (m)", "energy"];
    assert_below("dopri5", names, largest, [1e-9, 1e-10, 1e-8]);
    assert_fell_flat(&simulation, fall_time(start, false), "dopri5");
}

#[test]
fn the_coin_sliding_with_friction_balances_its_energy_with_the_friction_work() {
    // Spun and launched across its rolling motion, the coin slips: the friction's work is in
    // the energy balance (relative to the largest energy). Once the slip dies out (t ≈ 0.06 s)
    // the regularised friction creeps and its rate 1/ε makes the motion stiff, as for every
    // sliding contact: the run stops before.
    let prepared = prepared(&[
        ("rolling_disc(r)", "sliding_disc(r, 0.3)"),
        (
            "initial motion.y' =",
            "initial motion.x' = 0.5, motion.y' =",
        ),
        (
            "duration = 10, output = 0.05",
            "duration = 0.05, output = 0.005",
        ),
    ]);
    let simulation = completed(&prepared);
    let balance = simulation.report.energy_balance.expect("an energy balance");
    let first = total_energy(&simulation.samples[0]);
    let last = total_energy(simulation.samples.last().expect("samples"));
    println!("energy {first:e} → {last:e}, balance {balance:e}");
    assert!(
        first - last > 1e-3 * first,
        "the friction dissipates: {first} → {last}"
    );
    assert!(balance.abs() < 1e-10, "balance {balance:e}");
}

#[test]
fn the_disc_contact_bias_is_the_rate_of_the_rows_along_the_motion() {
    // At a state off the rolling motion (the coin tilted, slipping and spinning), γ = d/dt (G v)
    // at fixed velocities, by central differences of the rows along q̇: an independent check of
    // the lowest point's rate u̇.
    let prepared = prepared(&[]);
    let model = &prepared.model;
    let mut q = vec![0.3, -0.2, 0.007, 0.5, -0.1, 0.3, 0.8];
    let norm = q[3..7].iter().map(|x| x * x).sum::<f64>().sqrt();
    q[3..7].iter_mut().for_each(|x| *x /= norm);
    let v = vec![0.4, -1.1, 0.3, 2.0, -3.0, 15.0];
    let rows = rows_along_motion(model, &q, &v, 1e-6);
    let here = &rows.here;
    assert!(here.flat_disc.is_none());
    rows.assert_bias_is_the_rate();
    // The normal row is the rate of the gap, r sin θ below the centre's height.
    assert!(
        (rows.gap_rate[0] - here.velocity[2]).abs() < 1e-8,
        "{} against {}",
        rows.gap_rate[0],
        here.velocity[2]
    );
}

#[test]
fn the_coin_has_five_position_and_three_velocity_dof() {
    let report = lsdc::studies::analysis::tree(&mechanism("rolling_coin", &[])).expect("a tree");
    let contacts = report.contacts.expect("contacts");
    assert_eq!((contacts.position_dof, contacts.velocity_dof), (5, 3));
}

fn warning_codes(name: &str, replacements: &[(&str, &str)]) -> Vec<String> {
    let prepared = prepare(&mechanism(name, replacements), &[], &Settings::default())
        .unwrap_or_else(|d| panic!("{:?}", d.iter().map(|d| &d.message).collect::<Vec<_>>()));
    prepared
        .warnings
        .iter()
        .map(|d| d.code.to_string())
        .collect()
}

#[test]
fn a_sphere_contact_on_a_thin_disc_that_can_tilt_is_warned() {
    // The coin written with a sphere's contact: warned, tilted or upright.
    assert_eq!(
        warning_codes("rolling_coin", &[("rolling_disc(r)", "rolling(r)")]),
        ["W0820"]
    );
    assert_eq!(
        warning_codes(
            "rolling_coin",
            &[
                ("rolling_disc(r)", "sliding(r, 0.2)"),
                ("motion.b = -tilt", "motion.b = -pi / 2"),
            ]
        ),
        ["W0820"]
    );
    // Not with the disc's own contact, nor for a ball, nor for a disc (a cylinder of no length)
    // rolling in a plane motion, whose axis stays parallel to the plane.
    assert!(warning_codes("rolling_coin", &[]).is_empty());
    assert!(warning_codes("rolling_ball", &[]).is_empty());
    assert!(warning_codes(
        "rolling_cylinder",
        &[("let length = 0.2", "let length = 0")]
    )
    .is_empty());
}
