//! The position corrector (`corrector`) on problems written here in a few lines: a planar
//! four-bar closed against its configuration in closed form (Gauss–Newton and the
//! Levenberg–Marquardt fallback, a coordinate held), the same rows written twice and in other
//! units (rank-deficient and badly scaled), and targets that no configuration reaches or that
//! give no finite step, which must end with their reason, not hang.

use lsdc::corrector::{
    correct, minimum_norm_step, Acceptance, Correction, Damping, Progress, Settings, Stop,
};
use nalgebra::{DMatrix, DVector};

/// Rows r(q) with their Jacobian ∂r/∂q.
type Rows = fn(&[f64]) -> (DVector<f64>, DMatrix<f64>);

/// Closes `rows` over the coordinates not `held`: minimum-norm steps without damping, the
/// damped normal equations with it.
struct Closing {
    rows: Rows,
    held: Vec<bool>,
    tolerance: f64,
    q: Vec<f64>,
    residual: DVector<f64>,
    jacobian: DMatrix<f64>,
    trial: Vec<f64>,
    tried: Option<(DVector<f64>, DMatrix<f64>)>,
}

impl Closing {
    fn new(rows: Rows, q: &[f64], held: &[bool], tolerance: f64) -> Closing {
        let (residual, jacobian) = rows(q);
        Closing {
            rows,
            held: held.to_vec(),
            tolerance,
            q: q.to_vec(),
            residual,
            jacobian,
            trial: Vec::new(),
            tried: None,
        }
    }

    fn free(&self) -> Vec<usize> {
        (0..self.q.len()).filter(|&i| !self.held[i]).collect()
    }
}

impl Correction for Closing {
    type Error = ();

    fn settled(&self) -> bool {
        self.residual.amax() <= self.tolerance
    }

    fn merit(&self) -> f64 {
        self.residual.norm()
    }

    fn step(&mut self, damping: f64) -> Result<Option<f64>, ()> {
        let free = self.free();
        let j = self.jacobian.select_columns(&free);
        let step = if damping == 0.0 {
            minimum_norm_step(&j, &self.residual, 1e-12)
        } else {
            let normal = j.transpose() * &j;
            let scale = normal.diagonal().max().max(1e-12);
            let damped = normal + DMatrix::identity(free.len(), free.len()) * (damping * scale);
            let gradient = j.transpose() * &self.residual;
            damped.cholesky().map(|c| -c.solve(&gradient))
        };
        let Some(step) = step else { return Ok(None) };
        self.trial = self.q.clone();
        for (k, &i) in free.iter().enumerate() {
            self.trial[i] += step[k];
        }
        Ok(Some(step.amax()))
    }

    fn try_step(&mut self) -> Result<f64, ()> {
        let (residual, jacobian) = (self.rows)(&self.trial);
        let merit = residual.norm();
        self.tried = Some((residual, jacobian));
        Ok(merit)
    }

    fn accept(&mut self) {
        let (residual, jacobian) = self.tried.take().expect("tried");
        (self.q, self.residual, self.jacobian) = (self.trial.clone(), residual, jacobian);
    }
}

const GAUSS_NEWTON: Settings = Settings {
    iterations: 20,
    damping: Damping::None,
    acceptance: Acceptance::Descent,
    progress: Progress::Any,
};

const LEVENBERG_MARQUARDT: Settings = Settings {
    iterations: 200,
    damping: Damping::Levenberg {
        initial: 1e-6,
        floor: 1e-15,
        tries: 30,
        smallest_step: 1e-16,
    },
    acceptance: Acceptance::Descent,
    progress: Progress::Any,
};

/// The four-bar's links: crank 1, coupler 3.5, rocker 3, ground 4 (the example's).
const CRANK: f64 = 1.0;
const COUPLER: f64 = 3.5;
const ROCKER: f64 = 3.0;
const GROUND: f64 = 4.0;

/// The loop of a four-bar over (crank, coupler, rocker) absolute angles: the crank's tip plus
/// the coupler reaches the rocker's tip, 2 rows.
fn four_bar(q: &[f64]) -> (DVector<f64>, DMatrix<f64>) {
    let (a, b, c) = (q[0], q[1], q[2]);
    let residual = DVector::from_vec(vec![
        CRANK * a.cos() + COUPLER * b.cos() - GROUND - ROCKER * c.cos(),
        CRANK * a.sin() + COUPLER * b.sin() - ROCKER * c.sin(),
    ]);
    let jacobian = DMatrix::from_row_slice(
        2,
        3,
        &[
            -CRANK * a.sin(),
            -COUPLER * b.sin(),
            ROCKER * c.sin(),
            CRANK * a.cos(),
            COUPLER * b.cos(),
            -ROCKER * c.cos(),
        ],
    );
    (residual, jacobian)
}

