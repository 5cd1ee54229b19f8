//! Stops in a mechanism with closed loops, contacts or mimic couplings: a stop is one more row
//! of the constraints, unilateral. At an impact its row joins the constraint stack, solved on
//! the response that keeps the loops (restitution on the stop's row alone, the stack's other
//! rows brought to zero velocity, `rows::impact_velocities`); while its
//! coordinate rests on it, it is an active bilateral row: its acceleration is held at zero with
//! the other rows kept (`holding`), and after each step the positions are brought back onto the
//! other rows' position constraints and the bound together, the velocities onto all the rows.
//! No coordinate is ever set alone: that would open the loops, and their projection would then
//! give the resting coordinate a rate again. The stop is released when its force would pull.

use nalgebra::{DMatrix, DVector};

use super::{MechanicalSystem, SystemError};
use crate::corrector::{
    correct, minimum_norm_step, Acceptance, Correction, Damping, Progress, Settings,
};
use crate::dynamics::algorithms::{crba, forward_kinematics};
use crate::dynamics::contacts::{self, holonomic_rows};
use crate::dynamics::loops::basis::SOLVE_TOLERANCE;
use crate::dynamics::loops::{self, decompose, Extent};
use crate::dynamics::rows::{HeldRow, BOUND_ROUND_OFF};

/// Newton steps at most when moving the positions onto the rows and the bounds.
const NEWTON_ITERATIONS: usize = 8;

/// Gauss–Newton onto the rows and the bounds: a step kept while it reduces the largest residual.
const ON_BOUNDS: Settings = Settings {
    iterations: NEWTON_ITERATIONS,
    damping: Damping::None,
    acceptance: Acceptance::Descent,
    progress: Progress::Any,
};

/// The rows of one state: position residuals and their Jacobian, or velocity rows.
struct Rows {
    residual: DVector<f64>,
    jacobian: DMatrix<f64>,
}

