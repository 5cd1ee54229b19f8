//! Stops on joint coordinates (links' `lower`, `upper`, `restitution`): impacts located in time
//! against the closed forms of the motion, the impact law, and the refusals.

use lsdc::driver::compile_text;
use lsdc::dynamics::contacts::ContactRows;
use lsdc::dynamics::driven_points::PointRows;
use lsdc::dynamics::mimics::Mimic;
use lsdc::dynamics::response::Response;
use lsdc::dynamics::rows::{impact_velocities, HeldRow, Holder, RowStack};
use lsdc::dynamics::stops::Impact;
use lsdc::dynamics::stops::{Side, Stop};
use lsdc::load::LoadOptions;
use lsdc::prepare::{prepare, Integrator, Settings};
use lsdc::simulate::run::{run, Simulation};
use nalgebra::{DMatrix, DVector};

fn compile(text: &str) -> lsdc::driver::Compilation {
    let options = LoadOptions {
        library_dirs: Vec::new(),
        use_environment: false,
        scene: None,
    };
    compile_text("test.lsd", text, None, &options)
}

fn simulate(text: &str, settings: Settings) -> Simulation {
    let compilation = compile(text);
    assert!(!compilation.has_errors(), "{:?}", compilation.diagnostics);
    let mechanism = compilation.mechanism.expect("elaborates");
    let prepared = prepare(&mechanism, &[], &settings).unwrap_or_else(|d| panic!("{d:?}"));
    run(&prepared, &mut |_| {})
}

/// Complete elliptic integral of the first kind, K(k), by the arithmetic-geometric mean.
fn elliptic_k(k: f64) -> f64 {
    let (mut a, mut b) = (1.0f64, (1.0 - k * k).sqrt());
    for _ in 0..40 {
        (a, b) = (0.5 * (a + b), (a * b).sqrt());
    }
    std::f64::consts::PI / (2.0 * a)
}

fn settings(integrator: Integrator, duration: f64, tolerance: f64) -> Settings {
    Settings {
        integrator,
        duration,
        output: duration / 10.0,
        rtol: tolerance,
        atol: tolerance,
        ..Settings::default()
    }
}

const PENDULUM: &str = "import joints;\n\
    let rod = body mass = 1.2, iframe = [0, 0, -0.5] ++ 1, inertia = [0.1, 0.1, 0.001] end;\n\
    join earth and rod with limited_revolute([1, 0, 0], 0, pi, RESTITUTION) as swing;\n\
    apply force value = [0, 0, -9.81 * rod.mass], body = earth end on rod.iframe;\n\
    initial swing.q = pi / 2;\n";

/// The rod released from the horizontal reaches the stop at the bottom after a quarter period
/// of the swing from 90°, K(sin 45°)/ω0 with ω0² = m g d / I about the pivot; it leaves with e
/// times its rate, swings up to θ1 with 1 − cos θ1 = e² (1 − cos 90°) and comes back after a
/// half period of that swing, 2 K(sin(θ1/2))/ω0.
fn pendulum_impact_times(e: f64) -> [f64; 2] {
    let (m, g, d, inertia): (f64, f64, f64, f64) = (1.2, 9.81, 0.5, 0.1 + 1.2 * 0.25);
    let omega0 = (m * g * d / inertia).sqrt();
    let first = elliptic_k(std::f64::consts::FRAC_PI_4.sin()) / omega0;
    let theta1 = (1.0 - e * e).acos();
    [
        first,
        first + 2.0 * elliptic_k((theta1 / 2.0).sin()) / omega0,
    ]
}

fn check_impact_law(impact: &Impact, e: f64) {
    let rate = impact.rate_after / impact.rate_before;
    assert!((rate + e).abs() < 1e-12, "rate ratio {rate}");
    // One coordinate: all the kinetic energy is normal to the stop, and e² of it is kept.
    let kept = impact.kinetic_after / impact.kinetic_before;
    assert!((kept - e * e).abs() < 1e-12, "kept {kept}");
}

#[test]
fn a_pendulum_hits_its_stop_when_the_elliptic_integral_says() {
    let e = 0.5;
    let expected = pendulum_impact_times(e);
    let text = PENDULUM.replace("RESTITUTION", &e.to_string());
    let cases = [
        (Integrator::DormandPrince, 1e-12, 1e-9),
        (Integrator::Dop853, 1e-12, 1e-9),
        (Integrator::Implicit, 1e-10, 1e-6),
        (Integrator::Rk4, 1e-10, 1e-6),
    ];
    for (integrator, tolerance, bound) in cases {
        let mut settings = settings(integrator.clone(), 1.5, tolerance);
        if integrator == Integrator::Rk4 {
            settings.step = Some(1e-3);
        }
        let simulation = simulate(&text, settings);
        let report = &simulation.report;
        assert!(report.failure.is_none(), "{:?}", report.failure);
        assert_eq!(
            report.impacts.len(),
            2,
            "{integrator:?}: {:?}",
            report.impacts
        );
        for (impact, time) in report.impacts.iter().zip(expected) {
            assert_eq!(impact.side, Side::Lower);
            assert!(
                (impact.time - time).abs() < bound,
                "{integrator:?}: impact at {} instead of {time}",
                impact.time
            );
            check_impact_law(impact, e);
        }
    }
}

