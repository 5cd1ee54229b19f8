//! The loops' range-space method (`dynamics::loops::range_space`) against their null-space
//! method (`dynamics::loops::solve`), two independent solves of the same constrained
//! equations: the accelerations along a motion and whole runs agree to round-off on the
//! necklace of 10 and 30 rods (where the rule takes the range-space method), the four-bar, the
//! slider-crank and the row of ten four-bars (where it keeps the null-space method), in the
//! spatial and the planar forms. The rule itself: which mechanisms take which method.

use crate::long_chains::chains::necklace_program;
use lsdc::dynamics::loops::Method;
use lsdc::prepare::{Integrator, Prepared};
use lsdc::simulate::run::run;
use lsdc::simulate::system::MechanicalSystem;

use crate::common::programs::{prepared, prepared_text};

/// Relative agreement asked of the two methods: round-off, 1e-12 of the largest rate, plus
/// what the conditioning κ(M) of the tree's mass matrix makes of it (ε κ(M): a chain of 30
/// rods has κ(M) = 2e5, and the two methods' accelerations differ there by 1.2e-11 of the
/// largest, 0.3e-12 at 10 rods, κ(M) = 2.4e3), and of the runs' outputs, 1e-11 of the
/// largest coordinate.
const AGREEMENT: f64 = 1e-12;
const RUNS_AGREEMENT: f64 = 1e-11;

/// A system of `prepared` solving its loops by `method`, started at its initial state, in the
/// planar form when `planar`.
fn started(prepared: &Prepared, method: Method, planar: bool) -> (MechanicalSystem<'_>, Vec<f64>) {
    let model = &prepared.model;
    let (mut y, v) =
        (model.state_from_declared(&prepared.coordinates, &prepared.rates)).expect("initial state");
    y.extend_from_slice(&v);
    let reference = prepared.coordinates.clone();
    let mut system = MechanicalSystem::new(model, reference, prepared.settings.stabilisation);
    if planar {
        system.use_planar(prepared.planar.as_deref().ok());
    }
    system.force_loop_method(Some(method));
    system.start_loops(&mut y).expect("starts");
    (system, y)
}

/// The largest difference of the two methods' right-hand sides, relative to the largest rate,
/// over states along a motion (forward Euler steps of the null-space system, kept on the
/// loops by its projection).
pub(crate) fn largest_difference(
    prepared: &Prepared,
    planar: bool,
    steps: usize,
    step: f64,
) -> f64 {
    let (mut null, mut y) = started(prepared, Method::NullSpace, planar);
    let (mut range, _) = started(prepared, Method::RangeSpace, planar);
    let (mut a, mut b) = (vec![0.0; y.len()], vec![0.0; y.len()]);
    let mut largest = 0.0f64;
    for k in 0..steps {
        let t = step * k as f64;
        null.derivative(t, &y, &mut a).expect("null space");
        range.derivative(t, &y, &mut b).expect("range space");
        assert_eq!(null.loop_method(), Method::NullSpace);
        assert_eq!(range.loop_method(), Method::RangeSpace);
        let scale = a.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let difference = (a.iter().zip(&b)).fold(0.0f64, |m, (x, z)| m.max((x - z).abs()));
        largest = largest.max(difference / scale);
        y.iter_mut().zip(&a).for_each(|(y, rate)| *y += step * rate);
        null.keep_closed(t, &mut y).expect("closes");
    }
    largest
}

/// The mechanisms compared, each prepared anew when asked.
type Case = (String, Box<dyn Fn() -> Prepared>);

fn cases() -> Vec<Case> {
    let mut cases: Vec<Case> = Vec::new();
    for n in [10, 30] {
        let text = necklace_program(n);
        cases.push((
            format!("necklace of {n}"),
            Box::new(move || prepared_text(&text)),
        ));
    }
    for name in ["four_bar", "slider_crank", "hard/four_bar_row_10"] {
        cases.push((name.to_string(), Box::new(move || prepared(name, &[]))));
    }
    cases
}