impl MechanicalSystem<'_> {
    /// Brings a state back onto the rows and the bounds of the resting stops together, after
    /// the loops' or the contacts' own projection: Gauss–Newton on the positions with
    /// minimum-norm steps on the rows' position constraints and qₖ = bound, then the velocities'
    /// orthogonal projection onto every row and vₖ = 0. Whether y moved; nothing on a tree or
    /// when no stop rests.
    pub(in crate::simulate) fn keep_on_bounds(
        &mut self,
        y: &mut [f64],
    ) -> Result<bool, SystemError> {
        let model = self.model;
        let resting: Vec<usize> = (0..model.stops.len())
            .filter(|&k| self.state.resting[k])
            .collect();
        if resting.is_empty() || !(model.has_loops() || model.has_contacts()) {
            return Ok(false);
        }
        let before = y.to_vec();
        self.close_on_bounds(y, &resting)?;
        let (q, v) = model.split_state(y);
        let held: Vec<HeldRow> = self.resting_stop_rows().collect();
        let rows = self.velocity_rows(&q, v, &held)?;
        let velocity = DVector::from_column_slice(v);
        let projected = &velocity - decompose(&rows).pseudo_inverse * (&rows * &velocity);
        let positions = model.positions();
        y[positions..].copy_from_slice(projected.as_slice());
        Ok(y != before.as_slice())
    }

    /// Moves the positions of y onto the rows' position constraints and the bounds of the stops
    /// `stops` together: minimum-norm Gauss–Newton steps (`corrector`, rows scaled), each kept
    /// while it reduces the largest residual.
    pub(in crate::simulate) fn close_on_bounds(
        &mut self,
        y: &mut [f64],
        stops: &[usize],
    ) -> Result<(), SystemError> {
        let model = self.model;
        let (q, v) = model.split_state(y);
        let v = v.to_vec();
        let rows = self.position_rows(&q, &v, stops)?;
        let mut steps = BoundSteps {
            system: self,
            stops,
            v,
            q,
            rows,
            step: DVector::zeros(0),
            trial: None,
        };
        correct(&mut steps, &ON_BOUNDS)?;
        let mut q = steps.q;
        // The stops' rows are left at round-off, on either side of the bound: the bound itself
        // (a change at round-off, which leaves the other rows closed), so that the stop's event
        // function starts the next step at zero, not below it where its crossing would be missed.
        for stop in stops.iter().map(|&k| &model.stops[k]) {
            let snap = BOUND_ROUND_OFF * stop.bound.abs().max(1.0);
            if (q[stop.position] - stop.bound).abs() <= snap {
                q[stop.position] = stop.bound;
            }
        }
        y[..q.len()].copy_from_slice(&q);
        Ok(())
    }

    /// Every position constraint at q, with its Jacobian over the velocities: the loops' kept
    /// rows, then the constraint stack's (`rows`) of the contacts' kept normal rows (their
    /// gaps), every mimic coupling and the bounds of the stops `stops`, qₖ − bound.
    fn position_rows(
        &mut self,
        q: &[f64],
        v: &[f64],
        stops: &[usize],
    ) -> Result<Rows, SystemError> {
        let model = self.model;
        let mut rows = Rows {
            residual: DVector::zeros(0),
            jacobian: DMatrix::zeros(0, model.velocities()),
        };
        if model.has_loops() {
            let c = self.loop_rows_at(q, v)?;
            let kept = &self.scratch.loops.structure.choice.rows;
            let residual = DVector::from_iterator(kept.len(), kept.iter().map(|&r| c.residual[r]));
            rows.stack(residual, self.loop_kept_rows(&c.jacobian.dense()));
        }
        let all = self.contact_rows_at(q, v)?;
        let normal = holonomic_rows(&self.contact_rows_kept());
        let held: Vec<HeldRow> = (stops.iter())
            .map(|&index| HeldRow::on_stop(index, &model.stops[index]))
            .collect();
        let stack = &mut self.scratch.position_stack;
        stack.arrange(&normal, model.mimics.len(), &held);
        stack.gather(&all, &model.mimics);
        stack.position_values(model, &all, q);
        rows.stack(stack.values_mut().clone(), stack.rows().clone());
        Ok(rows)
    }

    /// Every velocity row at (q, v), dense over the state's velocities: the loops' kept rows,
    /// then the constraint stack's (`rows`) of the contacts' kept rows, every mimic coupling
    /// and the coordinates `held`.
    fn velocity_rows(
        &mut self,
        q: &[f64],
        v: &[f64],
        held: &[HeldRow],
    ) -> Result<DMatrix<f64>, SystemError> {
        let model = self.model;
        let mut rows = DMatrix::zeros(0, model.velocities());
        if model.has_loops() {
            let c = self.loop_rows_at(q, v)?;
            rows = self.loop_kept_rows(&c.jacobian.dense());
        }
        let all = self.contact_rows_at(q, v)?;
        let kept = self.contact_rows_kept();
        let stack = &mut self.scratch.velocity_stack;
        stack.arrange(&kept, model.mimics.len(), held);
        stack.gather(&all, &model.mimics);
        Ok(stack_below(&rows, stack.rows()))
    }

    /// The loops' rows at (q, v).
    fn loop_rows_at(&mut self, q: &[f64], v: &[f64]) -> Result<loops::Constraints, SystemError> {
        let model = self.model;
        forward_kinematics(model, &mut self.scratch.data, q, v)?;
        Ok(loops::constraints(
            model,
            &mut self.scratch.data,
            q,
            v,
            Extent::Rows,
        )?)
    }

    /// The contacts' rows at (q, v) (none without contacts). The contact rows of the run are
    /// decided by the first evaluation; a state evaluated here first keeps those independent
    /// on the tree (M⁻¹) or, with loops, every candidate row.
    fn contact_rows_at(
        &mut self,
        q: &[f64],
        v: &[f64],
    ) -> Result<contacts::ContactRows, SystemError> {
        let model = self.model;
        if !model.has_contacts() {
            return Ok(contacts::ContactRows::new(model));
        }
        forward_kinematics(model, &mut self.scratch.data, q, v)?;
        let rows = contacts::contact_rows(model, &mut self.scratch.data, v, false);
        if self.state.contact_rows.is_none() {
            self.state.contact_rows = Some(match model.has_loops() {
                true => contacts::candidate_rows(model),
                false => {
                    self.scratch.mass = crba(model, &mut self.scratch.data, q)?;
                    self.form_tree_response()?;
                    contacts::independent_rows(model, &mut self.scratch.response, &rows)
                }
            });
        }
        Ok(rows)
    }

    /// The contact rows of the run (`contact_rows_at` decides them).
    fn contact_rows_kept(&self) -> Vec<usize> {
        self.state.contact_rows.clone().unwrap_or_default()
    }

    /// The rows of the loops' structure among the 6 per loop of a dense constraint Jacobian.
    fn loop_kept_rows(&self, jacobian: &DMatrix<f64>) -> DMatrix<f64> {
        jacobian.select_rows(&self.scratch.loops.structure.choice.rows)
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

/// The positions' steps onto the rows and the resting stops' bounds, for the corrector.
struct BoundSteps<'s, 'm> {
    system: &'s mut MechanicalSystem<'m>,
    stops: &'s [usize],
    v: Vec<f64>,
    q: Vec<f64>,
    rows: Rows,
    step: DVector<f64>,
    /// The positions tried and their rows.
    trial: Option<(Vec<f64>, Rows)>,
}

impl Correction for BoundSteps<'_, '_> {
    type Error = SystemError;

    fn settled(&self) -> bool {
        self.merit() == 0.0
    }

    fn merit(&self) -> f64 {
        self.rows.residual.amax()
    }

    fn step(&mut self, _damping: f64) -> Result<Option<f64>, SystemError> {
        let rows = &self.rows;
        let Some(step) = minimum_norm_step(&rows.jacobian, &rows.residual, SOLVE_TOLERANCE) else {
            return Ok(None);
        };
        self.step = step;
        Ok(Some(self.step.amax()))
    }

    fn try_step(&mut self) -> Result<f64, SystemError> {
        let mut trial = self.q.clone();
        self.system.model.retract(&mut trial, self.step.as_slice());
        let there = self.system.position_rows(&trial, &self.v, self.stops)?;
        let merit = there.residual.amax();
        self.trial = Some((trial, there));
        Ok(merit)
    }

    fn accept(&mut self) {
        if let Some((q, rows)) = self.trial.take() {
            (self.q, self.rows) = (q, rows);
        }
    }
}

impl Rows {
    /// Appends the rows `jacobian` with their residuals `residual`.
    fn stack(&mut self, residual: DVector<f64>, jacobian: DMatrix<f64>) {
        let values = self.residual.iter().chain(residual.iter()).copied();
        self.residual = DVector::from_iterator(self.residual.len() + residual.len(), values);
        self.jacobian = stack_below(&self.jacobian, &jacobian);
    }
}

/// `upper` with the rows of `lower` below.
fn stack_below(upper: &DMatrix<f64>, lower: &DMatrix<f64>) -> DMatrix<f64> {
    let mut stacked = DMatrix::zeros(upper.nrows() + lower.nrows(), upper.ncols());
    stacked.rows_mut(0, upper.nrows()).copy_from(upper);
    stacked
        .rows_mut(upper.nrows(), lower.nrows())
        .copy_from(lower);
    stacked
}