#[test]
fn a_body_falling_onto_a_prismatic_stop_bounces_on_time() {
    let (g, h, e) = (9.81f64, 0.8f64, 0.6f64);
    let text = format!(
        "import joints;\n\
         let block = body mass = 2, iframe = 0, inertia = [0.1, 0.1, 0.1] end;\n\
         join earth and block with limited_prismatic([0, 0, 1], -{h}, 1, {e}) as slide;\n\
         apply force value = [0, 0, -{g} * block.mass], body = earth end on block.frame;\n"
    );
    // Free fall from rest: the stop after √(2h/g), then flights of 2 eᵏ v1 / g.
    let v1 = (2.0 * g * h).sqrt();
    let first = (2.0 * h / g).sqrt();
    let expected = [
        first,
        first + 2.0 * e * v1 / g,
        first + 2.0 * e * v1 / g + 2.0 * e * e * v1 / g,
    ];
    for integrator in [Integrator::DormandPrince, Integrator::Rk4] {
        let mut settings = settings(integrator.clone(), 1.25, 1e-12);
        settings.step = Some(1e-3);
        let simulation = simulate(&text, settings);
        let report = &simulation.report;
        assert!(report.failure.is_none(), "{:?}", report.failure);
        assert_eq!(report.impacts.len(), 3, "{:?}", report.impacts);
        for (k, (impact, time)) in report.impacts.iter().zip(expected).enumerate() {
            // The free fall is a polynomial of degree 2, which both methods follow exactly.
            assert!(
                (impact.time - time).abs() < 1e-10,
                "{integrator:?}: impact {k} at {} instead of {time}",
                impact.time
            );
            let speed = v1 * e.powi(k as i32);
            assert!((impact.rate_before + speed).abs() < 1e-9 * speed);
            check_impact_law(impact, e);
        }
    }
}

/// The oracle the run's impact (on the constraint stack) is checked against: the velocities just
/// after an impact on `stop` from the dense saddle-point system of the mass matrix, the rows
/// `g` kept (G v⁺ = 0) and the stop's row with its restitution, by a rank-revealing singular
/// value decomposition: v⁺ = v⁻ + M⁻¹ (Gᵀ Λ + eₖ P).
fn saddle_point_impact(
    stop: &Stop,
    mass: &DMatrix<f64>,
    loops: Option<&DMatrix<f64>>,
    v: &[f64],
) -> Option<DVector<f64>> {
    let n = mass.nrows();
    let k = stop.velocity;
    let empty = DMatrix::zeros(0, n);
    let g = loops.unwrap_or(&empty);
    let rows = g.nrows();
    // [M  −Gᵀ  −eₖ] [Δv]   [0]
    // [G   0    0 ] [Λ ] = [−G v⁻]
    // [eₖᵀ 0    0 ] [P ]   [−(1 + e) vₖ]
    let system = saddle_point(mass, g, &[k]);
    let mut right = DVector::zeros(n + rows + 1);
    let before = DVector::from_column_slice(v);
    right.rows_mut(n, rows).copy_from(&(-(g * &before)));
    right[n + rows] = -(1.0 + stop.restitution) * v[k];
    let solution = rank_revealing_solve(system, &right)?;
    Some(before + solution.rows(0, n))
}

/// The saddle-point matrix of the mass matrix `mass`, the constraint rows `g` and the unit rows
/// of the velocities `held`: [M −Gᵀ −Eᵀ; G 0 0; E 0 0].
fn saddle_point(mass: &DMatrix<f64>, g: &DMatrix<f64>, held: &[usize]) -> DMatrix<f64> {
    let (n, rows) = (mass.nrows(), g.nrows());
    let size = n + rows + held.len();
    let mut system = DMatrix::zeros(size, size);
    system.view_mut((0, 0), (n, n)).copy_from(mass);
    system
        .view_mut((0, n), (n, rows))
        .copy_from(&(-g.transpose()));
    system.view_mut((n, 0), (rows, n)).copy_from(g);
    for (i, &k) in held.iter().enumerate() {
        system[(k, n + rows + i)] = -1.0;
        system[(n + rows + i, k)] = 1.0;
    }
    system
}