#[test]
fn range_space_and_null_space_accelerations_agree_along_motions() {
    for (name, make) in cases() {
        let prepared = make();
        for planar in [false, true] {
            let difference = largest_difference(&prepared, planar, 20, 2e-3);
            let bound = AGREEMENT + f64::EPSILON * mass_conditioning(&prepared);
            assert!(
                difference <= bound,
                "{name} (planar: {planar}): the two methods' accelerations differ by {difference:e}"
            );
        }
    }
}

#[test]
fn range_space_and_null_space_runs_agree() {
    // Whole runs at RK4's fixed steps: the same steps, the same outputs to round-off.
    for (name, make) in cases() {
        let with = |method| {
            let mut prepared = make();
            prepared.loop_method = Some(method);
            let settings = &mut prepared.settings;
            (settings.integrator, settings.step) = (Integrator::Rk4, Some(2e-3));
            (settings.duration, settings.output) = (0.1, 0.01);
            run(&prepared, &mut |_| {})
        };
        let (null, range) = (with(Method::NullSpace), with(Method::RangeSpace));
        assert!(
            null.report.failure.is_none() && range.report.failure.is_none(),
            "{name}"
        );
        assert_eq!(null.report.steps, range.report.steps, "{name}");
        let scale =
            (null.samples.iter().flat_map(|s| &s.coordinates)).fold(0.0f64, |m, x| m.max(x.abs()));
        let difference = (null.samples.iter().zip(&range.samples))
            .flat_map(|(a, b)| a.coordinates.iter().zip(&b.coordinates))
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        assert!(
            difference <= RUNS_AGREEMENT * scale,
            "{name}: runs differ by {difference:e} (scale {scale})"
        );
        let energy = |s: &lsdc::simulate::run::Simulation| s.report.energy_drift;
        assert_eq!(energy(&null).is_some(), energy(&range).is_some(), "{name}");
    }
}

#[test]
fn the_range_space_method_is_taken_where_the_motions_outnumber_the_rows() {
    // The necklace of N rods: 3 kept rows, N − 2 allowed motions, the range-space method from
    // N − 2 = 6 on. A row of four-bars: 3 rows per loop, one motion.
    let taken = |prepared: &Prepared| {
        let model = &prepared.model;
        let (mut y, v) = (model.state_from_declared(&prepared.coordinates, &prepared.rates))
            .expect("initial state");
        y.extend_from_slice(&v);
        let reference = prepared.coordinates.clone();
        let mut system = MechanicalSystem::new(model, reference, prepared.settings.stabilisation);
        system.start_loops(&mut y).expect("starts");
        let mut rates = vec![0.0; y.len()];
        system.derivative(0.0, &y, &mut rates).expect("evaluates");
        system.loop_method()
    };
    for n in [8, 10] {
        let necklace = prepared_text(&necklace_program(n));
        assert_eq!(taken(&necklace), Method::RangeSpace, "necklace of {n}");
    }
    // Three to seven rods, one to five motions on three rows: the null-space method, as on the
    // four-bar and the row.
    for n in [3, 5, 7] {
        let necklace = prepared_text(&necklace_program(n));
        assert_eq!(taken(&necklace), Method::NullSpace, "necklace of {n}");
    }
    for name in ["four_bar", "slider_crank", "hard/four_bar_row_10"] {
        assert_eq!(taken(&prepared(name, &[])), Method::NullSpace, "{name}");
    }
}

/// The condition number of the tree's mass matrix at the initial configuration.
pub(crate) fn mass_conditioning(prepared: &Prepared) -> f64 {
    let model = &prepared.model;
    let (q, _) =
        (model.state_from_declared(&prepared.coordinates, &prepared.rates)).expect("state");
    let mut data = lsdc::dynamics::algorithms::Data::new(model);
    let mass = lsdc::dynamics::algorithms::crba(model, &mut data, &q[..model.nq]).expect("mass");
    let values = mass.symmetric_eigenvalues();
    values.max() / values.min()
}
