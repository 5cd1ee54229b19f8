//! The tangent space of the constraints at a state of a mechanism with closed loops, for the
//! implicit methods' Jacobian (`jacobian`, the Rosenbrock-W method differentiates the equations
//! of motion along it only): the allowed motions of the loops' block that leave the resting
//! stops' coordinates at rest.

use nalgebra::DMatrix;

use super::{MechanicalSystem, SystemError};
use crate::dynamics::loops::decompose;

impl MechanicalSystem<'_> {
    /// The tangent space of the loops' constraints at y, for the implicit method's Jacobian:
    /// for each allowed motion n of the velocities (the massive ones the equations of motion
    /// solve on) that leaves the resting stops' coordinates at rest, the state's direction
    /// (q̇(n), 0) that moves the positions along it and (0, n) that moves the velocities along
    /// it. `None` for a tree, whose state moves freely.
    /// Evaluates the equations of motion at y once (their solve finds the allowed motions).
    pub fn tangent_basis(
        &mut self,
        t: f64,
        y: &[f64],
    ) -> Result<Option<DMatrix<f64>>, SystemError> {
        let model = self.model;
        if !model.has_loops() {
            return Ok(None);
        }
        let mut dydt = vec![0.0; self.dimension()];
        self.derivative(t, y, &mut dydt)?;
        let structure = &self.scratch.loops.structure;
        self.scratch.loop_scratch.ensure_motions(structure);
        let (q, _) = model.split_state(y);
        let motions =
            self.motions_off_bounds(self.scratch.loop_scratch.solved_motions().into_owned());
        let (positions, velocities) = (model.positions(), model.velocities());
        let count = motions.ncols();
        let mut basis = DMatrix::zeros(positions + velocities, 2 * count);
        for k in 0..count {
            let motion = motions.column(k);
            let mut column = basis.column_mut(k);
            let rates = column.as_mut_slice();
            for joint in &model.joints {
                let range = joint.q_offset..joint.q_offset + joint.nq();
                let v_range = joint.v_offset..joint.v_offset + joint.nv();
                joint.position_rate(
                    &q[range.clone()],
                    &motion.as_slice()[v_range],
                    &mut rates[range],
                );
            }
            for (i, rate) in motion.iter().enumerate().skip(model.nv) {
                rates[model.nq + i - model.nv] = *rate;
            }
            basis
                .view_mut((positions, count + k), (velocities, 1))
                .copy_from(&motion);
        }
        Ok(Some(basis))
    }

    /// The allowed motions `motions` (columns over the state's velocities) restricted to those
    /// that leave the resting stops' coordinates at rest: the tangent directions of the run
    /// while they rest (none when every allowed motion moves them).
    pub(super) fn motions_off_bounds(&self, motions: DMatrix<f64>) -> DMatrix<f64> {
        let model = self.model;
        let held: Vec<usize> = (0..model.stops.len())
            .filter(|&k| self.state.resting[k])
            .map(|k| model.stops[k].velocity)
            .collect();
        if held.is_empty() || motions.ncols() == 0 {
            return motions;
        }
        let moved = motions.select_rows(&held);
        let allowed = decompose(&moved).null_space;
        motions * allowed
    }
}