/// A rank-revealing solve: redundant constraint rows (a planar loop's, a follower held with
/// its leader) leave the velocities or accelerations well defined, though not their forces.
fn rank_revealing_solve(system: DMatrix<f64>, right: &DVector<f64>) -> Option<DVector<f64>> {
    system.svd(true, true).solve(right, 1e-12).ok()
}

/// The run's impact: the stop's row (with its rate after) and the `mimics` as rows of the
/// constraint stack, solved on X = M⁻¹.
fn stack_impact(stop: &Stop, mass: &DMatrix<f64>, mimics: &[Mimic], v: &[f64]) -> DVector<f64> {
    let n = mass.nrows();
    let mut response = Response::default();
    assert!(response.on_tree(mass));
    let mut stack = RowStack::over(n, 0);
    let row = HeldRow {
        velocity: stop.velocity,
        holder: Holder::Impact {
            index: 0,
            rate_after: -stop.restitution * v[stop.velocity],
        },
    };
    let contacts = ContactRows::default();
    let points = PointRows::default();
    stack.arrange(&[], mimics.len(), &points, &[row]);
    stack.gather(&contacts, mimics, &points);
    let mut after = vec![0.0; n];
    assert!(impact_velocities(
        &mut stack,
        &mut response,
        &contacts,
        mimics,
        &points,
        v,
        &mut after
    ));
    DVector::from_vec(after)
}

/// A mass matrix with coupling: the impulse acts through it, so the other rates change too,
/// M (v⁺ − v⁻) is along the stopped coordinate alone, and the kinetic energy lost is
/// (1 − e²) of the part normal to the stop, ½ v_k² / (M⁻¹)_kk; the constraint stack's impact
/// agrees with the dense saddle point to round-off, with and without a coupling row.
#[test]
fn the_impulse_acts_through_the_mass_matrix() {
    let mass = DMatrix::from_row_slice(3, 3, &[3.0, 0.8, -0.4, 0.8, 2.0, 0.3, -0.4, 0.3, 1.5]);
    let v = [0.7, -1.3, 0.4];
    let stop = Stop {
        coordinate: "b.q".to_string(),
        side: Side::Upper,
        bound: 1.0,
        restitution: 0.3,
        position: 1,
        velocity: 1,
    };
    let after = stack_impact(&stop, &mass, &[], &v);
    let oracle = saddle_point_impact(&stop, &mass, None, &v).expect("solvable");
    assert!(
        (&after - &oracle).amax() < 1e-15,
        "{after} against {oracle}"
    );
    let before = DVector::from_column_slice(&v);
    assert!((after[1] + 0.3 * v[1]).abs() < 1e-14);
    let impulse = &mass * (&after - &before);
    assert!(
        impulse[0].abs() < 1e-14 && impulse[2].abs() < 1e-14,
        "{impulse}"
    );
    let energy = |x: &DVector<f64>| 0.5 * x.dot(&(&mass * x));
    let inverse = mass.clone().try_inverse().unwrap();
    let normal = 0.5 * v[1] * v[1] / inverse[(1, 1)];
    let lost = energy(&before) - energy(&after);
    assert!(
        (lost - (1.0 - 0.09) * normal).abs() < 1e-13,
        "{lost} {normal}"
    );
    // Kept through the impact, a coupling row q̇₀ − 2 q̇₂ = 0 changes the impulse but not the
    // law.
    let coupling = Mimic {
        joint: 0,
        leader_joint: 2,
        coordinate: "a.q".to_string(),
        leader_coordinate: "c.q".to_string(),
        position: 0,
        velocity: 0,
        leader_position: 2,
        leader_velocity: 2,
        multiplier: 2.0,
        offset: 0.0,
    };
    let g = DMatrix::from_row_slice(1, 3, &[1.0, 0.0, -2.0]);
    let v = [0.8, -1.3, 0.4];
    let after = stack_impact(&stop, &mass, &[coupling], &v);
    let oracle = saddle_point_impact(&stop, &mass, Some(&g), &v).expect("solvable");
    assert!(
        (&after - &oracle).amax() < 1e-14,
        "{after} against {oracle}"
    );
    assert!((after[0] - 2.0 * after[2]).abs() < 1e-13);
    assert!((after[1] + 0.3 * v[1]).abs() < 1e-13);
}

