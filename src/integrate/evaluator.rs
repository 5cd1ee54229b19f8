//! Calls the system's right-hand side and projection, counting calls and catching non-finite values.

use super::outcome::{Failure, IntegrationError, Stats};
use super::system::{CallbackError, OdeSystem};

/// Why a step attempt, or the integration, stopped.
#[derive(Clone, Debug)]
pub(super) enum Halt {
    /// A NaN or infinity appeared at `time`; a shorter step may avoid it.
    NotFinite { time: f64 },
    /// Nothing the integrator can do about it.
    Fatal { time: f64, failure: Failure },
}

impl Halt {
    pub(super) fn fatal(time: f64, failure: Failure) -> Halt {
        Halt::Fatal { time, failure }
    }

    /// The same halt, no longer open to a retry with a shorter step.
    pub(super) fn made_fatal(self) -> Halt {
        match self {
            Halt::NotFinite { time } => Halt::fatal(time, Failure::NotFinite),
            fatal => fatal,
        }
    }

    pub(super) fn into_error(self, stats: Stats) -> IntegrationError {
        let (time, failure) = match self {
            Halt::NotFinite { time } => (time, Failure::NotFinite),
            Halt::Fatal { time, failure } => (time, failure),
        };
        IntegrationError {
            time,
            failure,
            stats: Box::new(stats),
        }
    }
}

/// The system with the bookkeeping every method needs around it.
pub(super) struct Evaluator<'s> {
    system: &'s mut dyn OdeSystem,
    /// Borrowed, not moved in and out at each step: the counts are a few hundred bytes.
    pub(super) stats: &'s mut Stats,
}

impl<'s> Evaluator<'s> {
    /// Evaluates `system`, counting on in `stats` (an integration's so far).
    pub(super) fn resume(system: &'s mut dyn OdeSystem, stats: &'s mut Stats) -> Self {
        Evaluator { system, stats }
    }

    /// The system's observation of the output at (t, y) (`OdeSystem::observe`).
    pub(super) fn observe(&mut self, t: f64, y: &[f64]) -> Result<(), CallbackError> {
        self.system.observe(t, y)
    }

    /// dy/dt at (t, y); a non-finite state or derivative becomes `Halt::NotFinite` at `t`.
    pub(super) fn rhs(&mut self, t: f64, y: &[f64], dydt: &mut [f64]) -> Result<(), Halt> {
        if !all_finite(y) {
            return Err(Halt::NotFinite { time: t });
        }
        self.stats.rhs_evaluations += 1;
        self.system
            .rhs(t, y, dydt)
            .map_err(|error| Halt::fatal(t, Failure::System(error.to_string())))?;
        if !all_finite(dydt) {
            return Err(Halt::NotFinite { time: t });
        }
        Ok(())
    }

    /// Lets the system move the end (t, y) of an accepted step onto its invariant manifold;
    /// returns whether `y` changed. Errors stop the integration like those of `rhs`.
    pub(super) fn project(&mut self, t: f64, y: &mut [f64]) -> Result<bool, Halt> {
        let moved = self
            .system
            .project(t, y)
            .map_err(|error| Halt::fatal(t, Failure::System(error.to_string())))?;
        // The step is already accepted: a shorter one cannot undo a projection gone wrong.
        if moved && !all_finite(y) {
            return Err(Halt::fatal(t, Failure::NotFinite));
        }
        Ok(moved)
    }

    /// Where the step ending at (t, y) should end instead (`OdeSystem::cut_step`).
    pub(super) fn cut_step(&mut self, t: f64, y: &[f64]) -> Result<Option<f64>, Halt> {
        self.system
            .cut_step(t, y)
            .map_err(|error| Halt::fatal(t, Failure::System(error.to_string())))
    }

    /// Where the adaptive step ending at (t, y) should end instead
    /// (`OdeSystem::cut_adaptive_step`).
    pub(super) fn cut_adaptive_step(&mut self, t: f64, y: &[f64]) -> Result<Option<f64>, Halt> {
        self.system
            .cut_adaptive_step(t, y)
            .map_err(|error| Halt::fatal(t, Failure::System(error.to_string())))
    }

    pub(super) fn event_count(&self) -> usize {
        self.system.event_count()
    }

    /// The event functions at (t, y) (`OdeSystem::events`).
    pub(super) fn events(&mut self, t: f64, y: &[f64], values: &mut [f64]) -> Result<(), Halt> {
        self.system
            .events(t, y, values)
            .map_err(|error| Halt::fatal(t, Failure::System(error.to_string())))
    }

    /// Lets the system act at event `index` (`OdeSystem::handle_event`), and counts it.
    pub(super) fn handle_event(&mut self, t: f64, y: &mut [f64], index: usize) -> Result<(), Halt> {
        self.stats.events += 1;
        self.system
            .handle_event(t, y, index)
            .map_err(|error| Halt::fatal(t, Failure::System(error.to_string())))?;
        match all_finite(y) {
            true => Ok(()),
            false => Err(Halt::fatal(t, Failure::NotFinite)),
        }
    }

    /// The system's tangent directions at (t, y) (`OdeSystem::tangent_basis`); finding them
    /// counts as one evaluation of the right-hand side.
    pub(super) fn tangent_basis(
        &mut self,
        t: f64,
        y: &[f64],
    ) -> Result<Option<nalgebra::DMatrix<f64>>, Halt> {
        let basis = self
            .system
            .tangent_basis(t, y)
            .map_err(|error| Halt::fatal(t, Failure::System(error.to_string())))?;
        if basis.is_some() {
            self.stats.rhs_evaluations += 1;
        }
        Ok(basis)
    }

    /// The system's own Jacobian at (t, y) (`OdeSystem::jacobian`), if it has one; its
    /// evaluations are the system's own affair, not counted as right-hand sides.
    pub(super) fn jacobian(
        &mut self,
        t: f64,
        y: &[f64],
        dydt: &[f64],
        jacobian: &mut nalgebra::DMatrix<f64>,
    ) -> Result<bool, Halt> {
        let given = self
            .system
            .jacobian(t, y, dydt, jacobian)
            .map_err(|error| Halt::fatal(t, Failure::System(error.to_string())))?;
        if given && !all_finite(jacobian.as_slice()) {
            return Err(Halt::NotFinite { time: t });
        }
        Ok(given)
    }

    /// Whether f does not depend on t (`OdeSystem::autonomous`).
    pub(super) fn autonomous(&self) -> bool {
        self.system.autonomous()
    }

    /// Whether the step control should forget the error's trend (`OdeSystem::breaks_error_trend`).
    pub(super) fn breaks_error_trend(&self) -> bool {
        self.system.breaks_error_trend()
    }
}

pub(super) fn all_finite(values: &[f64]) -> bool {
    values.iter().all(|v| v.is_finite())
}
