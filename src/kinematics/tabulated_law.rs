//! A law of time given at knots rather than by an expression: at each knot its position, rate
//! and acceleration; between two knots the quintic polynomial that takes those six values at
//! its ends (quintic Hermite interpolation). The law is twice continuously differentiable, and
//! at the knots it is exactly what was given, so a run sampled at the knots (`lsdc inverse
//! --motion`) reads the given motion there, not an interpolation of it.

/// The six coefficients of one interval's quintic in s = (t − start) / length.
#[derive(Clone, Debug)]
struct Quintic {
    start: f64,
    length: f64,
    coefficients: [f64; 6],
}

/// A law through knots: see the module's documentation.
#[derive(Clone, Debug)]
pub struct TabulatedLaw {
    intervals: Vec<Quintic>,
}

/// Why knots cannot make a law.
#[derive(Clone, Debug, PartialEq)]
pub enum KnotsError {
    /// Fewer than two knots.
    TooFew,
    /// Times not strictly increasing from the knot with this index on.
    NotIncreasing(usize),
    /// A value that is not finite, at this knot.
    NotFinite(usize),
}

impl TabulatedLaw {
    /// The law through knots at `times` with these positions, rates and accelerations.
    pub fn through(
        times: &[f64],
        positions: &[f64],
        rates: &[f64],
        accelerations: &[f64],
    ) -> Result<TabulatedLaw, KnotsError> {
        if times.len() < 2 {
            return Err(KnotsError::TooFew);
        }
        let values = [times, positions, rates, accelerations];
        if let Some(k) = (0..times.len()).find(|&k| values.iter().any(|v| !v[k].is_finite())) {
            return Err(KnotsError::NotFinite(k));
        }
        let mut intervals = Vec::with_capacity(times.len() - 1);
        for k in 0..times.len() - 1 {
            let length = times[k + 1] - times[k];
            if length <= 0.0 {
                return Err(KnotsError::NotIncreasing(k + 1));
            }
            let start = [positions[k], rates[k], accelerations[k]];
            let end = [positions[k + 1], rates[k + 1], accelerations[k + 1]];
            intervals.push(Quintic {
                start: times[k],
                length,
                coefficients: hermite(length, start, end),
            });
        }
        Ok(TabulatedLaw { intervals })
    }

    /// Position, rate and acceleration at `t` (before the first knot and after the last, the
    /// end intervals' polynomials continued).
    pub fn at(&self, t: f64) -> [f64; 3] {
        let index = self
            .intervals
            .partition_point(|interval| interval.start <= t)
            .saturating_sub(1);
        let Quintic {
            start,
            length,
            coefficients: c,
        } = &self.intervals[index];
        let s = (t - start) / length;
        let position = c[0] + s * (c[1] + s * (c[2] + s * (c[3] + s * (c[4] + s * c[5]))));
        let rate = c[1] + s * (2.0 * c[2] + s * (3.0 * c[3] + s * (4.0 * c[4] + s * 5.0 * c[5])));
        let acceleration = 2.0 * c[2] + s * (6.0 * c[3] + s * (12.0 * c[4] + s * 20.0 * c[5]));
        [position, rate / length, acceleration / (length * length)]
    }
}

/// The quintic in s ∈ [0, 1] whose value, first and second derivatives in t = start + s·h are
/// `start` at s = 0 and `end` at s = 1: c₀..c₂ from the start, then c₃..c₅ from the three
/// conditions at the end, c₃ + c₄ + c₅ = P, 3c₃ + 4c₄ + 5c₅ = V, 6c₃ + 12c₄ + 20c₅ = A, solved
/// in closed form.
fn hermite(h: f64, start: [f64; 3], end: [f64; 3]) -> [f64; 6] {
    let [c0, c1, c2] = [start[0], h * start[1], h * h * start[2] / 2.0];
    let p = end[0] - (c0 + c1 + c2);
    let v = h * end[1] - (c1 + 2.0 * c2);
    let a = h * h * end[2] - 2.0 * c2;
    [
        c0,
        c1,
        c2,
        10.0 * p - 4.0 * v + a / 2.0,
        -15.0 * p + 7.0 * v - a,
        6.0 * p - 3.0 * v + a / 2.0,
    ]
}
