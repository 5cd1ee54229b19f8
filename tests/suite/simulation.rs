//! Simulations against analytic solutions and conservation laws.

use lsdc::driver::compile_text;
use lsdc::load::LoadOptions;
use lsdc::prepare::{prepare, Integrator, Settings};
use lsdc::simulate::run::{run, Simulation};

fn simulate(text: &str, settings: Settings) -> Simulation {
    let options = LoadOptions {
        library_dirs: Vec::new(),
        use_environment: false,
        scene: None,
    };
    let compilation = compile_text("test.lsd", text, None, &options);
    assert!(!compilation.has_errors(), "{:?}", compilation.diagnostics);
    let mechanism = compilation.mechanism.expect("elaborates");
    let prepared = prepare(&mechanism, &[], &settings).unwrap_or_else(|d| panic!("{d:?}"));
    let simulation = run(&prepared, &mut |_| {});
    assert!(
        simulation.report.failure.is_none(),
        "{:?}",
        simulation.report.failure
    );
    simulation
}

/// Complete elliptic integral of the first kind, K(k), by the arithmetic-geometric mean.
fn elliptic_k(k: f64) -> f64 {
    let (mut a, mut b) = (1.0f64, (1.0 - k * k).sqrt());
    // The mean converges quadratically; 40 rounds is far more than double precision needs, and
    // a fixed count avoids waiting for a and b to agree to the last bit.
    for _ in 0..40 {
        (a, b) = (0.5 * (a + b), (a * b).sqrt());
    }
    std::f64::consts::PI / (2.0 * a)
}

