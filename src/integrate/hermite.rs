//! Cubic Hermite interpolation over one step from the states and derivatives at its ends.

/// The data of one step that the cubic through both ends with matching slopes needs.
#[derive(Clone, Debug, Default)]
pub struct HermiteSegment {
    t_start: f64,
    step: f64,
    y_start: Vec<f64>,
    f_start: Vec<f64>,
    y_end: Vec<f64>,
    f_end: Vec<f64>,
}

impl HermiteSegment {
    pub fn new(dimension: usize) -> Self {
        let zeros = vec![0.0; dimension];
        HermiteSegment {
            t_start: 0.0,
            step: 0.0,
            y_start: zeros.clone(),
            f_start: zeros.clone(),
            y_end: zeros.clone(),
            f_end: zeros,
        }
    }

    /// Remembers the step from (t_start, y_start) over `step` to y_end, with dy/dt at both ends.
    pub fn set(&mut self, t_start: f64, step: f64, ends: [&[f64]; 4]) {
        let [y_start, f_start, y_end, f_end] = ends;
        self.t_start = t_start;
        self.step = step;
        self.y_start.copy_from_slice(y_start);
        self.f_start.copy_from_slice(f_start);
        self.y_end.copy_from_slice(y_end);
        self.f_end.copy_from_slice(f_end);
    }

    /// The interpolant at `t`, written into `out`.
    pub fn evaluate(&self, t: f64, out: &mut [f64]) {
        let h = self.step;
        let theta = (t - self.t_start) / h;
        // The Hermite cubic written as the chord plus a correction vanishing at both ends, which
        // keeps the end values exact.
        let bump = theta * (theta - 1.0);
        for (i, value) in out.iter_mut().enumerate() {
            let (y0, y1) = (self.y_start[i], self.y_end[i]);
            let chord = (1.0 - theta) * y0 + theta * y1;
            let slopes = (1.0 - 2.0 * theta) * (y1 - y0)
                + (theta - 1.0) * h * self.f_start[i]
                + theta * h * self.f_end[i];
            *value = chord + bump * slopes;
        }
    }
}

/// The first four coefficients of a Runge–Kutta method's continuous extension in Hairer's form
/// (its cubic Hermite part: y, Δ, h f₀ − Δ and Δ − h f₁ − (h f₀ − Δ), with Δ = y_new − y), for
/// the step of size `h` from `y` to `y_new` with slopes `first` and `last` at its ends (Hairer,
/// Nørsett and Wanner, II.6). Dormand–Prince 5(4) and DOP853 add their higher coefficients.
pub(super) fn hermite_part_into(
    h: f64,
    (y, y_new): (&[f64], &[f64]),
    (first, last): (&[f64], &[f64]),
    [r0, r1, r2, r3]: [&mut [f64]; 4],
) {
    for i in 0..y.len() {
        let change = y_new[i] - y[i];
        let start_bulge = h * first[i] - change;
        r0[i] = y[i];
        r1[i] = change;
        r2[i] = start_bulge;
        r3[i] = change - h * last[i] - start_bulge;
    }
}
