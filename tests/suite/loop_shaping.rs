//! The Delta seed's loop shaping (notes on the Delta seed §5 R15-R19, T14) reproduced from the
//! output of `lsdc linearize --format json` on the decoupled axes
//! (examples/control/delta_decoupled_axes.lsd): the transfer function of an axis,
//! G(s) = C (sI − A)⁻¹ B + D from the JSON's matrices, is 1/(s + 1)²; with K = 5000 its
//! crossover is 70.7 rad/s and its phase margin 1.62°, and the phase-lead that brings the margin
//! to 55° is the seed's C(s) = (0.01414 s + 0.3309)/(0.004681 s + 1).

use nalgebra::{Complex, DMatrix};

use crate::common::lsdc;

/// A matrix of the JSON, an array of rows.
fn matrix(json: &serde_json::Value, key: &str) -> DMatrix<f64> {
    let rows: Vec<Vec<f64>> = serde_json::from_value(json[key].clone()).expect("rows");
    let columns = rows.first().map_or(0, Vec::len);
    DMatrix::from_fn(rows.len(), columns, |r, c| rows[r][c])
}

/// The linear model's transfer function from input `input` to output `output`.
struct Transfer {
    a: DMatrix<f64>,
    b: DMatrix<f64>,
    c: DMatrix<f64>,
    d: DMatrix<f64>,
    input: usize,
    output: usize,
}

impl Transfer {
    /// G(s) = C (sI − A)⁻¹ B + D at s = jω.
    fn at(&self, omega: f64) -> Complex<f64> {
        let n = self.a.nrows();
        let complex = |m: &DMatrix<f64>| m.map(|x| Complex::new(x, 0.0));
        let shifted =
            DMatrix::from_diagonal_element(n, n, Complex::new(0.0, omega)) - complex(&self.a);
        let column = complex(&self.b.columns(self.input, 1).into_owned());
        let x = shifted
            .lu()
            .solve(&column)
            .expect("jω is no eigenvalue of A");
        let row = complex(&self.c.rows(self.output, 1).into_owned());
        (row * x)[(0, 0)] + self.d[(self.output, self.input)]
    }
}

/// The frequency (rad/s) where |f(jω)| falls through 1, by bisection on [low, high].
fn crossover(f: impl Fn(f64) -> Complex<f64>, mut low: f64, mut high: f64) -> f64 {
    assert!(f(low).norm() > 1.0 && f(high).norm() < 1.0);
    while high - low > 1e-12 * high {
        let middle = 0.5 * (low + high);
        match f(middle).norm() > 1.0 {
            true => low = middle,
            false => high = middle,
        }
    }
    0.5 * (low + high)
}

/// The phase margin (degrees) of an open loop whose gain crosses 1 at ω_c.
fn phase_margin(open_loop: Complex<f64>) -> f64 {
    180.0 + open_loop.arg().to_degrees()
}

#[test]
fn the_seeds_loop_shaping_numbers_follow_from_the_linear_model() {
    let (code, stdout, stderr) = lsdc(&[
        "linearize",
        "examples/control/delta_decoupled_axes.lsd",
        "--coordinate",
        "leg[1]:A.q",
        "--coordinate",
        "leg[2]:A.q",
        "--coordinate",
        "leg[3]:A.q",
        "--input",
        "leg[1]:u",
        "--input",
        "leg[2]:u",
        "--input",
        "leg[3]:u",
        "--format",
        "json",
    ]);
    assert_eq!(code, 0, "{stderr}");
    let json: serde_json::Value = serde_json::from_str(&stdout).expect("JSON");
    let names = |key: &str| -> Vec<String> { serde_json::from_value(json[key].clone()).unwrap() };
    let axis = Transfer {
        a: matrix(&json, "A"),
        b: matrix(&json, "B"),
        c: matrix(&json, "C"),
        d: matrix(&json, "D"),
        input: names("inputs")
            .iter()
            .position(|n| n == "leg[1]:u")
            .unwrap(),
        output: names("outputs").iter().position(|n| n == "y1").unwrap(),
    };
    // G(s) = 1/(s + 1)² (R15: |G(0)| = 1), at a few frequencies.
    for omega in [0.0, 0.5, 1.0, 10.0, 70.0] {
        let s = Complex::new(0.0, omega);
        let expected = Complex::new(1.0, 0.0) / ((s + 1.0) * (s + 1.0));
        let found = axis.at(omega);
        assert!(
            (found - expected).norm() < 1e-9 * expected.norm(),
            "ω = {omega}: {found} against {expected}"
        );
    }
    // R16: K = 5000 crosses over at √(K − 1) = 70.70 rad/s.
    let gain = 5000.0;
    let open_loop = |omega: f64| axis.at(omega) * gain;
    let omega_c = crossover(open_loop, 1.0, 1000.0);
    assert!(
        (omega_c - (gain - 1.0_f64).sqrt()).abs() < 1e-8 * omega_c,
        "{omega_c}"
    );
    assert!(
        (omega_c - 70.7).abs() < 0.005,
        "the seed prints 70.7: {omega_c}"
    );
    // R18: the margin 180° − 2 atan(ω_c) = 1.62°.
    let margin = phase_margin(open_loop(omega_c));
    assert!(
        (margin - (180.0 - 2.0 * omega_c.atan().to_degrees())).abs() < 1e-8,
        "{margin}"
    );
    assert!(
        (margin - 1.62).abs() < 0.005,
        "the seed prints 1.62°: {margin}"
    );
    // R19: the lead for 55°, its largest phase φ_max = 55° − 1.62° at ω_c:
    // α = tan(45° − φ_max/2)/ω_c, β = 1/sin φ_max, r = 1/√(β² − 1),
    // C(s) = (r (β + 1) α s + r (β − 1))/(α s + 1).
    let lift = (55.0 - margin).to_radians();
    let alpha = (std::f64::consts::FRAC_PI_4 - lift / 2.0).tan() / omega_c;
    let beta = 1.0 / lift.sin();
    let r = 1.0 / (beta * beta - 1.0).sqrt();
    let (numerator_s, numerator_1) = (r * (beta + 1.0) * alpha, r * (beta - 1.0));
    // The seed's four printed digits, which it computed from ω_c and φ_max rounded to 70.7
    // and 53.38° (its α is 0.0046805 from them, printed 0.004681): within a unit of the last.
    let printed = [
        (numerator_s, 0.01414, 1e-5),
        (numerator_1, 0.3309, 1e-4),
        (alpha, 0.004681, 1e-6),
    ];
    for (found, digits, unit) in printed {
        assert!((found - digits).abs() <= unit, "{found} against {digits}");
    }
    let lead = |omega: f64| {
        let s = Complex::new(0.0, omega);
        (s * numerator_s + numerator_1) / (s * alpha + 1.0)
    };
    // The lead leaves the crossover where it was (|C(jω_c)| = 1) and lifts the margin to 55°.
    let shaped = |omega: f64| lead(omega) * open_loop(omega);
    let shaped_crossover = crossover(shaped, 1.0, 1000.0);
    assert!(
        (shaped_crossover - omega_c).abs() < 1e-6 * omega_c,
        "{shaped_crossover}"
    );
    let shaped_margin = phase_margin(shaped(shaped_crossover));
    assert!((shaped_margin - 55.0).abs() < 1e-6, "{shaped_margin}");
}
