//! The loops' rows in planar form (`dynamics::planar`): of a planar loop's six rows (`rows`),
//! only the rotation about the normal and the two translations in the plane can be non-zero;
//! they are computed here from the planar kinematics, three per loop, and written in the
//! fixed axes where the loops' block reads them (ω n, v₁ e₁ + v₂ e₂: for a plane normal to a
//! fixed axis, three entries of the six; the others, out of the plane, are never among the
//! kept rows, and are left as they are). The equations of motion read G and γ
//! (`Extent::Motion`), which is all this computes.

use nalgebra::Vector2;

use super::rows::Constraints;
use crate::dynamics::model::Model;
use crate::dynamics::planar::algebra::{cross_motion, PlanarMotion, PlanarTransform};
use crate::dynamics::planar::algorithms::PlanarData;
use crate::dynamics::planar::model::{PlanarLoopKind, PlanarModel};

/// A motion of the fixed plane about its origin, taken about the point `p`: v + ω n̂ × p.
fn shifted(p: &Vector2<f64>, m: &PlanarMotion) -> PlanarMotion {
    PlanarMotion::new(m[0], m[1] - m[0] * p.y, m[2] + m[0] * p.x)
}

/// G and γ of every loop at (q, v) into `c`, with the position and velocity rows left at zero
/// (as `constraints_into` at `Extent::Motion`); `data` must hold the planar kinematics of
/// (q, v) for the rows (`planar::algorithms::kinematics` with `for_rows`).
pub fn planar_constraints_into(
    model: &Model,
    planar: &PlanarModel,
    data: &PlanarData,
    (q, v): (&[f64], &[f64]),
    c: &mut Constraints,
) {
    let world = |data: &PlanarData, motions: &[PlanarMotion], body: usize| match body {
        0 => PlanarMotion::zeros(),
        b => data.world[b].motion_to_parent(&motions[b]),
    };
    for (k, closing) in planar.loops.iter().enumerate() {
        let own = model.loop_offset(k);
        let (coordinate, rate) = (q[model.nq + own], v[model.nv + own]);
        let base: PlanarTransform = data.world[closing.first_body];
        // The loop point, and the chain's motion there per unit rate (fixed plane's axes).
        let (point, unit) = match &closing.kind {
            PlanarLoopKind::Revolute { rate } => (
                base.point_to_parent(&closing.first),
                PlanarMotion::new(*rate, 0.0, 0.0),
            ),
            PlanarLoopKind::Prismatic { direction } => {
                let along = base.rotate(direction);
                (
                    base.point_to_parent(&(closing.first + direction * coordinate)),
                    PlanarMotion::new(0.0, along.x, along.y),
                )
            }
        };
        let block = &mut c.jacobian.blocks[k];
        for &(local, column, sign) in &c.path_signs[k] {
            let moved = shifted(&point, &data.world_columns[column]) * sign;
            planar.write_spatial(&moved, &mut block.values.column_mut(local));
        }
        let local = block.local(model.nv + own);
        planar.write_spatial(&-unit, &mut block.values.column_mut(local));
        // γ: the difference of the two frames' accelerations at the loop point at zero joint
        // accelerations; the chain's velocity about the origin is its motion about the point
        // moved back there.
        let first_velocity = world(data, &data.velocity, closing.first_body);
        let chain_velocity = shifted(&-point, &(unit * rate));
        let end_acceleration = world(data, &data.acceleration, closing.first_body)
            + cross_motion(&first_velocity, &chain_velocity);
        let difference = world(data, &data.acceleration, closing.second_body) - end_acceleration;
        let gamma = shifted(&point, &difference);
        planar.write_spatial(&gamma, &mut c.bias.fixed_rows_mut::<6>(6 * k));
    }
    c.velocity.fill(0.0);
}