#[test]
fn a_coordinate_stopped_dead_rests_and_the_symplectic_method_refuses_stops() {
    // At the bottom, the rod stopped dead rests in equilibrium: the run goes on.
    let text = PENDULUM.replace("RESTITUTION", "0");
    let simulation = simulate(&text, settings(Integrator::DormandPrince, 1.0, 1e-10));
    assert!(simulation.report.failure.is_none());
    assert_eq!(simulation.report.impacts.len(), 1);
    assert!(!simulation.report.impacts[0].rests);
    // Above it, gravity holds it against the stop: it rests there, held by the stop's contact
    // torque, and stays at the bound.
    let text = text.replace(
        "limited_revolute([1, 0, 0], 0, pi",
        "limited_revolute([1, 0, 0], 0.3, pi",
    );
    let simulation = simulate(&text, settings(Integrator::DormandPrince, 1.0, 1e-10));
    assert!(
        simulation.report.failure.is_none(),
        "{:?}",
        simulation.report.failure
    );
    assert_eq!(simulation.report.impacts.len(), 1);
    assert!(simulation.report.impacts[0].rests);
    let last = simulation.samples.last().expect("samples");
    assert!(
        (last.coordinates[0] - 0.3).abs() < 1e-12,
        "{:?}",
        last.coordinates
    );
    let text = PENDULUM.replace("RESTITUTION", "1");
    let simulation = simulate(&text, settings(Integrator::Symplectic, 1.0, 1e-10));
    let failure = simulation.report.failure.expect("refused");
    assert!(
        failure.message.contains("does not handle stops"),
        "{}",
        failure.message
    );
}

#[test]
fn bad_stops_are_located_errors() {
    let cases = [
        ("limited_revolute([1, 0, 0], 1, 0, 0.5)", "E0451"),
        ("limited_revolute([1, 0, 0], 0, 1, 1.5)", "E0452"),
        (
            "link(a, b) dof1 = a || [1, 0, 0], dof2 = b || [0, 1, 0], lower = 0 end",
            "E0450",
        ),
    ];
    for (link, code) in cases {
        let text = format!(
            "import joints;\nlet rod = body mass = 1, iframe = [0, 0, -0.5] ++ 1, inertia = [0.1, 0.1, 0.1] end;\n\
             join earth and rod with {link} as swing;\n"
        );
        let compilation = compile(&text);
        let mechanism = compilation.mechanism.expect("elaborates");
        let errors = prepare(&mechanism, &[], &Settings::default())
            .err()
            .expect("refused");
        assert!(errors.iter().any(|d| d.code == code), "{code}: {errors:?}");
    }
}

/// While the rod rests on its stop, its acceleration is held at zero: the Jacobian the
/// implicit method uses there is that of the held right-hand side (the differences of f), not
/// the free motion's from inverse dynamics, whose row of the stopped coordinate is not zero.
/// Radau IIA, which Newton-iterates with it, then follows dopri5 through the resting phase.
#[test]
fn the_jacobian_while_resting_is_the_held_right_hand_sides() {
    use lsdc::integrate::{integrate, Method, OdeSystem, Settings as Steps};
    use lsdc::simulate::system::MechanicalSystem;
    let text = PENDULUM
        .replace("RESTITUTION", "0")
        .replace("0, pi, ", "0.3, pi, ")
        .replace("swing.q = pi / 2", "swing.q = 0.3");
    let prepared = super::common::programs::prepared_text(&text);
    let y = super::common::programs::initial_state(&prepared);
    let model = &prepared.model;
    let reference = prepared.coordinates.clone();
    let stabilisation = prepared.settings.stabilisation;
    let mut system = MechanicalSystem::new(model, reference.clone(), stabilisation);
    system.state.resting[0] = true;
    let n = y.len();
    let mut f = vec![0.0; n];
    system.derivative(0.0, &y, &mut f).expect("f");
    assert!(f[1].abs() < 1e-14, "held acceleration {}", f[1]);
    assert!(system.scratch.contact[0] > 0.0, "the stop pushes");
    let mut given = nalgebra::DMatrix::zeros(n, n);
    if OdeSystem::jacobian(&mut system, 0.0, &y, &f, &mut given).expect("jacobian") {
        for j in 0..n {
            let mut moved = y.clone();
            moved[j] += 1e-7;
            let mut g = vec![0.0; n];
            system.derivative(0.0, &moved, &mut g).expect("f");
            for i in 0..n {
                let difference = (g[i] - f[i]) / 1e-7;
                assert!((difference - given[(i, j)]).abs() < 1e-5, "({i}, {j})");
            }
        }
    }
    // Through the resting phase: from rest at the bound, held there by its weight.
    let steps = Steps {
        rtol: 1e-10,
        atol: 1e-10,
        ..Steps::default()
    };
    let mut ends = Vec::new();
    for method in [Method::Radau5, Method::DormandPrince] {
        let mut system = MechanicalSystem::new(model, reference.clone(), stabilisation);
        system.state.resting[0] = true;
        let mut observer = |_: f64, _: &[f64]| Ok(());
        let (end, _) = integrate(
            &method,
            &mut system,
            0.0,
            &y,
            2.0,
            &[],
            &steps,
            &mut observer,
        )
        .expect("integrates");
        ends.push(end);
    }
    for end in &ends {
        assert!(
            (end[0] - 0.3).abs() < 1e-12 && end[1].abs() < 1e-12,
            "{end:?}"
        );
    }
}
