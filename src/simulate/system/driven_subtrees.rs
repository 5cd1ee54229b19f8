//! The run of a tree whose drives are all in fully driven subtrees (`dynamics::driven_subtrees`):
//! the accelerations by hybrid dynamics, the driven ones their laws', the free ones from the
//! articulated-body algorithm loaded by the subtrees, and the drives' efforts from the
//! subtrees' inverse dynamics (`dynamics::algorithms::hybrid`), with no row of the constraint
//! stack and no mass matrix. After a step the driven coordinates are put back on their laws by
//! the same least change in the kinetic metric the drives' rows take (`stacked`), computed by
//! the hybrid dynamics at rest instead of through M⁻¹: the run is the one with the drives' rows
//! to round-off.

use nalgebra::DVector;

use super::subtree_run::SubtreeRun;
use super::{MechanicalSystem, SystemError};
use crate::dynamics::algorithms::forward_kinematics;
use crate::dynamics::algorithms::hybrid::{hybrid_after_kinematics, least_change};
use crate::dynamics::driven_subtrees::DrivenSubtrees;
use crate::dynamics::rows::LAW_ROUND_OFF;

impl<'m> MechanicalSystem<'m> {
    /// Runs the drives of the fully driven subtrees `subtrees` by hybrid dynamics from now
    /// on, or as rows of the constraint stack with `None`.
    pub fn use_driven_subtrees(&mut self, subtrees: Option<&'m DrivenSubtrees>) {
        self.driven = subtrees.map(|s| Box::new(SubtreeRun::new(self.model, s)));
    }

    /// Whether the evaluations here take the driven subtrees' hybrid dynamics: native code,
    /// when it computes the accelerations, solves the rows instead.
    pub(super) fn drives_by_subtrees(&self) -> bool {
        self.driven.is_some() && self.native.is_none()
    }

    /// The accelerations at (t, q, v) by hybrid dynamics (see the module's comment), the
    /// drives' efforts and their power recorded.
    pub(super) fn subtree_accelerations(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
        accelerations: &mut DVector<f64>,
    ) -> Result<(), SystemError> {
        let model = self.model;
        let reads_efforts = self.reads_efforts();
        match reads_efforts {
            true => self.evaluate_efforts(t, q, v)?,
            false => forward_kinematics(model, &mut self.scratch.data, q, v)?,
        }
        let scratch = &mut *self.scratch;
        for drive in &model.drives {
            let law = drive.evaluate(t, &mut scratch.law_values);
            accelerations[drive.velocity] = law.acceleration;
        }
        let efforts = match reads_efforts {
            true => &scratch.efforts,
            false => &scratch.no_efforts,
        };
        let run = self
            .driven
            .as_deref_mut()
            .expect("a run by driven subtrees");
        let forces = (efforts.tau.as_slice(), &efforts.external[..]);
        let known = &run.subtrees.known;
        let solved = hybrid_after_kinematics(
            model,
            &mut scratch.data,
            known,
            forces,
            accelerations,
            &mut run.efforts,
        );
        if let Err(e) = solved {
            return Err(self.dynamics_error(&e));
        }
        scratch.drive_power = 0.0;
        for (index, drive) in model.drives.iter().enumerate() {
            let effort = run.efforts[drive.velocity];
            scratch.drive_efforts[index] = effort;
            scratch.drive_power += effort * v[drive.velocity];
        }
        Ok(())
    }

    /// Puts the driven coordinates of y back on their laws at t, as the drives' rows would
    /// (`stacked`): the positions, when one is off its law by more than round-off, by the least
    /// change in the kinetic metric that closes them; then the rates, onto their laws' by the
    /// least change at the positions reached. Whether y moved.
    pub(super) fn keep_driven_subtrees(
        &mut self,
        t: f64,
        y: &mut [f64],
    ) -> Result<bool, SystemError> {
        let model = self.model;
        let (mut q, mut v) = (
            std::mem::take(&mut self.scratch.positions),
            std::mem::take(&mut self.scratch.velocities),
        );
        v.clear();
        v.extend_from_slice(model.split_state_into(y, &mut q));
        let kept = self.keep_driven_in(t, y, &mut q, &mut v);
        (self.scratch.positions, self.scratch.velocities) = (q, v);
        kept
    }

    fn keep_driven_in(
        &mut self,
        t: f64,
        y: &mut [f64],
        q: &mut Vec<f64>,
        v: &mut Vec<f64>,
    ) -> Result<bool, SystemError> {
        let model = self.model;
        let scratch = &mut *self.scratch;
        let run = self
            .driven
            .as_deref_mut()
            .expect("a run by driven subtrees");
        let mut open = false;
        for drive in &model.drives {
            let law = drive.evaluate(t, &mut scratch.law_values);
            let off = q[drive.position] - law.position;
            run.change[drive.velocity] = -off;
            open |= off.abs() > LAW_ROUND_OFF * (1.0 + law.position.abs());
        }
        let known = &run.subtrees.known;
        let at_rest = (&run.rest[..], &run.no_external[..]);
        if open {
            let solved = least_change(
                model,
                &mut scratch.data,
                known,
                (q, at_rest.0, at_rest.1),
                &mut run.change,
            );
            solved.map_err(|e| self.dynamics_error(&e))?;
            let run = self
                .driven
                .as_deref_mut()
                .expect("a run by driven subtrees");
            model.retract(q, run.change.as_slice());
            let positions = model.positions();
            y[..positions].copy_from_slice(q);
            let rates = model.split_state_into(y, q);
            v.clear();
            v.extend_from_slice(rates);
        }
        let scratch = &mut *self.scratch;
        let run = self
            .driven
            .as_deref_mut()
            .expect("a run by driven subtrees");
        let mut off = false;
        for drive in &model.drives {
            let law = drive.evaluate(t, &mut scratch.law_values);
            let change = law.rate - v[drive.velocity];
            run.change[drive.velocity] = change;
            off |= change != 0.0;
        }
        if off {
            let known = &run.subtrees.known;
            let solved = least_change(
                model,
                &mut scratch.data,
                known,
                (q, &run.rest, &run.no_external),
                &mut run.change,
            );
            solved.map_err(|e| self.dynamics_error(&e))?;
            let run = self.driven.as_deref().expect("a run by driven subtrees");
            for (rate, change) in v.iter_mut().zip(run.change.iter()) {
                *rate += change;
            }
            y[model.positions()..].copy_from_slice(v);
        }
        Ok(open || off)
    }
}
