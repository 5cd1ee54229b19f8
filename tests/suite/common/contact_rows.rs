//! The contacts' rows of a model at a state, and their rates along the motion by central
//! differences: the oracle of γ (the rows' velocity-product term) and of the normal row (the
//! gap's rate).

use lsdc::dynamics::algorithms::{forward_kinematics, Data};
use lsdc::dynamics::contacts::{contact_rows, ContactRows};
use lsdc::dynamics::model::Model;
use nalgebra::DVector;

/// The rows at a state and their rates along its motion.
pub struct RowsAlongMotion {
    /// The rows at (q, v), γ included.
    pub here: ContactRows,
    /// d/dt (G v) at fixed v, (G(q + h v) v − G(q − h v) v) / 2h.
    pub velocity_rate: DVector<f64>,
    /// The same for each contact's gap.
    pub gap_rate: Vec<f64>,
}

/// The contacts' rows of `model` at (q, v) and their rates along q̇ = v by central differences
/// of step `h`.
pub fn rows_along_motion(model: &Model, q: &[f64], v: &[f64], h: f64) -> RowsAlongMotion {
    let mut data = Data::new(model);
    let mut rows_at = |q: &[f64], with_bias: bool| {
        forward_kinematics(model, &mut data, q, v).expect("kinematics");
        contact_rows(model, &mut data, v, with_bias)
    };
    let here = rows_at(q, true);
    let mut moved = |sign: f64| {
        let mut moved = q.to_vec();
        let step: Vec<f64> = v.iter().map(|x| sign * h * x).collect();
        model.retract(&mut moved, &step);
        rows_at(&moved, false)
    };
    let (ahead, behind) = (moved(1.0), moved(-1.0));
    let velocity_rate = (&ahead.velocity - &behind.velocity) / (2.0 * h);
    let gap_rate = (ahead.gap.iter().zip(&behind.gap))
        .map(|(a, b)| (a - b) / (2.0 * h))
        .collect();
    RowsAlongMotion {
        here,
        velocity_rate,
        gap_rate,
    }
}

impl RowsAlongMotion {
    /// Asserts that the first contact's rows change along the motion (a state that tests
    /// something) and that its γ is their rate, to 1e-6 relative.
    pub fn assert_bias_is_the_rate(&self) {
        let (here, rate) = (&self.here, &self.velocity_rate);
        assert!(
            rate.rows(0, 3).norm() > 0.1,
            "a state where the rows change: {rate}"
        );
        for row in 0..3 {
            assert!(
                (rate[row] - here.bias[row]).abs() < 1e-6 * (1.0 + rate[row].abs()),
                "row {row}: {} against {}",
                here.bias[row],
                rate[row]
            );
        }
    }
}
