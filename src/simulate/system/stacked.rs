//! Keeps the rows beyond the loops' after a step (the contacts', the driven coordinates' and,
//! with closed loops, the mimic couplings'), on the response X as the accelerations solve them
//! (`holding`). After the loops' own projection, the position rows (the contacts' gaps, the
//! couplings' violations, the driven coordinates' distances to their laws at t) are
//! closed by Newton steps of least kinetic metric along X Gᵀ (along the loops and the tree's
//! couplings to first order), each followed by the loops' projection; then the velocities are
//! projected along X onto every kept row (the rolling rows, not integrable, on velocities only)
//! and onto the rates held (a driven coordinate's law's rate at t; at rest, a joint stuck by
//! its friction, a stop's resting coordinate): the loops' velocity rows and a tree's couplings
//! stay kept, since G X = 0 for them.

use super::{MechanicalSystem, SystemError};
use crate::corrector::{correct, Acceptance, Correction, Damping, Progress, Settings};
use crate::dynamics::algorithms::{crba_after_kinematics, forward_kinematics};
use crate::dynamics::loops::{self, Wanted};

/// Newton steps at most that close the position rows.
const POSITION_STEPS: usize = 4;

/// The position rows' iteration: every step is kept (a least change along X followed by the
/// loops' projection, not a descent on one measure) until the rows are at their round-off.
const STACKED: Settings = Settings {
    iterations: POSITION_STEPS,
    damping: Damping::None,
    acceptance: Acceptance::EveryStep,
    progress: Progress::Any,
};

impl MechanicalSystem<'_> {
    /// Keeps the contacts' rows and the couplings solved as rows in the state y (see the
    /// module's documentation). Whether y moved; nothing when there are no such rows.
    pub(super) fn keep_stacked(&mut self, t: f64, y: &mut [f64]) -> Result<bool, SystemError> {
        let model = self.model;
        let couplings = self.coupling_count();
        if !model.has_contacts() && couplings == 0 && model.drives.is_empty() {
            return Ok(false);
        }
        let (mut q, mut v) = (
            std::mem::take(&mut self.scratch.positions),
            std::mem::take(&mut self.scratch.velocities),
        );
        let kept = self.keep_stacked_in(t, y, &mut q, &mut v, couplings);
        (self.scratch.positions, self.scratch.velocities) = (q, v);
        kept
    }

    /// `keep_stacked` with the storage of the positions and velocities.
    fn keep_stacked_in(
        &mut self,
        t: f64,
        y: &mut [f64],
        q: &mut Vec<f64>,
        v: &mut Vec<f64>,
        couplings: usize,
    ) -> Result<bool, SystemError> {
        let model = self.model;
        let positions = model.positions();
        self.split_into(y, q, v);
        self.gather_held(t);
        let open = self.stacked_rows_at(t, q, v, couplings)?;
        let largest = self.scratch.position_stack.values_mut().amax();
        let mut steps = StackedSteps {
            system: self,
            t,
            y: &mut *y,
            q: &mut *q,
            v: &mut *v,
            couplings,
            open,
            largest,
        };
        let moved = correct(&mut steps, &STACKED)?.accepted > 0;
        self.gather_held(t);
        let kept = self.state.contact_rows.as_deref().unwrap_or_default();
        let stack = &mut self.scratch.velocity_stack;
        stack.arrange(kept, couplings, &self.scratch.held);
        stack.gather(&self.scratch.contact_state, &model.mimics);
        let off = stack.velocity_values(&self.scratch.contact_state, &model.mimics, v);
        stack.add_least_change(&mut self.scratch.response, v);
        y[positions..].copy_from_slice(v);
        Ok(moved || off)
    }

    /// At (q, v), the geometry (`stacked_geometry`) and the position rows' values in the
    /// position stack; whether any of them is above its round-off.
    fn stacked_rows_at(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
        couplings: usize,
    ) -> Result<bool, SystemError> {
        self.stacked_geometry(t, q, v)?;
        let stack = &mut self.scratch.position_stack;
        // The held rows with a position are the stops' (kept by `stop_rows`) and the drives'.
        let drives = &self.scratch.held[..self.model.drives.len()];
        stack.arrange(&self.scratch.normal_rows, couplings, drives);
        stack.gather(&self.scratch.contact_state, &self.model.mimics);
        Ok(stack.position_values(self.model, &self.scratch.contact_state, q))
    }

    /// The positions and velocities of y into `q` (quaternions at unit length) and `v`.
    fn split_into(&self, y: &[f64], q: &mut Vec<f64>, v: &mut Vec<f64>) {
        let rates = self.model.split_state_into(y, q);
        v.clear();
        v.extend_from_slice(rates);
    }

    /// At (q, v): the loops' allowed motions (a constrained solve), the contacts' rows without
    /// γ, the response X and the contact rows of the run decided if they were not.
    pub(super) fn stacked_geometry(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
    ) -> Result<(), SystemError> {
        let model = self.model;
        self.scratch.response_here = false;
        if model.has_loops() {
            self.solve_constrained(t, q, v, Wanted::Accelerations)?;
            self.form_response_at(q)?;
            forward_kinematics(model, &mut self.scratch.data, q, v)?;
        } else {
            forward_kinematics(model, &mut self.scratch.data, q, v)?;
            crba_after_kinematics(model, &mut self.scratch.data, &mut self.scratch.mass);
            self.form_tree_response()?;
        }
        if model.has_contacts() {
            self.contact_rows_here(v, false)?;
        }
        self.decide_contact_rows();
        Ok(())
    }
}

/// The position rows' steps, for the corrector: each one the least change along X that closes
/// the rows to first order, then the loops' projection; the state y follows every step.
struct StackedSteps<'s, 'm> {
    system: &'s mut MechanicalSystem<'m>,
    t: f64,
    y: &'s mut [f64],
    q: &'s mut Vec<f64>,
    v: &'s mut Vec<f64>,
    couplings: usize,
    /// Whether a position row at the current state is above its round-off, and the largest.
    open: bool,
    largest: f64,
}

impl Correction for StackedSteps<'_, '_> {
    type Error = SystemError;

    fn settled(&self) -> bool {
        !self.open
    }

    fn merit(&self) -> f64 {
        self.largest
    }

    fn step(&mut self, _damping: f64) -> Result<Option<f64>, SystemError> {
        let system = &mut *self.system;
        system.scratch.step.fill(0.0);
        let step = system.scratch.step.as_mut_slice();
        system
            .scratch
            .position_stack
            .add_least_change(&mut system.scratch.response, step);
        Ok(Some(0.0))
    }

    fn try_step(&mut self) -> Result<f64, SystemError> {
        let system = &mut *self.system;
        let model = system.model;
        model.retract(self.q, system.scratch.step.as_slice());
        if model.has_loops() {
            let choice = &system.scratch.loops.structure.choice;
            loops::project(model, &mut system.scratch.data, choice, self.q, self.v)?;
        }
        let positions = model.positions();
        self.y[..positions].copy_from_slice(self.q);
        self.y[positions..].copy_from_slice(self.v);
        system.split_into(self.y, self.q, self.v);
        self.open = system.stacked_rows_at(self.t, self.q, self.v, self.couplings)?;
        self.largest = system.scratch.position_stack.values_mut().amax();
        Ok(self.largest)
    }

    fn accept(&mut self) {}
}