#[test]
fn pendulum_period_matches_the_elliptic_integral() {
    let (g, length) = (9.81f64, 0.7f64);
    let cases = [0.1, 0.5, 1.0, 2.0, 3.0]
        .into_iter()
        .flat_map(|a| [(a, Integrator::DormandPrince), (a, Integrator::Dop853)]);
    for (amplitude, integrator) in cases {
        let period = 4.0 * (length / g).sqrt() * elliptic_k((amplitude / 2.0f64).sin());
        let text = format!(
            "import joints;\nlet bob = body mass = 1.3, iframe = [0, 0, -{length}] ++ 1, inertia = 0 end;\n\
             join earth and bob with revolute([1, 0, 0]) as swing;\n\
             apply force value = [0, 0, -{g} * bob.mass], body = earth end on bob.iframe;\n\
             initial swing.q = {amplitude};\n"
        );
        let settings = Settings {
            integrator: integrator.clone(),
            duration: 2.0 * period + period / 4.0,
            output: period / 4.0,
            rtol: 1e-14,
            atol: 1e-14,
            ..Settings::default()
        };
        let simulation = simulate(&text, settings);
        // At t = T/4 + k T/2 the pendulum passes the vertical: θ = 0 and the timing error is θ/θ̇.
        for sample in simulation.samples.iter().skip(1).step_by(2) {
            let timing_error = sample.coordinates[0] / sample.rates[0];
            assert!(
                timing_error.abs() < 1e-9 * period,
                "amplitude {amplitude}, {integrator:?}: t = {}, θ/θ̇ = {timing_error:e}",
                sample.time
            );
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Conservation laws and a classical period on the examples `double_pendulum`, `heavy_top`,
// `free_body`, `satellite_springs` and `elliptic_pendulum`. Each example carries its own
// `simulate` declaration (duration, outputs, tolerance 1e-12, dopri5), which overrides the
// default `Settings` passed here. The oracles are computed in this file from the declared
// coordinates and rates, with the examples' numbers repeated here.

use lsdc::simulate::run::Sample;

fn example(name: &str) -> String {
    let path = format!("{}/examples/{name}.lsd", env!("CARGO_MANIFEST_DIR"));
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}"))
}

/// Simulates an example with its own `simulate` settings and checks it ran for `duration`.
fn simulate_example(name: &str, duration: f64) -> Simulation {
    let started = std::time::Instant::now();
    let simulation = simulate(&example(name), Settings::default());
    let last = simulation.samples.last().expect("samples");
    assert!(
        (last.time - duration).abs() < 1e-9,
        "{name}: the run stopped at {} instead of {duration}",
        last.time
    );
    assert_eq!(simulation.report.integrator, "dopri5");
    eprintln!(
        "{name}: {} steps, {} rejected, {:.3} s wall",
        simulation.report.steps,
        simulation.report.rejected_steps,
        started.elapsed().as_secs_f64()
    );
    simulation
}

type V3 = [f64; 3];
type M3 = [[f64; 3]; 3];

/// Rotation by `angle` about coordinate axis `axis` (0 = x, 1 = y, 2 = z).
fn rot(axis: usize, angle: f64) -> M3 {
    let (s, c) = angle.sin_cos();
    let (i, j) = ((axis + 1) % 3, (axis + 2) % 3);
    let mut m = [[0.0; 3]; 3];
    m[axis][axis] = 1.0;
    m[i][i] = c;
    m[j][j] = c;
    m[j][i] = s;
    m[i][j] = -s;
    m
}

fn mul(a: &M3, b: &M3) -> M3 {
    std::array::from_fn(|i| std::array::from_fn(|j| (0..3).map(|k| a[i][k] * b[k][j]).sum()))
}

fn apply(m: &M3, v: &V3) -> V3 {
    std::array::from_fn(|i| (0..3).map(|k| m[i][k] * v[k]).sum())
}

fn transpose(m: &M3) -> M3 {
    std::array::from_fn(|i| std::array::from_fn(|j| m[j][i]))
}

fn add(a: &V3, b: &V3) -> V3 {
    std::array::from_fn(|i| a[i] + b[i])
}

fn sub(a: &V3, b: &V3) -> V3 {
    std::array::from_fn(|i| a[i] - b[i])
}

fn scale(k: f64, a: &V3) -> V3 {
    a.map(|x| k * x)
}

fn dot(a: &V3, b: &V3) -> f64 {
    (0..3).map(|i| a[i] * b[i]).sum()
}

fn cross(a: &V3, b: &V3) -> V3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn norm(a: &V3) -> f64 {
    dot(a, a).sqrt()
}

const X: V3 = [1.0, 0.0, 0.0];
const Y: V3 = [0.0, 1.0, 0.0];
const Z: V3 = [0.0, 0.0, 1.0];

/// Bryant angles (a, b, c) about x, then y, then z: the rotation Rx(a) Ry(b) Rz(c), and the
/// angular velocity in the fixed basis and in the rotated basis from the angle rates.
fn bryant(angles: &[f64], rates: &[f64]) -> (M3, V3, V3) {
    let rx = rot(0, angles[0]);
    let rxy = mul(&rx, &rot(1, angles[1]));
    let r = mul(&rxy, &rot(2, angles[2]));
    let fixed = add(
        &add(&scale(rates[0], &X), &scale(rates[1], &apply(&rx, &Y))),
        &scale(rates[2], &apply(&rxy, &Z)),
    );
    let body = apply(&transpose(&r), &fixed);
    (r, fixed, body)
}

fn angular_momentum(sample: &Sample) -> V3 {
    [sample.momentum[0], sample.momentum[1], sample.momentum[2]]
}

fn linear_momentum(sample: &Sample) -> V3 {
    [sample.momentum[3], sample.momentum[4], sample.momentum[5]]
}

/// The scale `energy_drift` divides by: the largest of |E(0)| and the kinetic energies.
fn energy_scale(samples: &[Sample], e0: f64) -> f64 {
    samples
        .iter()
        .map(|s| s.kinetic_energy.abs())
        .fold(e0.abs(), f64::max)
}

/// Item 1: the double pendulum keeps its energy to 1e-9 over 10 s (dopri5, tolerance 1e-12).
#[test]
fn double_pendulum_keeps_its_energy() {
    let simulation = simulate_example("double_pendulum", 10.0);
    assert_eq!(simulation.coordinate_names, ["shoulder.q", "elbow.q"]);
    // The example's rods: lengths, masses, centres of mass at mid-length, thin-rod moments.
    let (g, l1, m1, l2, m2) = (9.81, 1.0, 1.0, 0.8, 0.8);
    let (c1, c2, i1, i2) = (l1 / 2.0, l2 / 2.0, m1 * l1 * l1 / 12.0, m2 * l2 * l2 / 12.0);
    // Both rods swing about x: a point at distance d along the rod at absolute angle φ from the
    // downward vertical is at (y, z) = d (sin φ, −cos φ).
    let energy = |s: &Sample| {
        let (t1, t2, w1, w2) = (s.coordinates[0], s.coordinates[1], s.rates[0], s.rates[1]);
        let (phi, wphi) = (t1 + t2, w1 + w2);
        let v1 = [c1 * w1 * t1.cos(), c1 * w1 * t1.sin()];
        let v2 = [
            l1 * w1 * t1.cos() + c2 * wphi * phi.cos(),
            l1 * w1 * t1.sin() + c2 * wphi * phi.sin(),
        ];
        let kinetic = 0.5 * m1 * (v1[0] * v1[0] + v1[1] * v1[1])
            + 0.5 * i1 * w1 * w1
            + 0.5 * m2 * (v2[0] * v2[0] + v2[1] * v2[1])
            + 0.5 * i2 * wphi * wphi;
        let (z1, z2) = (-c1 * t1.cos(), -l1 * t1.cos() - c2 * phi.cos());
        (kinetic, kinetic + g * (m1 * z1 + m2 * z2))
    };
    let samples = &simulation.samples;
    let e0 = energy(&samples[0]).1;
    let scale = energy_scale(samples, e0);
    let mut drift = 0.0f64;
    for s in samples {
        let (kinetic, total) = energy(s);
        let reported = s.kinetic_energy + s.potential_energy.expect("gravity has a potential");
        assert!(
            (s.kinetic_energy - kinetic).abs() < 1e-12 * scale,
            "t = {}: kinetic energy {} against {kinetic}",
            s.time,
            s.kinetic_energy
        );
        assert!(
            (reported - total).abs() < 1e-12 * scale,
            "t = {}: energy {reported} against {total}",
            s.time
        );
        drift = drift.max((total - e0).abs() / scale);
    }
    let reported = simulation.report.energy_drift.expect("conservative");
    eprintln!("double pendulum: energy drift {reported:e} (report), {drift:e} (hand formula)");
    assert!(reported < 1e-9, "energy drift {reported:e}");
    assert!(drift < 1e-9, "energy drift {drift:e}");
}

/// Item 2: the heavy symmetric top keeps its energy, its spin about the symmetry axis and the
/// vertical component of its angular momentum about the fixed point.
#[test]
fn heavy_top_keeps_energy_spin_and_vertical_momentum() {
    let simulation = simulate_example("heavy_top", 10.0);
    assert_eq!(
        simulation.coordinate_names,
        ["pivot.a", "pivot.b", "pivot.c"]
    );
    // The example's top: centre of mass at l on the body's z axis, moments about it.
    let (g, m, l, transverse, axial) = (9.81, 1.0, 0.1, 0.01, 0.015);
    // Moments about the fixed point (the origin): parallel axes for the transverse ones.
    let moments = [transverse + m * l * l, transverse + m * l * l, axial];
    let state = |s: &Sample| {
        let (r, _, w) = bryant(&s.coordinates, &s.rates);
        let body_momentum: V3 = std::array::from_fn(|k| moments[k] * w[k]);
        let momentum = apply(&r, &body_momentum);
        let kinetic = 0.5 * dot(&w, &body_momentum);
        let height = l * apply(&r, &Z)[2];
        (kinetic, kinetic + m * g * height, w[2], momentum)
    };
    let samples = &simulation.samples;
    let (_, e0, spin0, momentum0) = state(&samples[0]);
    assert!((spin0 - 30.0).abs() < 1e-12, "initial spin {spin0}");
    let scale = energy_scale(samples, e0);
    let (mut energy_drift, mut spin_drift, mut vertical_drift) = (0.0f64, 0.0f64, 0.0f64);
    let mut largest_tilt_change = 0.0f64;
    for s in samples {
        let (kinetic, energy, spin, momentum) = state(s);
        let reported = s.kinetic_energy + s.potential_energy.expect("gravity has a potential");
        assert!(
            (s.kinetic_energy - kinetic).abs() < 1e-10 * scale,
            "t = {}: kinetic energy {} against {kinetic}",
            s.time,
            s.kinetic_energy
        );
        assert!(
            (reported - energy).abs() < 1e-10 * scale,
            "t = {}: energy {reported} against {energy}",
            s.time
        );
        let gap = norm(&sub(&angular_momentum(s), &momentum));
        assert!(
            gap < 1e-10 * norm(&momentum0),
            "t = {}: angular momentum {:?} against {momentum:?}",
            s.time,
            angular_momentum(s)
        );
        energy_drift = energy_drift.max((energy - e0).abs() / scale);
        spin_drift = spin_drift.max((spin - spin0).abs() / spin0.abs());
        vertical_drift =
            vertical_drift.max((s.momentum[2] - samples[0].momentum[2]).abs() / norm(&momentum0));
        let axis = apply(&bryant(&s.coordinates, &s.rates).0, &Z);
        largest_tilt_change = largest_tilt_change.max((axis[2] - 0.3f64.cos()).abs());
    }
    let reported = simulation.report.energy_drift.expect("conservative");
    eprintln!(
        "heavy top: energy drift {reported:e} (report), {energy_drift:e} (hand formula); spin drift {spin_drift:e}; \
         vertical momentum drift {vertical_drift:e} of |L| = {:.6}; nutation: cos(tilt) moved by {largest_tilt_change:e}",
        norm(&momentum0)
    );
    // The top does precess and nutate: the axis does not stay where it started.
    assert!(
        largest_tilt_change > 1e-4,
        "the axis barely moved: {largest_tilt_change:e}"
    );
    assert!(reported < 1e-9, "energy drift {reported:e}");
    assert!(energy_drift < 1e-9, "energy drift {energy_drift:e}");
    assert!(spin_drift < 1e-9, "spin drift {spin_drift:e}");
    assert!(
        vertical_drift < 1e-9,
        "vertical angular momentum drift {vertical_drift:e}"
    );
}

/// Item 3: a free asymmetric body spun about its intermediate axis flips over (Dzhanibekov);
/// its angular momentum stays within 1e-10 (absolute, |L| ≈ 4) and the run goes through the
/// singularity of the Bryant angles, where the middle angle is π/2.
#[test]
fn free_body_flips_through_the_angle_singularity_and_keeps_its_momentum() {
    let simulation = simulate_example("free_body", 10.0);
    assert_eq!(
        simulation.coordinate_names,
        ["drift.x", "drift.y", "drift.z", "drift.a", "drift.b", "drift.c"]
    );
    let (m, moments) = (1.0, [1.0, 2.0, 3.0]);
    let samples = &simulation.samples;
    let l0 = angular_momentum(&samples[0]);
    let p0 = linear_momentum(&samples[0]);
    assert!(
        (norm(&p0) - 0.1).abs() < 1e-12 && (norm(&l0) - 4.0).abs() < 1e-3,
        "initial momenta {p0:?}, {l0:?}"
    );
    let direction = scale(1.0 / norm(&l0), &l0);
    let (mut angular_drift, mut linear_drift, mut energy_gap) = (0.0f64, 0.0f64, 0.0f64);
    let (mut smallest_cosine, mut crossing) = (f64::INFINITY, None);
    let (mut alignment_min, mut alignment_max) = (f64::INFINITY, f64::NEG_INFINITY);
    let mut previous: Option<&Sample> = None;
    for s in samples {
        angular_drift = angular_drift.max(norm(&sub(&angular_momentum(s), &l0)));
        linear_drift = linear_drift.max(norm(&sub(&linear_momentum(s), &p0)));
        let (position, velocity) = (
            [s.coordinates[0], s.coordinates[1], s.coordinates[2]],
            [s.rates[0], s.rates[1], s.rates[2]],
        );
        let (r, _, w) = bryant(&s.coordinates[3..], &s.rates[3..]);
        // The rotation from the angles alone (exact even at the singularity) with the conserved
        // momenta gives the kinetic energy: p² / 2m + ½ Σ L_k² / I_k, L = L0 − r × p0 in the
        // body's axes. (Positions and angles only: no declared rate enters.)
        let spin = apply(&transpose(&r), &sub(&l0, &cross(&position, &p0)));
        let kinetic = 0.5 * dot(&p0, &p0) / m
            + (0..3)
                .map(|k| 0.5 * spin[k] * spin[k] / moments[k])
                .sum::<f64>();
        energy_gap = energy_gap.max((kinetic - s.kinetic_energy).abs() / s.kinetic_energy);
        // Away from the singularity the angle rates are well conditioned: R I ω + m r × v is
        // the momentum the simulation reports.
        if s.coordinates[4].cos().abs() > 0.1 {
            let own = add(
                &apply(&r, &std::array::from_fn(|k| moments[k] * w[k])),
                &scale(m, &cross(&position, &velocity)),
            );
            assert!(
                norm(&sub(&own, &angular_momentum(s))) < 1e-10 * norm(&l0),
                "t = {}: {own:?} against {:?}",
                s.time,
                angular_momentum(s)
            );
        }
        let alignment = dot(&apply(&r, &Y), &direction);
        alignment_min = alignment_min.min(alignment);
        alignment_max = alignment_max.max(alignment);
        smallest_cosine = smallest_cosine.min(s.coordinates[4].cos().abs());
        if let Some(p) = previous {
            let branch =
                |b: f64| ((b - std::f64::consts::FRAC_PI_2) / std::f64::consts::PI).floor();
            if crossing.is_none() && branch(p.coordinates[4]) != branch(s.coordinates[4]) {
                crossing = Some(s.time);
            }
        }
        previous = Some(s);
    }
    let lsdc::simulate::run::MomentumDrift { linear, angular } = simulation
        .report
        .momentum_drift
        .expect("a free body without efforts");
    eprintln!(
        "free body: angular momentum drift {angular_drift:e} (|L| = {:.6}), report {angular:e}; linear {linear_drift:e}, report {linear:e}; \
         kinetic energy from the angles {energy_gap:e}; first crossing of π/2 + kπ at t = {crossing:?}; smallest |cos b| {smallest_cosine:e}; \
         y axis along L from {alignment_max:.6} to {alignment_min:.6}; energy drift {:?}",
        norm(&l0),
        simulation.report.energy_drift
    );
    assert!(
        crossing.is_some(),
        "the middle angle never crossed π/2 + kπ (smallest |cos b| = {smallest_cosine:e})"
    );
    // The flip: the intermediate axis starts along L and turns to point against it.
    assert!(
        alignment_max > 0.99 && alignment_min < -0.99,
        "no flip: y·L/|L| within [{alignment_min}, {alignment_max}]"
    );
    assert!(
        angular_drift < 1e-10,
        "angular momentum drift {angular_drift:e}"
    );
    assert!(
        angular < 1e-10,
        "reported angular momentum drift {angular:e}"
    );
    assert!(
        energy_gap < 1e-10,
        "kinetic energy from the angles differs by {energy_gap:e}"
    );
}

/// Item 4: the satellite of `satellite_numeric.lsd`, free, with springs and dampers in its arm's
/// joints: its total linear and angular momentum are conserved, and its centre of mass moves
/// in a straight line at constant speed.
#[test]
fn satellite_with_joint_springs_keeps_its_momentum() {
    let simulation = simulate_example("satellite_springs", 10.0);
    assert_eq!(
        simulation.coordinate_names,
        [
            "base.x", "base.y", "base.z", "base.ps", "base.th", "base.ph", "hinge.x", "slide.x",
            "tilt.x"
        ]
    );
    let (m_satellite, m_reflector, z12, z34) = (1200.0, 40.0, 0.8, 0.5);
    let total = m_satellite + m_reflector;
    // `join satellite.frame and earth with D`: the satellite's pose is D⁻¹, D = T(x, y, z)
    // Rz(ψ) Rx(θ) Rz(φ). The reflector's centre of mass is z34 up its frame, reached through
    // the hinge (Rx at z12), the slide (along y) and the tilt (Ry).
    let centre_of_mass = |s: &Sample| {
        let q = &s.coordinates;
        let rotation = mul(&mul(&rot(2, q[3]), &rot(0, q[4])), &rot(2, q[5]));
        let back = transpose(&rotation);
        let translation = [q[0], q[1], q[2]];
        let satellite = scale(-1.0, &apply(&back, &translation));
        let arm = add(&[0.0, q[7], 0.0], &apply(&rot(1, q[8]), &[0.0, 0.0, z34]));
        let reflector_local = add(&[0.0, 0.0, z12], &apply(&rot(0, q[6]), &arm));
        let reflector = apply(&back, &sub(&reflector_local, &translation));
        scale(
            1.0 / total,
            &add(
                &scale(m_satellite, &satellite),
                &scale(m_reflector, &reflector),
            ),
        )
    };
    let samples = &simulation.samples;
    let (p0, l0) = (linear_momentum(&samples[0]), angular_momentum(&samples[0]));
    let (r0, v0) = (centre_of_mass(&samples[0]), scale(1.0 / total, &p0));
    let (mut straight, mut linear_drift, mut angular_drift) = (0.0f64, 0.0f64, 0.0f64);
    let (mut hinge_min, mut hinge_max) = (f64::INFINITY, f64::NEG_INFINITY);
    for s in samples {
        straight = straight.max(norm(&sub(
            &centre_of_mass(s),
            &add(&r0, &scale(s.time, &v0)),
        )));
        linear_drift = linear_drift.max(norm(&sub(&linear_momentum(s), &p0)));
        angular_drift = angular_drift.max(norm(&sub(&angular_momentum(s), &l0)));
        hinge_min = hinge_min.min(s.coordinates[6]);
        hinge_max = hinge_max.max(s.coordinates[6]);
    }
    let lsdc::simulate::run::MomentumDrift { linear, angular } = simulation
        .report
        .momentum_drift
        .expect("nothing outside acts on the satellite");
    let (linear, angular) = (linear / norm(&p0), angular / norm(&l0));
    eprintln!(
        "satellite: |p| = {:.6}, |L| = {:.6}; relative momentum drift: linear {linear:e}, angular {angular:e} (report), \
         {:e}, {:e} (samples); centre of mass off its line by {straight:e} m; hinge within [{hinge_min:.4}, {hinge_max:.4}]",
        norm(&p0),
        norm(&l0),
        linear_drift / norm(&p0),
        angular_drift / norm(&l0)
    );
    assert!(
        hinge_max - hinge_min > 0.1,
        "the arm barely moved: hinge within [{hinge_min}, {hinge_max}]"
    );
    assert!(norm(&v0) > 0.05, "the centre of mass should drift: {v0:?}");
    assert!(linear < 1e-9, "linear momentum drift {linear:e} of |p|");
    assert!(angular < 1e-9, "angular momentum drift {angular:e} of |L|");
    assert!(
        straight < 1e-9,
        "the centre of mass left its straight line by {straight:e} m"
    );
}

/// Item 5: Euler's elliptic pendulum (a cart of mass m1 = 2 on a rail, a point mass m2 = 1 on
/// a rod of length a = 0.5, g = 9.81): small oscillations have a period of 1.158203 s, from
/// ω² = g (m1 + m2) / (m1 a). The period is measured from the zero crossings of the angle,
/// located by cubic Hermite interpolation between outputs.
#[test]
fn elliptic_pendulum_small_oscillation_period() {
    let simulation = simulate_example("elliptic_pendulum", 6.0);
    assert_eq!(simulation.coordinate_names, ["rail.q", "swing.q"]);
    let samples = &simulation.samples;
    assert!((samples[0].coordinates[1] - 1e-3).abs() < 1e-15);
    let mut crossings = Vec::new();
    for pair in samples.windows(2) {
        let (a, b) = (&pair[0], &pair[1]);
        let (p0, p1) = (a.coordinates[1], b.coordinates[1]);
        if p0 == 0.0 || p0.signum() == p1.signum() {
            continue;
        }
        let h = b.time - a.time;
        let (m0, m1) = (a.rates[1] * h, b.rates[1] * h);
        let hermite = |s: f64| {
            let (s2, s3) = (s * s, s * s * s);
            (2.0 * s3 - 3.0 * s2 + 1.0) * p0
                + (s3 - 2.0 * s2 + s) * m0
                + (-2.0 * s3 + 3.0 * s2) * p1
                + (s3 - s2) * m1
        };
        let (mut lo, mut hi) = (0.0f64, 1.0f64);
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if hermite(mid).signum() == p0.signum() {
                lo = mid
            } else {
                hi = mid
            }
        }
        crossings.push(a.time + 0.5 * (lo + hi) * h);
    }
    assert!(crossings.len() >= 8, "{} crossings", crossings.len());
    let period =
        2.0 * (crossings[crossings.len() - 1] - crossings[0]) / (crossings.len() - 1) as f64;
    let half_periods: Vec<f64> = crossings.windows(2).map(|w| w[1] - w[0]).collect();
    let spread = half_periods
        .iter()
        .map(|d| (2.0 * d - period).abs())
        .fold(0.0, f64::max);
    let (m1, m2, a, g) = (2.0f64, 1.0f64, 0.5f64, 9.81f64);
    let linear = 2.0 * std::f64::consts::PI * (m1 * a / (g * (m1 + m2))).sqrt();
    eprintln!(
        "elliptic pendulum: period {period:.9} s over {} crossings (half periods within {spread:e} s); 1.158203 (note), \
         {linear:.9} (formula); relative error {:e} against the note, {:e} against the formula",
        crossings.len(),
        (period - 1.158203) / 1.158203,
        (period - linear) / linear
    );
    assert!(
        ((period - 1.158203) / 1.158203).abs() < 1e-6,
        "period {period}"
    );
    // A sharper oracle: with p_x = 0 the angle obeys L = ½ m2 a² (1 − μ cos²θ) θ̇² + m2 g a cos θ,
    // μ = m2 / (m1 + m2): an inertia (1 − μ)(1 + α θ²), α = μ / (1 − μ), and the pendulum's
    // potential. At amplitude A the period is T0 (1 + (α/4 + 1/16) A² + O(A⁴)).
    let (amplitude, mu) = (1e-3f64, m2 / (m1 + m2));
    let alpha = mu / (1.0 - mu);
    let corrected = linear * (1.0 + (alpha / 4.0 + 1.0 / 16.0) * amplitude * amplitude);
    eprintln!("elliptic pendulum: period {period:.12} against {corrected:.12} at amplitude {amplitude}: relative {:e}", (period - corrected) / corrected);
    assert!(
        ((period - corrected) / corrected).abs() < 1e-9,
        "period {period} against {corrected} with the amplitude correction"
    );
}

/// The declared rates of a free joint are the body's velocity in the program's coordinates: the
/// rates of x, y, z are p / m, and the Bryant angle rates give the angular velocity
/// R I⁻¹ Rᵀ (L − r × p). Checked away from the singularity (|cos b| > 0.1), to 1e-10 of |v| and |ω|.
#[test]
fn free_body_declared_rates_match_its_velocity() {
    let simulation = simulate_example("free_body", 10.0);
    let (m, moments) = (1.0, [1.0, 2.0, 3.0]);
    let (mut worst_linear, mut worst_angular) = ((0.0f64, 0.0f64), (0.0f64, 0.0f64));
    for s in &simulation.samples {
        if s.coordinates[4].cos().abs() <= 0.1 {
            continue;
        }
        let (p, l) = (linear_momentum(s), angular_momentum(s));
        let position = [s.coordinates[0], s.coordinates[1], s.coordinates[2]];
        let velocity = scale(1.0 / m, &p);
        let (r, omega, _) = bryant(&s.coordinates[3..], &s.rates[3..]);
        let spin = apply(&transpose(&r), &sub(&l, &cross(&position, &p)));
        let expected = apply(&r, &std::array::from_fn(|k| spin[k] / moments[k]));
        let linear = norm(&sub(&[s.rates[0], s.rates[1], s.rates[2]], &velocity)) / norm(&velocity);
        let angular = norm(&sub(&omega, &expected)) / norm(&expected);
        if linear > worst_linear.0 {
            worst_linear = (linear, s.time);
        }
        if angular > worst_angular.0 {
            worst_angular = (angular, s.time);
        }
    }
    eprintln!(
        "free body: declared rates off by {:e} (linear, t = {}), {:e} (angular, t = {})",
        worst_linear.0, worst_linear.1, worst_angular.0, worst_angular.1
    );
    assert!(
        worst_linear.0 < 1e-10,
        "x', y', z' off the velocity by {:e} of |v| at t = {}",
        worst_linear.0,
        worst_linear.1
    );
    assert!(
        worst_angular.0 < 1e-10,
        "angle rates off the angular velocity by {:e} of |ω| at t = {}",
        worst_angular.0,
        worst_angular.1
    );
}

/// `examples/speed_feedback_motor`: a geared motor (ratio r) whose law `2 - c q'` reads the
/// join's own rate drives an inertia J about its axis. J q'' = r (2 - c q') from rest gives
/// q' = (2/c)(1 - e^{-t/τ}) and q = (2/c)(t - τ (1 - e^{-t/τ})), τ = J / (r c).
#[test]
fn motor_reading_its_own_rate_follows_the_first_order_response() {
    let (ratio, c, inertia) = (3.0f64, 0.05f64, 0.6f64);
    let tau = inertia / (ratio * c);
    let simulation = simulate_example("speed_feedback_motor", 10.0);
    assert!(simulation.samples.len() > 10);
    for sample in &simulation.samples {
        let t = sample.time;
        let decay = (-t / tau).exp();
        let rate = 2.0 / c * (1.0 - decay);
        let angle = 2.0 / c * (t - tau * (1.0 - decay));
        assert!(
            (sample.rates[0] - rate).abs() < 1e-7 * (2.0 / c),
            "t = {t}: q' = {}, expected {rate}",
            sample.rates[0]
        );
        assert!(
            (sample.coordinates[0] - angle).abs() < 1e-7 * (1.0 + angle),
            "t = {t}: q = {}, expected {angle}",
            sample.coordinates[0]
        );
    }
}

/// A join read in its own link by a definition (`damped(spin)`) and directly, its second
/// coordinate read first: each `spin.x` is the link's coordinate of that name. Decoupled
/// along z: a damped spin J a'' = -a' and a spring slider m s'' = -s.
#[test]
fn a_join_reads_its_own_coordinates_by_name_in_any_order() {
    let text = "let rotor = body mass = 3, iframe = 1, inertia = [0.4, 0.4, 0.6] end;\n\
        let damped(j) = -j.a';\n\
        join earth and rotor with link(s, a)\n\
          dof1 = s * [0, 0, 1], dof2 = a || [0, 0, 1],\n\
          torque2 = [0, 0, damped(spin)], force1 = [0, 0, -spin.s]\n\
        end as spin;\n\
        initial spin.s = 0.5, spin.a' = 1;\n";
    let settings = Settings {
        duration: 2.0,
        output: 0.5,
        rtol: 1e-12,
        atol: 1e-12,
        ..Settings::default()
    };
    let (mass, inertia) = (3.0f64, 0.6f64);
    for sample in &simulate(text, settings).samples {
        let t = sample.time;
        let slider = 0.5 * (t / mass.sqrt()).cos();
        let spin_rate = (-t / inertia).exp();
        assert!((sample.coordinates[0] - slider).abs() < 1e-8, "t = {t}: s");
        assert!((sample.rates[1] - spin_rate).abs() < 1e-8, "t = {t}: a'");
    }
}
