//! The Jacobian of a tree's equations of motion that the implicit integrator takes from inverse
//! dynamics (`MechanicalSystem::jacobian`), against differences of the equations of motion
//! themselves: central differences (truncation error O(δ²)) and forward ones, the implicit
//! method's own way before.

use std::cell::RefCell;
use std::rc::Rc;

use crate::common::programs::prepared;
use lsdc::dynamics::loops::Stabilisation;
use lsdc::simulate::prepare::Prepared;
use lsdc::simulate::system::MechanicalSystem;
use nalgebra::DMatrix;

/// f at y, and the power of the non-conservative efforts there.
fn evaluated(system: &mut MechanicalSystem, y: &[f64]) -> (Vec<f64>, f64) {
    let mut dydt = vec![0.0; y.len()];
    system.derivative(0.0, y, &mut dydt).expect("f");
    (dydt, system.power)
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
    let reference = Rc::new(RefCell::new(prepared.coordinates.clone()));
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
