//! Constraints on the motion beyond the loops' rows, solved together with them: the rows E a
//! state's motion must keep (E v = 0, E v̇ = 0, all constant), their forces Eᵀλ, and the
//! response P of the accelerations to generalised forces they act through
//! (`loops::constrained_response` with loops, M⁻¹ with the mimic couplings kept on a tree). The
//! rows are, in this order:
//!
//! - with loops, each mimic coupling q_f − m q_l − o = 0 (on a tree it is eliminated instead,
//!   `mimics::solve`), kept at the position level too ([`MechanicalSystem::keep_couplings`]);
//! - each coordinate resting on its stop;
//! - each joint held at rest by its dry friction (sticking).

use nalgebra::{DMatrix, DVector};

use super::{MechanicalSystem, SystemError};
use crate::dynamics::algorithms::crba;
use crate::dynamics::friction::Phase;
use crate::dynamics::loops;
use crate::dynamics::mimics;

/// Relative size of a coupling's violation (position or rate) below which it is not corrected.
const COUPLING_ROUND_OFF: f64 = 1e-13;

/// Newton steps at most that `keep_couplings` takes to close the couplings with the loops.
const COUPLING_STEPS: usize = 4;

impl MechanicalSystem<'_> {
    /// The mimic couplings' rows solved with the loops' (none on a tree, which eliminates them),
    /// over the state's velocities.
    pub(super) fn coupling_rows(&self) -> DMatrix<f64> {
        let model = self.model;
        match model.has_loops() {
            true => mimics::rows(&model.mimics, model.velocities()),
            false => DMatrix::zeros(0, model.velocities()),
        }
    }

    /// The rows held at an evaluation ([`coupling_rows`](Self::coupling_rows), then the stops'
    /// resting coordinates and the sticking joints' unit rows), and how many are couplings.
    pub(in crate::simulate) fn held_rows(&self) -> (DMatrix<f64>, usize) {
        let model = self.model;
        let couplings = self.coupling_rows();
        let units = self.held_velocities();
        let count = couplings.nrows();
        let mut rows = DMatrix::zeros(count + units.len(), model.velocities());
        rows.rows_mut(0, count).copy_from(&couplings);
        for (i, &velocity) in units.iter().enumerate() {
            rows[(count + i, velocity)] = 1.0;
        }
        (rows, count)
    }

    /// The velocities held at rest: the resting stops' coordinates, then the sticking joints'.
    pub(super) fn held_velocities(&self) -> Vec<usize> {
        let model = self.model;
        let resting = (0..model.stops.len()).filter(|&k| self.resting[k]);
        let sticking = (0..model.frictions.len()).filter(|&k| self.phases[k] == Phase::Sticking);
        (resting.map(|k| model.stops[k].velocity))
            .chain(sticking.map(|k| model.frictions[k].velocity))
            .collect()
    }

    /// The accelerations' response P F to the generalised forces F (columns over the state's
    /// velocities) at positions q: with loops, at the allowed motions of the last constrained
    /// solve (which must be at q); on a tree, M⁻¹F with the mimic couplings kept.
    pub(super) fn response(
        &mut self,
        q: &[f64],
        forces: &DMatrix<f64>,
    ) -> Result<DMatrix<f64>, SystemError> {
        let model = self.model;
        let mass = crba(model, &mut self.data, &q[..model.nq])?;
        let response = match model.has_loops() {
            true => {
                let motions = self.loop_scratch.solved_motions();
                loops::constrained_response(&mass, motions, forces)
            }
            false => mimics::solve(&model.mimics, &mass, forces),
        };
        response.ok_or(SystemError::SingularMassMatrix)
    }

    /// The change of the velocities (or accelerations) of least kinetic metric along the
    /// response P that brings `rows` from `values` to zero: −P Eᵀ (E P Eᵀ)⁺ e, and the forces
    /// λ = −(E P Eᵀ)⁺ e it takes. Rank-revealing: a follower held at rest with its leader gives
    /// two rows for one coupled motion.
    pub(in crate::simulate) fn held_change(
        &mut self,
        q: &[f64],
        rows: &DMatrix<f64>,
        values: &DVector<f64>,
    ) -> Result<(DVector<f64>, DVector<f64>), SystemError> {
        let values = DMatrix::from_column_slice(values.len(), 1, values.as_slice());
        let (change, forces) = self.held_changes(q, rows, &values)?;
        Ok((change.column(0).into_owned(), forces.column(0).into_owned()))
    }

    /// [`held_change`](Self::held_change) for several columns of values at once: the changes
    /// and forces column by column.
    pub(in crate::simulate) fn held_changes(
        &mut self,
        q: &[f64],
        rows: &DMatrix<f64>,
        values: &DMatrix<f64>,
    ) -> Result<(DMatrix<f64>, DMatrix<f64>), SystemError> {
        let responses = self.response(q, &rows.transpose())?;
        let coupling = rows * &responses;
        let forces = (coupling.svd(true, true).solve(&(-values), 1e-12))
            .map_err(|_| SystemError::SingularMassMatrix)?;
        Ok((&responses * &forces, forces))
    }

    /// Keeps the mimic couplings of a mechanism with loops in the state y after the loops'
    /// projection (which knows nothing of them): Newton steps along P Eᵀ, which move along the
    /// loops to first order, each followed by the loops' projection, until the couplings hold
    /// at round-off; then the velocities' change of least kinetic metric that keeps them (it
    /// keeps the loops' velocity rows: G P = 0). Whether y moved. Nothing on a tree, whose
    /// accelerations keep the couplings exactly (a linear invariant of the run).
    pub fn keep_couplings(&mut self, t: f64, y: &mut [f64]) -> Result<bool, SystemError> {
        let model = self.model;
        if !model.has_loops() || model.mimics.is_empty() {
            return Ok(false);
        }
        let rows = self.coupling_rows();
        let positions = model.positions();
        let mut moved = false;
        for _ in 0..COUPLING_STEPS {
            let (mut q, v) = model.split_state(y);
            let mut v = v.to_vec();
            let violation = DVector::from_iterator(
                model.mimics.len(),
                model.mimics.iter().map(|m| m.violation(&q)),
            );
            let scale = 1.0
                + model
                    .mimics
                    .iter()
                    .map(|m| q[m.position].abs())
                    .fold(0.0, f64::max);
            if violation.amax() <= COUPLING_ROUND_OFF * scale {
                break;
            }
            self.solve_constrained(t, &q, &v, loops::Wanted::Accelerations)?;
            let (step, _) = self.held_change(&q, &rows, &violation)?;
            model.retract(&mut q, step.as_slice());
            let choice = &self.loops.structure.choice;
            loops::project(model, &mut self.data, choice, &mut q, &mut v)?;
            y[..positions].copy_from_slice(&q);
            y[positions..].copy_from_slice(&v);
            moved = true;
        }
        let (q, v) = model.split_state(y);
        let rates = &rows * DVector::from_column_slice(v);
        let scale = 1.0 + v.iter().fold(0.0, |m: f64, x| m.max(x.abs()));
        if rates.amax() > COUPLING_ROUND_OFF * scale {
            let v = v.to_vec();
            self.solve_constrained(t, &q, &v, loops::Wanted::Accelerations)?;
            let (change, _) = self.held_change(&q, &rows, &rates)?;
            for (x, dx) in y[positions..].iter_mut().zip(change.iter()) {
                *x += dx;
            }
            moved = true;
        }
        Ok(moved)
    }
}
