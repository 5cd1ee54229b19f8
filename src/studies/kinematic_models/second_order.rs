//! The accelerations a motion needs to stay on the loops, and the frame's acceleration then:
//! the second-order terms of the kinematic models (the loops' exact velocity-product term
//! γ = Ġ v and the bodies' bias accelerations, no differences).

use nalgebra::DVector;

use super::error::KinematicsError;
use super::motion_basis::{dimensionless_rows, frame_jacobian, frame_origin, row_scale};
use super::output::Output;
use crate::dynamics::algorithms::Data;
use crate::dynamics::loops::{self, Extent};
use crate::dynamics::model::Model;
use crate::spatial::{self, Motion};

/// The accelerations a motion at rates `v` needs to stay on the loops, at least: the loops'
/// acceleration rows G v̇ + γ = 0 give the least-norm v̇ₚ = −G⁺γ (any other differs by an
/// allowed motion), and the frame's acceleration is then J v̇ₚ + β (β from the bodies' bias
/// accelerations).
pub(crate) struct SecondOrder {
    /// v̇ₚ (state accelerations).
    pub particular: DVector<f64>,
    /// The frame's acceleration with v̇ₚ (classical: the acceleration of its origin).
    pub frame: DVector<f64>,
    /// The frame's motion at `v`.
    pub output_rates: Vec<f64>,
}

pub(crate) fn second_order(
    model: &Model,
    output: &Output,
    q: &[f64],
    v: &[f64],
    scales: &[f64],
    length: f64,
) -> Result<SecondOrder, KinematicsError> {
    let mut data = Data::new(model);
    let moving = loops::constraints(model, &mut data, q, v, Extent::WithBias)?;
    if !model.has_loops() {
        // Without loops `constraints` leaves the bodies' bias accelerations uncomputed.
        crate::dynamics::algorithms::bias_accelerations(model, &mut data);
    }
    let point = frame_origin(&data, &output.frame);
    let g = dimensionless_rows(&moving.jacobian.dense(), length, scales);
    let gamma = DVector::from_iterator(
        moving.bias.len(),
        (moving.bias.iter().enumerate()).map(|(r, x)| x * row_scale(r, length)),
    );
    let particular_scaled = -(loops::decompose(&g).pseudo_inverse * gamma);
    let particular = DVector::from_iterator(
        v.len(),
        (0..v.len()).map(|c| particular_scaled[c] * scales[c]),
    );
    let frame_jacobian = frame_jacobian(model, &data, output, &point);
    let body = output.frame.body;
    let world = |m: &Motion| spatial::motion_to_parent(&data.world[body], m);
    let velocity = spatial::shifted(&point, &world(&data.velocity[body]));
    let acceleration = spatial::shifted(&point, &world(&data.acceleration[body]));
    // The classical acceleration of the frame's origin: the spatial one at that point plus
    // ω × v (Featherstone, Rigid Body Dynamics Algorithms, 2008, §2.11).
    let omega = spatial::angular(&velocity);
    let classical = spatial::twist(
        spatial::angular(&acceleration),
        spatial::linear(&acceleration) + omega.cross(&spatial::linear(&velocity)),
    );
    let offset = 6 - output.rows();
    let bias_output = DVector::from_fn(output.rows(), |r, _| classical[offset + r]);
    let output_rates: Vec<f64> = (0..output.rows()).map(|r| velocity[offset + r]).collect();
    let frame = &frame_jacobian * &particular + bias_output;
    Ok(SecondOrder {
        particular,
        frame,
        output_rates,
    })
}
