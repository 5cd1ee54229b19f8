//! The Jacobian of a tree's equations of motion that the implicit integrator takes from inverse
//! dynamics (`MechanicalSystem::jacobian`), against differences of the equations of motion
//! themselves: central differences (truncation error O(δ²)) and forward ones, the implicit
//! method's own way before.

use crate::common::programs::prepared;
use lsdc::dynamics::loops::Stabilisation;
use lsdc::prepare::Prepared;
use lsdc::simulate::system::MechanicalSystem;
use nalgebra::DMatrix;

/// f at y, and the power of the non-conservative efforts there.
fn evaluated(system: &mut MechanicalSystem, y: &[f64]) -> (Vec<f64>, f64) {
    let mut dydt = vec![0.0; y.len()];
    system.derivative(0.0, y, &mut dydt).expect("f");
    (dydt, system.scratch.power)
}

/// ∂f/∂y and the power's gradient by differences of f, central or forward.
fn differenced(
    system: &mut MechanicalSystem,
    y: &[f64],
    central: bool,
) -> (DMatrix<f64>, Vec<f64>) {
    let n = y.len();
    let (f0, p0) = evaluated(system, y);
    let mut jacobian = DMatrix::zeros(n, n);
    let mut power = vec![0.0; n];
    for j in 0..n {
        let scale = y[j].abs().max(1e-3);
        let delta = match central {
            true => f64::EPSILON.cbrt() * scale,
            false => f64::EPSILON.sqrt() * scale,
        };
        let mut moved = y.to_vec();
        moved[j] += delta;
        let (plus, p_plus) = evaluated(system, &moved);
        let (minus, p_minus, width) = match central {
            true => {
                moved[j] = y[j] - delta;
                let (minus, p_minus) = evaluated(system, &moved);
                (minus, p_minus, 2.0 * delta)
            }
            false => (f0.clone(), p0, delta),
        };
        for i in 0..n {
            jacobian[(i, j)] = (plus[i] - minus[i]) / width;
        }
        power[j] = (p_plus - p_minus) / width;
    }
    (jacobian, power)
}

/// The largest difference in each column relative to that column's largest entry, or to a
/// millionth of the matrix's largest where the column is smaller (a spin about a symmetry axis
/// changes nothing: its column is zero but for rounding).
fn relative_difference(a: &DMatrix<f64>, b: &DMatrix<f64>) -> f64 {
    let floor = 1e-6 * b.amax();
    (0..a.ncols())
        .map(|j| {
            let scale = b.column(j).amax().max(floor);
            (a.column(j) - b.column(j)).amax() / scale
        })
        .fold(0.0, f64::max)
}

fn gradient_difference(a: &[f64], b: &[f64]) -> f64 {
    let scale = b.iter().fold(1e-9_f64, |m, x| m.max(x.abs()));
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
        / scale
}

/// The example's initial state, its velocities replaced by `rates` when given.
fn state(prepared: &Prepared, rates: Option<&[f64]>) -> Vec<f64> {
    let rates = rates.unwrap_or(&prepared.rates);
    let (q, v) = prepared
        .model
        .state_from_declared(&prepared.coordinates, rates)
        .expect("state");
    [q, v].concat()
}

fn system(prepared: &Prepared) -> MechanicalSystem<'_> {
    let reference = prepared.coordinates.clone();
    MechanicalSystem::new(&prepared.model, reference, Stabilisation::Projection)
}

/// Checks the inverse-dynamics Jacobian of an example at y against both differences. Both
/// Jacobians difference forward in the end, and their rounding, ε |f| / δ, is largest against
/// small columns: on the governor, where stiff forces of 1e5 N make f large, the spin rate's
/// column of forward differences of f is off by 2.7e-6 from the central ones (the others by
/// 6e-8 at most), and the inverse dynamics' by 4.5e-6.
fn check(name: &str, prepared: &Prepared, y: &[f64]) {
    let mut system = system(prepared);
    let (dydt, _) = evaluated(&mut system, y);
    let n = y.len();
    let mut jacobian = DMatrix::zeros(n, n);
    let mut power = vec![0.0; n];
    let given = system
        .jacobian(0.0, y, &dydt, &mut jacobian, &mut power)
        .expect("jacobian");
    assert!(
        given,
        "{name}: a tree of coordinate joints has its Jacobian"
    );
    for central in [true, false] {
        let (expected, expected_power) = differenced(&mut system, y, central);
        let (matrix, gradient) = (
            relative_difference(&jacobian, &expected),
            gradient_difference(&power, &expected_power),
        );
        assert!(
            matrix < 1e-5 && gradient < 1e-5,
            "{name} (central {central}): Jacobian off by {matrix:e}, power's gradient by {gradient:e}\n{jacobian}\n{expected}"
        );
    }
}

