//! Keeps the rows beyond the loops' after a step (the contacts', the driven coordinates', the
//! resting stops' and, with closed loops, the mimic couplings'), on the response X as the
//! accelerations solve them (`holding`): the one position correction of the stack's rows, by
//! the one corrector (`corrector`). After the loops' own projection, the position rows (the
//! contacts' gaps, the couplings' violations, the driven coordinates' distances to their laws
//! at t and, with loops or contacts, the resting stops' distances to their bounds) are closed
//! together by Newton steps of least kinetic metric along X Gᵀ (along the loops and the tree's
//! couplings to first order), each followed by the loops' projection; then the velocities are
//! projected along X onto every kept row (the rolling rows, not integrable, on velocities only)
//! and onto the rates held (a driven coordinate's law's rate at t; at rest, a joint stuck by
//! its friction, a stop's resting coordinate): the loops' velocity rows and a tree's couplings
//! stay kept, since G X = 0 for them. Before an impact the positions are closed the same way
//! with the impacting stop's bound among the rows (`impacts`): no coordinate is ever set alone,
//! which would open the loops and leave a driven coordinate off its law.

use super::{MechanicalSystem, SystemError};
use crate::corrector::{correct, Acceptance, Correction, Damping, Progress, Settings};
use crate::dynamics::loops;
use crate::dynamics::rows::{HeldRow, Holder, BOUND_ROUND_OFF};

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
    /// Keeps the stack's rows beyond the loops' in the state y (see the module's
    /// documentation). Whether y moved; nothing when there are no such rows.
    pub(super) fn keep_stacked(&mut self, t: f64, y: &mut [f64]) -> Result<bool, SystemError> {
        if self.drives_by_subtrees() {
            return self.keep_driven_subtrees(t, y);
        }
        if !self.has_stacked_rows() {
            return Ok(false);
        }
        self.with_state_storage(|system, q, v| {
            let closed = system.close_stacked(t, y, q, v, None)?;
            Ok(system.project_stacked_rates(t, y, v) || closed)
        })
    }

    /// Before an impact on stop `index` at time t: the positions of y moved onto the stack's
    /// position rows and the bounds of the resting stops and of stop `index` together.
    pub(super) fn close_for_impact(
        &mut self,
        t: f64,
        y: &mut [f64],
        index: usize,
    ) -> Result<(), SystemError> {
        self.with_state_storage(|system, q, v| system.close_stacked(t, y, q, v, Some(index)))?;
        Ok(())
    }

    /// Whether the run has rows beyond the loops' to keep after a step: contacts, couplings
    /// solved as rows, drives, or a stop resting in a mechanism with loops or contacts (on a
    /// tree without contacts a resting coordinate keeps its bound, set at its impact, with a
    /// zero rate and acceleration).
    fn has_stacked_rows(&self) -> bool {
        let model = self.model;
        let bounds =
            (model.has_loops() || model.has_contacts()) && self.state.resting.contains(&true);
        model.has_contacts()
            || self.coupling_count() > 0
            || !model.drives.is_empty()
            || !model.position_drives.is_empty()
            || bounds
    }

    /// Runs `keep` with the storage of the positions and velocities.
    fn with_state_storage<R>(
        &mut self,
        keep: impl FnOnce(&mut Self, &mut Vec<f64>, &mut Vec<f64>) -> R,
    ) -> R {
        let (mut q, mut v) = (
            std::mem::take(&mut self.scratch.positions),
            std::mem::take(&mut self.scratch.velocities),
        );
        let kept = keep(self, &mut q, &mut v);
        (self.scratch.positions, self.scratch.velocities) = (q, v);
        kept
    }

    /// Moves the positions of y onto the stack's position rows at t (the held ones those of
    /// `position_held`, with the stop `impacting`'s bound), by the corrector's steps
    /// (`StackedSteps`); a stop's coordinate left within round-off of its bound is set on it.
    /// Whether y moved. `q` and `v` are storage.
    fn close_stacked(
        &mut self,
        t: f64,
        y: &mut [f64],
        q: &mut Vec<f64>,
        v: &mut Vec<f64>,
        impacting: Option<usize>,
    ) -> Result<bool, SystemError> {
        let couplings = self.coupling_count();
        self.split_into(y, q, v);
        self.gather_position_held(t, impacting);
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
        Ok(self.set_on_bounds(y) || moved)
    }

    /// The velocities `v` of y, at the state `close_stacked` left (X and the contacts' rows
    /// formed there), projected along X onto every row of the stack and every held rate at t,
    /// into `v` and y. Whether any row was off.
    fn project_stacked_rates(&mut self, t: f64, y: &mut [f64], v: &mut [f64]) -> bool {
        let model = self.model;
        self.gather_held(t);
        let couplings = self.coupling_count();
        let kept = self.state.contact_rows.as_deref().unwrap_or_default();
        let stack = &mut self.scratch.velocity_stack;
        let points = &self.scratch.point_state;
        stack.arrange(kept, couplings, points, &self.scratch.held);
        stack.gather(&self.scratch.contact_state, &model.mimics, points);
        let off = stack.velocity_values(&self.scratch.contact_state, &model.mimics, points, v);
        stack.add_least_change(&mut self.scratch.response, v);
        y[model.positions()..].copy_from_slice(v);
        off
    }

    /// The held rows with a position into `position_held`: the drives' (their laws at t) and,
    /// with loops or contacts, the resting stops' and the stop `impacting`'s.
    fn gather_position_held(&mut self, t: f64, impacting: Option<usize>) {
        let model = self.model;
        self.gather_held(t);
        let mut rows = std::mem::take(&mut self.scratch.position_held);
        rows.clear();
        let drives = model.drives.len();
        rows.extend_from_slice(&self.scratch.held[..drives]);
        if model.has_loops() || model.has_contacts() {
            // `gather_held` puts the resting stops' rows after the drives'.
            let stops = self.scratch.held[drives..].iter();
            rows.extend(stops.filter(|row| matches!(row.holder, Holder::Stop { .. })));
            if let Some(index) = impacting {
                rows.push(HeldRow::on_stop(index, &model.stops[index]));
            }
        }
        self.scratch.position_held = rows;
    }

    /// Sets on its bound each stop coordinate of `position_held` left within round-off of it
    /// (a change at round-off, which leaves the other rows closed), so that the stop's event
    /// function starts the next step at zero, not below it where its crossing would be missed.
    /// Whether any moved.
    fn set_on_bounds(&self, y: &mut [f64]) -> bool {
        let mut moved = false;
        for row in &self.scratch.position_held {
            if let Holder::Stop {
                position, bound, ..
            } = row.holder
            {
                let snap = BOUND_ROUND_OFF * bound.abs().max(1.0);
                if y[position] != bound && (y[position] - bound).abs() <= snap {
                    y[position] = bound;
                    moved = true;
                }
            }
        }
        moved
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
        let points = &self.scratch.point_state;
        stack.arrange(
            &self.scratch.normal_rows,
            couplings,
            points,
            &self.scratch.position_held,
        );
        stack.gather(&self.scratch.contact_state, &self.model.mimics, points);
        let contacts = &self.scratch.contact_state;
        Ok(stack.position_values(self.model, contacts, points, q))
    }

    /// The positions and velocities of y into `q` (quaternions at unit length) and `v`.
    fn split_into(&self, y: &[f64], q: &mut Vec<f64>, v: &mut Vec<f64>) {
        let rates = self.model.split_state_into(y, q);
        v.clear();
        v.extend_from_slice(rates);
    }

    /// At (q, v): the response X of the stack (`form_stack_response`: with loops, their
    /// block solved), the contacts' rows without γ and the contact rows of the run decided if
    /// they were not.
    pub(super) fn stacked_geometry(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
    ) -> Result<(), SystemError> {
        self.form_stack_response(t, q, v)?;
        if self.model.has_contacts() {
            self.contact_rows_here(v, false)?;
        }
        self.point_rows_here(t, v, false);
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
