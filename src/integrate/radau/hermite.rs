//! Radau IIA's dense output on the components whose slope is not stiff: the quintic Hermite
//! polynomial through the values and slopes at the last three step ends.
//!
//! The collocation polynomial of a step (degree 3) is only of order 3 inside the step, where
//! the step's ends are of order 5: on the flyball governor at tolerance 1e-9 its positions at
//! outputs between the ends were 5 times less accurate than at the ends (7.7e-11 against
//! 1.5e-11). The quintic through (t, y, f) at the ends of the last two steps is of order 5
//! inside them, as long as the slopes f are as accurate as the values: where f_i amplifies
//! the state's errors (a stiff component, whose row of the Jacobian is large against 1/h), its
//! slope is not, and the collocation polynomial, which needs no slope from outside the step,
//! is kept. On the governor the quintic serves the coordinates (slopes the rates) and not the
//! rates (slopes the stiff springs' accelerations), where it made the rates' error at the
//! outputs 2 to 15 times larger.

use nalgebra::DMatrix;

/// The quintic's slopes are trusted on a component i where h Σ_j |J_ij| is at most this: an
/// error ε of the state changes the slope's contribution h f_i by at most ε.
const SMOOTH_SLOPE: f64 = 1.0;

/// One step end: time, state, slope.
struct End {
    t: f64,
    y: Vec<f64>,
    f: Vec<f64>,
}

pub(super) struct Hermite {
    /// The end of the step before the last, when the last step started from it.
    earlier: Option<End>,
    /// The nodes t₀, t₀, t₁, t₁, t₂, t₂ of the quintic through the last three ends, and its
    /// divided differences per component (Newton's form); empty until two steps in a row.
    nodes: [f64; 6],
    differences: Vec<[f64; 6]>,
    /// The components the quintic serves (`SMOOTH_SLOPE`).
    smooth: Vec<bool>,
}

impl Hermite {
    pub(super) fn new(dimension: usize) -> Self {
        Hermite {
            earlier: None,
            nodes: [0.0; 6],
            differences: Vec::with_capacity(dimension),
            smooth: vec![false; dimension],
        }
    }

    /// Forgets the earlier steps (the method starts again from a point no step reached).
    pub(super) fn forget(&mut self) {
        self.earlier = None;
        self.differences.clear();
    }

    /// Takes the accepted step from (t, y), where the slope is f, of size h to y_new with slope
    /// f_new; `jacobian` says which components' slopes are smooth.
    pub(super) fn add_step(
        &mut self,
        jacobian: &DMatrix<f64>,
        (t, y, f): (f64, &[f64], &[f64]),
        (h, y_new, f_new): (f64, &[f64], &[f64]),
    ) {
        self.differences.clear();
        if let Some(earlier) = self.earlier.as_ref().filter(|end| end.t < t) {
            let times = [earlier.t, t, t + h];
            self.nodes = [times[0], times[0], times[1], times[1], times[2], times[2]];
            for i in 0..y.len() {
                let values = [earlier.y[i], y[i], y_new[i]];
                let slopes = [earlier.f[i], f[i], f_new[i]];
                self.differences
                    .push(divided_differences(&self.nodes, values, slopes));
            }
            for (i, smooth) in self.smooth.iter_mut().enumerate() {
                let row: f64 = jacobian.row(i).iter().map(|x| x.abs()).sum();
                *smooth = h * row <= SMOOTH_SLOPE;
            }
        }
        let end = self.earlier.get_or_insert_with(|| End {
            t,
            y: y.to_vec(),
            f: f.to_vec(),
        });
        end.t = t;
        end.y.copy_from_slice(y);
        end.f.copy_from_slice(f);
    }

    /// Overwrites the smooth components of `out` with the quintic's values at `t` (nothing
    /// before two steps in a row).
    pub(super) fn evaluate(&self, t: f64, out: &mut [f64]) {
        for ((out, d), smooth) in out.iter_mut().zip(&self.differences).zip(&self.smooth) {
            if *smooth {
                *out = newton_form(d, &self.nodes, t);
            }
        }
    }
}

/// The divided differences `f[z₀]`, `f[z₀, z₁]`, …, `f[z₀, …, z₅]` over the nodes t₀, t₀, t₁, t₁,
/// t₂, t₂ (each twice: value and slope) of the values and slopes at t₀, t₁, t₂.
pub fn divided_differences(nodes: &[f64; 6], values: [f64; 3], slopes: [f64; 3]) -> [f64; 6] {
    let mut d = [
        values[0], values[0], values[1], values[1], values[2], values[2],
    ];
    for order in 1..6 {
        for j in (order..6).rev() {
            d[j] = match order == 1 && j % 2 == 1 {
                // A repeated node: the divided difference is the slope there.
                true => slopes[j / 2],
                false => (d[j] - d[j - 1]) / (nodes[j] - nodes[j - order]),
            };
        }
    }
    d
}

/// The polynomial of divided differences `d` over `nodes` (Newton's form) at `t`.
pub fn newton_form(d: &[f64; 6], nodes: &[f64; 6], t: f64) -> f64 {
    (0..5).rev().fold(d[5], |p, k| d[k] + (t - nodes[k]) * p)
}