#[test]
fn the_inverse_dynamics_jacobian_agrees_with_differences_of_the_motion() {
    // The governor away from rest: the dampers' forces depend on the rates, the springs' on
    // the positions, with entries of 1e6 beside entries of 1 in one column.
    let governor = prepared("governor", &[]);
    let moving = [10.0, 0.7, -0.4, 0.3];
    check("governor", &governor, &state(&governor, Some(&moving)));
    for name in [
        "pendulum",
        "double_pendulum",
        "elastic_pendulum",
        "elliptic_pendulum",
    ] {
        let example = prepared(name, &[]);
        let mut y = state(&example, None);
        let half = y.len() / 2;
        for (k, rate) in y[half..].iter_mut().enumerate() {
            *rate += 0.3 + 0.2 * k as f64;
        }
        check(name, &example, &y);
    }
}

#[test]
fn loops_and_quaternions_leave_the_jacobian_to_differences() {
    for name in ["four_bar", "heavy_top", "satellite_springs"] {
        let example = prepared(name, &[]);
        let y = state(&example, None);
        let mut system = system(&example);
        let (dydt, _) = evaluated(&mut system, &y);
        let n = y.len();
        let (mut jacobian, mut power) = (DMatrix::zeros(n, n), vec![0.0; n]);
        let given = system.jacobian(0.0, &y, &dydt, &mut jacobian, &mut power);
        assert!(!given.expect("no error"), "{name}");
    }
}

#[test]
fn the_equations_are_autonomous_unless_an_effort_reads_the_time() {
    assert!(system(&prepared("governor", &[])).autonomous());
    let driven = prepared(
        "double_pendulum",
        &[(
            "initial",
            "apply torque value = [sin(time), 0, 0], body = earth end on lower ;\ninitial",
        )],
    );
    assert!(!system(&driven).autonomous());
}

/// A spatial three-link arm: dry and viscous friction in the shoulder and the elbow (the
/// elbow limited to [−0.5, 1.2]), the wrist mimicking the elbow.
const COUPLED_ARM: &str = "import joints ;\nimport gravity ;\n\
    let rod(l) = body mass = l, iframe = [0, 0, -l / 2] ++ 1, inertia = [l * l * l / 12, l * l * l / 12, 0.001] end ;\n\
    let upper = rod(1.0) ;\nlet lower = rod(0.8) ;\nlet hand = rod(0.5) ;\n\
    join earth and upper with friction_revolute([1, 0, 0], 2, 0.3) as shoulder ;\n\
    join [0, 0, -1] ++ 1 @ upper and lower with link(q) dof = q || [0, 1, 0], lower = -0.5, upper = 1.2, restitution = 0.5, friction = 0.5, damping = 0.2 end as elbow ;\n\
    join [0, 0, -0.8] ++ 1 @ lower and hand with mimic_revolute([1, 0, 0], elbow, 0.5, 0.1) as wrist ;\n\
    apply gravity_field ;\n\
    initial shoulder.q = 0.4, elbow.q = 0.3, wrist.q = 0.25, shoulder.q' = 1.2, elbow.q' = -0.7, wrist.q' = -0.35 ;\n";

/// The largest relative differences of the inverse-dynamics Jacobian at y and of its power's
/// gradient from central differences of f, with the system's phases and resting stops as
/// `setup` leaves them.
fn central_difference(
    prepared: &Prepared,
    y: &[f64],
    setup: impl Fn(&mut MechanicalSystem),
) -> (f64, f64) {
    let mut system = system(prepared);
    setup(&mut system);
    let (dydt, _) = evaluated(&mut system, y);
    let n = y.len();
    let (mut jacobian, mut power) = (DMatrix::zeros(n, n), vec![0.0; n]);
    let given = system.jacobian(0.0, y, &dydt, &mut jacobian, &mut power);
    assert!(given.expect("no error"), "the tree's Jacobian applies");
    let (expected, expected_power) = differenced(&mut system, y, true);
    (
        relative_difference(&jacobian, &expected),
        gradient_difference(&power, &expected_power),
    )
}

