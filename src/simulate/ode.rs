//! The run as its integrator sees it: the equations of motion as an ODE system (positions, then
//! velocities), with the work of the non-conservative efforts as one more state when it is
//! tracked, and the outputs observed on the same system (`OdeSystem::observe`).

use super::system::{MechanicalSystem, RunObserver};
use crate::integrate::{CallbackError, OdeSystem};

impl OdeSystem for MechanicalSystem<'_> {
    fn dimension(&self) -> usize {
        MechanicalSystem::dimension(self)
    }

    fn rhs(&mut self, t: f64, y: &[f64], dydt: &mut [f64]) -> Result<(), CallbackError> {
        Ok(self.derivative(t, y, dydt)?)
    }

    /// Keeps the step's end on the constraints, and the reference angles follow it.
    fn project(&mut self, t: f64, y: &mut [f64]) -> Result<bool, CallbackError> {
        let moved = self.keep_closed(t, y)?;
        self.follow_reference(t, y)?;
        Ok(moved)
    }

    fn tangent_basis(
        &mut self,
        t: f64,
        y: &[f64],
    ) -> Result<Option<nalgebra::DMatrix<f64>>, CallbackError> {
        Ok(MechanicalSystem::tangent_basis(self, t, y)?)
    }

    fn autonomous(&self) -> bool {
        MechanicalSystem::autonomous(self)
    }

    fn jacobian(
        &mut self,
        t: f64,
        y: &[f64],
        dydt: &[f64],
        jacobian: &mut nalgebra::DMatrix<f64>,
    ) -> Result<bool, CallbackError> {
        let mut power_gradient = vec![0.0; y.len()];
        Ok(MechanicalSystem::jacobian(
            self,
            t,
            y,
            dydt,
            jacobian,
            &mut power_gradient,
        )?)
    }

    fn breaks_error_trend(&self) -> bool {
        self.scratch.loops.breaks_trend
    }

    fn cut_step(&mut self, t: f64, y: &[f64]) -> Result<Option<f64>, CallbackError> {
        Ok(self.cut_at_passage(t, y)?)
    }

    fn cut_adaptive_step(&mut self, t: f64, y: &[f64]) -> Result<Option<f64>, CallbackError> {
        Ok(self.leave_passage_soon(t, y)?)
    }

    fn event_count(&self) -> usize {
        self.event_total()
    }

    fn events(&mut self, t: f64, y: &[f64], values: &mut [f64]) -> Result<(), CallbackError> {
        Ok(self.event_values(t, y, values)?)
    }

    fn handle_event(&mut self, t: f64, y: &mut [f64], index: usize) -> Result<(), CallbackError> {
        Ok(self.act_on_event(t, y, index)?)
    }
}

/// The run as the integrator sees it: the mechanism's equations of motion, then the program's
/// states (`state(x0)`, their rates from the efforts' tape), and when `tracks_work` one more
/// state, the work W of its non-conservative efforts (W' = their power; the step control watches
/// the motion and the states only, so the work changes no step); and its outputs, observed on
/// the same system. Each evaluation first sets the states' values in the run state, where the
/// efforts read them.
pub(super) struct RunOde<'r, 'm> {
    pub(super) system: &'r mut MechanicalSystem<'m>,
    pub(super) tracks_work: bool,
    pub(super) observer: &'r mut RunObserver<'r, 'm>,
}

impl RunOde<'_, '_> {
    /// The mechanism's part of the state and the states' count; the states' values set.
    fn load(&mut self, y: &[f64]) -> (usize, usize) {
        let (n, states) = (self.system.dimension(), self.system.state_count());
        if states > 0 {
            self.system.set_states(&y[n..n + states]);
        }
        (n, states)
    }
}

impl OdeSystem for RunOde<'_, '_> {
    fn dimension(&self) -> usize {
        self.system.dimension() + self.system.state_count() + usize::from(self.tracks_work)
    }