/// The same rows written twice, the second copy in millimetres: rank 2 of 4 rows, rows 1000
/// apart in size.
fn four_bar_twice(q: &[f64]) -> (DVector<f64>, DMatrix<f64>) {
    let (r, j) = four_bar(q);
    let residual = DVector::from_iterator(4, r.iter().copied().chain(r.iter().map(|x| 1e3 * x)));
    let mut jacobian = DMatrix::zeros(4, 3);
    jacobian.rows_mut(0, 2).copy_from(&j);
    jacobian.rows_mut(2, 2).copy_from(&(j * 1e3));
    (residual, jacobian)
}

/// The coupler's and the rocker's angles in closed form at crank angle `a`, the coupler above
/// the line from the crank's tip B to the rocker's pivot D: the rocker's tip C is where the
/// circles about B (coupler) and D (rocker) meet.
fn closed_form(a: f64) -> (f64, f64) {
    let (bx, by) = (CRANK * a.cos(), CRANK * a.sin());
    let (dx, dy) = (GROUND - bx, -by);
    let d = dx.hypot(dy);
    let along = (COUPLER.powi(2) - ROCKER.powi(2) + d * d) / (2.0 * d);
    let height = (COUPLER.powi(2) - along * along).sqrt();
    let (ex, ey) = (dx / d, dy / d);
    let (cx, cy) = (bx + along * ex - height * ey, by + along * ey + height * ex);
    let coupler = (cy - by).atan2(cx - bx);
    let rocker = cy.atan2(cx - GROUND);
    (coupler, rocker)
}

#[test]
fn gauss_newton_closes_the_four_bar_onto_its_closed_form_holding_the_crank() {
    let crank = 1.2;
    let (coupler, rocker) = closed_form(crank);
    let start = [crank, coupler + 0.1, rocker - 0.15];
    let mut closing = Closing::new(four_bar, &start, &[true, false, false], 1e-13);
    let outcome = correct(&mut closing, &GAUSS_NEWTON).unwrap();
    assert_eq!(outcome.stop, Stop::Settled);
    // Quadratic convergence: a handful of steps from 0.15 rad.
    assert!(outcome.accepted <= 6, "{outcome:?}");
    assert_eq!(closing.q[0], crank, "the held crank moved");
    assert!((closing.q[1] - coupler).abs() < 1e-12, "{:?}", closing.q);
    assert!((closing.q[2] - rocker).abs() < 1e-12, "{:?}", closing.q);
}

#[test]
fn levenberg_marquardt_closes_the_four_bar_from_far() {
    let crank = 0.7;
    let (coupler, rocker) = closed_form(crank);
    let start = [crank, coupler + 0.6, rocker + 0.5];
    let mut closing = Closing::new(four_bar, &start, &[true, false, false], 1e-13);
    let outcome = correct(&mut closing, &LEVENBERG_MARQUARDT).unwrap();
    assert_eq!(outcome.stop, Stop::Settled);
    assert!((closing.q[1] - coupler).abs() < 1e-12, "{:?}", closing.q);
    assert!((closing.q[2] - rocker).abs() < 1e-12, "{:?}", closing.q);
}

#[test]
fn redundant_rows_in_other_units_take_the_same_steps() {
    // Every coordinate free: the rows leave one motion, along which the minimum-norm steps
    // do not move the state; the duplicated rows (rank 2 of 4, a thousandfold apart) must
    // give the same steps as the two rows alone.
    let start = [1.0, 0.75, 1.6];
    let free = [false; 3];
    let mut single = Closing::new(four_bar, &start, &free, 1e-13);
    // The same tolerance, 1e-13 m, in the units of the larger copy.
    let mut twice = Closing::new(four_bar_twice, &start, &free, 1e-10);
    let one = correct(&mut single, &GAUSS_NEWTON).unwrap();
    let other = correct(&mut twice, &GAUSS_NEWTON).unwrap();
    assert_eq!(one.stop, Stop::Settled);
    assert_eq!(other.stop, Stop::Settled);
    assert!(four_bar(&twice.q).0.amax() < 1e-13);
    for (a, b) in single.q.iter().zip(&twice.q) {
        assert!(
            (a - b).abs() < 1e-12,
            "{:?} against {:?}",
            single.q,
            twice.q
        );
    }
    // The minimum-norm step of a consistent system is the pseudo-inverse's, scaled or not.
    let (r, j) = four_bar_twice(&start);
    let step = minimum_norm_step(&j, &r, 1e-12).unwrap();
    let (r2, j2) = four_bar(&start);
    let expected = -(j2.pseudo_inverse(1e-12).unwrap() * r2);
    assert!((step - expected).amax() < 1e-13);
}