/// Mimic couplings, friction slipping and sticking, a coordinate resting on its stop: the
/// Jacobian keeps the coupling's reduced solve and holds the held coordinates' rows, and
/// agrees with central differences of f (truncation error O(δ²), δ = ε^⅓): measured 2.4e-8
/// slipping, 6.3e-8 sticking, 2.3e-7 resting on the stop (the forward differences' own
/// truncation, δ/2 |r''| with δ = √ε |yⱼ|), 5.8e-9 at most on the power's gradient. The held
/// coordinates' rates are not zero in the first checks (f holds their accelerations at zero
/// whatever their rates), so that every increment is the usual √ε |yⱼ|: at a rate of exactly
/// zero the increment is √(ε 1e-5) = 4.7e-11 (Hairer's rule, the implicit method's own
/// differences of f take it too), whose rounding ε |r| / δ leaves 1.6e-6 in the sticking
/// joint's rate column.
#[test]
fn the_jacobian_keeps_the_couplings_and_the_held_rows() {
    use lsdc::dynamics::friction::Phase;
    let arm = super::common::programs::prepared_text(COUPLED_ARM);
    let moving = state(&arm, None);
    let half = moving.len() / 2;
    let elbow = arm.model.stops[0].position;
    let phases = |shoulder: Phase, resting: bool| {
        move |system: &mut MechanicalSystem| {
            system.state.phases = vec![shoulder, Phase::Slipping(-1.0)];
            system.state.resting[0] = resting;
        }
    };
    let mut on_bound = moving.clone();
    on_bound[elbow] = -0.5;
    let mut at_rest = moving.clone();
    at_rest[half] = 0.0;
    let cases = [
        (
            "slipping",
            &moving,
            phases(Phase::Slipping(1.0), false),
            1e-7,
        ),
        ("sticking", &moving, phases(Phase::Sticking, false), 1e-7),
        (
            "resting",
            &on_bound,
            phases(Phase::Slipping(1.0), true),
            5e-7,
        ),
        (
            "sticking at rest",
            &at_rest,
            phases(Phase::Sticking, false),
            3e-6,
        ),
    ];
    for (name, y, setup, tolerance) in cases {
        let (matrix, gradient) = central_difference(&arm, y, setup);
        assert!(
            matrix < tolerance && gradient < tolerance,
            "{name}: Jacobian off by {matrix:e}, power's gradient by {gradient:e}"
        );
    }
    // Both held, the wrist with the elbow: no acceleration moves with the state.
    let mut system = system(&arm);
    phases(Phase::Sticking, true)(&mut system);
    let (dydt, _) = evaluated(&mut system, &on_bound);
    let n = on_bound.len();
    let (mut jacobian, mut power) = (DMatrix::zeros(n, n), vec![0.0; n]);
    assert!(system
        .jacobian(0.0, &on_bound, &dydt, &mut jacobian, &mut power)
        .expect("no error"));
    let held = jacobian.rows(half, half).amax();
    assert!(held < 1e-8, "both held: {held:e}");
    let gears = prepared("meshed_gears", &[]);
    let mut turning = state(&gears, None);
    let half = turning.len() / 2;
    turning[half] = 2.0;
    turning[half + 1] = -6.0;
    let (meshed, _) = central_difference(&gears, &turning, |_| {});
    assert!(meshed < 1e-7, "meshed gears: {meshed:e}");
}

/// A slider of 1000 kg on a spring, resting on its stop, carries a rotor of 1e-10 kg m² held by
/// its friction: the held rows' entries (1/m = 1e-3 and 1/J = 1e10) are fifteen orders apart,
/// and both are held in the Jacobian as in f (scaled before the dependent rows are found):
/// the slider's acceleration does not move with its position, where the spring alone would
/// give −k/m. Against central differences of f.
#[test]
fn the_jacobian_holds_rows_of_very_different_sizes() {
    use lsdc::dynamics::friction::Phase;
    let text = "import joints ;\n\
        let slider = body mass = 1000, iframe = 0, inertia = [1, 1, 1] end ;\n\
        let rotor = body mass = 1e-6, iframe = 0, inertia = [1e-10, 1e-10, 1e-10] end ;\n\
        join earth and slider with limited_prismatic([0, 0, 1], 0, 1, 0) as lift ;\n\
        join slider and rotor with friction_revolute([0, 0, 1], 1, 0) as spin ;\n\
        apply force value = [0, 0, -9.81 * slider.mass - 1e4 * (lift.q - 0.1)], body = earth end on slider.frame ;\n";
    let prepared = super::common::programs::prepared_text(text);
    let y = state(&prepared, None);
    let held = |system: &mut MechanicalSystem| {
        system.state.phases = vec![Phase::Sticking];
        system.state.resting[0] = true;
    };
    let (matrix, gradient) = central_difference(&prepared, &y, held);
    assert!(
        matrix < 1e-7 && gradient < 1e-7,
        "Jacobian off by {matrix:e}, power's gradient by {gradient:e}"
    );
}