    fn rhs(&mut self, t: f64, y: &[f64], dydt: &mut [f64]) -> Result<(), CallbackError> {
        let (n, states) = self.load(y);
        self.system.derivative(t, &y[..n], &mut dydt[..n])?;
        if states > 0 {
            self.system.state_rates(&mut dydt[n..n + states])?;
        }
        if self.tracks_work {
            dydt[n + states] = self.system.scratch.power;
        }
        Ok(())
    }

    fn project(&mut self, t: f64, y: &mut [f64]) -> Result<bool, CallbackError> {
        let (n, _) = self.load(y);
        OdeSystem::project(&mut *self.system, t, &mut y[..n])
    }

    /// The loops' tangent directions, and each state's own: the states move freely.
    fn tangent_basis(
        &mut self,
        t: f64,
        y: &[f64],
    ) -> Result<Option<nalgebra::DMatrix<f64>>, CallbackError> {
        let (n, states) = self.load(y);
        let Some(motion) = self.system.tangent_basis(t, &y[..n])? else {
            return Ok(None);
        };
        let mut basis = nalgebra::DMatrix::zeros(n + states, motion.ncols() + states);
        basis
            .view_mut((0, 0), (n, motion.ncols()))
            .copy_from(&motion);
        for k in 0..states {
            basis[(n + k, motion.ncols() + k)] = 1.0;
        }
        Ok(Some(basis))
    }

    fn autonomous(&self) -> bool {
        self.system.autonomous()
    }

    /// The mechanism's Jacobian, and with the work, its rate's gradient as the last row (the
    /// rate does not depend on the work itself). With states, differences of the whole
    /// right-hand side (`Ok(false)`): the mechanism's Jacobian does not see them.
    fn jacobian(
        &mut self,
        t: f64,
        y: &[f64],
        dydt: &[f64],
        jacobian: &mut nalgebra::DMatrix<f64>,
    ) -> Result<bool, CallbackError> {
        let (n, states) = self.load(y);
        if states > 0 {
            return Ok(false);
        }
        if !self.tracks_work {
            return OdeSystem::jacobian(&mut *self.system, t, y, dydt, jacobian);
        }
        let mut motion = nalgebra::DMatrix::zeros(n, n);
        let mut power_gradient = vec![0.0; n];
        let given =
            (self.system).jacobian(t, &y[..n], &dydt[..n], &mut motion, &mut power_gradient)?;
        jacobian.fill(0.0);
        jacobian.view_mut((0, 0), (n, n)).copy_from(&motion);
        for (j, gradient) in power_gradient.iter().enumerate() {
            jacobian[(n, j)] = *gradient;
        }
        Ok(given)
    }

    fn breaks_error_trend(&self) -> bool {
        self.system.scratch.loops.breaks_trend
    }

    fn cut_step(&mut self, t: f64, y: &[f64]) -> Result<Option<f64>, CallbackError> {
        let (n, _) = self.load(y);
        Ok(self.system.cut_at_passage(t, &y[..n])?)
    }

    fn cut_adaptive_step(&mut self, t: f64, y: &[f64]) -> Result<Option<f64>, CallbackError> {
        let (n, _) = self.load(y);
        Ok(self.system.leave_passage_soon(t, &y[..n])?)
    }

    fn event_count(&self) -> usize {
        self.system.event_total()
    }

    fn events(&mut self, t: f64, y: &[f64], values: &mut [f64]) -> Result<(), CallbackError> {
        let (n, _) = self.load(y);
        Ok(self.system.event_values(t, &y[..n], values)?)
    }

    /// The impact, release or friction switch; the states and the work of the non-conservative
    /// efforts do not jump.
    fn handle_event(&mut self, t: f64, y: &mut [f64], index: usize) -> Result<(), CallbackError> {
        let (n, _) = self.load(y);
        Ok(self.system.act_on_event(t, &mut y[..n], index)?)
    }

    fn observe(&mut self, t: f64, y: &[f64]) -> Result<(), CallbackError> {
        (self.observer)(self.system, t, y)
    }
}