/// A two-link arm (links 1 and 1) whose tip must reach (5, 0): at most 2 away from its base.
fn unreachable(q: &[f64]) -> (DVector<f64>, DMatrix<f64>) {
    let (a, b) = (q[0], q[0] + q[1]);
    let residual = DVector::from_vec(vec![a.cos() + b.cos() - 5.0, a.sin() + b.sin()]);
    let jacobian = DMatrix::from_row_slice(
        2,
        2,
        &[-a.sin() - b.sin(), -b.sin(), a.cos() + b.cos(), b.cos()],
    );
    (residual, jacobian)
}

#[test]
fn an_unreachable_target_ends_with_its_reason_and_the_nearest_configuration() {
    let start = [0.3, 0.4];
    let distance = unreachable(&start).0.norm();
    // Gauss–Newton: the full step overshoots (the arm cannot stretch further), and a step
    // that does not reduce the distance ends the correction where it started.
    let mut closing = Closing::new(unreachable, &start, &[false; 2], 1e-12);
    let outcome = correct(&mut closing, &GAUSS_NEWTON).unwrap();
    assert_eq!(outcome.stop, Stop::NoDescent, "{outcome:?}");
    assert_eq!((outcome.iterations, outcome.accepted), (1, 0));
    assert_eq!(closing.residual.norm(), distance);
    // Levenberg–Marquardt: the damped steps stretch the arm towards the target, 3 left.
    let mut closing = Closing::new(unreachable, &start, &[false; 2], 1e-12);
    let outcome = correct(&mut closing, &LEVENBERG_MARQUARDT).unwrap();
    assert!(
        matches!(
            outcome.stop,
            Stop::NoDescent | Stop::Stalled | Stop::Exhausted
        ),
        "{outcome:?}"
    );
    assert!(outcome.iterations <= LEVENBERG_MARQUARDT.iterations);
    assert!(
        (closing.residual.norm() - 3.0).abs() < 1e-9,
        "{:?}",
        closing.q
    );
    assert!(closing.q.iter().all(|x| x.abs() < 1e-6), "{:?}", closing.q);
}

/// Rows that are not finite anywhere.
fn not_finite(q: &[f64]) -> (DVector<f64>, DMatrix<f64>) {
    (
        DVector::from_element(1, 1.0 + q[0]),
        DMatrix::from_element(1, 1, f64::NAN),
    )
}

#[test]
fn rows_without_a_finite_step_end_at_once() {
    for settings in [GAUSS_NEWTON, LEVENBERG_MARQUARDT] {
        let mut closing = Closing::new(not_finite, &[0.0], &[false], 1e-12);
        let outcome = correct(&mut closing, &settings).unwrap();
        assert_eq!(outcome.stop, Stop::NoStep, "{outcome:?}");
        assert_eq!((outcome.iterations, outcome.accepted), (1, 0));
        assert_eq!(closing.q, [0.0]);
    }
}

#[test]
fn the_iterations_are_bounded_and_a_slow_step_ends_the_correction() {
    let crank = 1.2;
    let (coupler, rocker) = closed_form(crank);
    let start = [crank, coupler + 0.1, rocker - 0.15];
    let held = [true, false, false];
    let one = Settings {
        iterations: 1,
        ..GAUSS_NEWTON
    };
    let mut closing = Closing::new(four_bar, &start, &held, 1e-13);
    let outcome = correct(&mut closing, &one).unwrap();
    assert_eq!(outcome.stop, Stop::Exhausted);
    assert_eq!((outcome.iterations, outcome.accepted), (1, 1));
    // No Gauss–Newton step from 0.15 rad divides the residual a thousandfold.
    let demanding = Settings {
        progress: Progress::Ratio(1e-3),
        ..GAUSS_NEWTON
    };
    let mut closing = Closing::new(four_bar, &start, &held, 1e-13);
    let outcome = correct(&mut closing, &demanding).unwrap();
    assert_eq!(outcome.stop, Stop::Slow);
    assert_eq!(outcome.accepted, 1);
}
