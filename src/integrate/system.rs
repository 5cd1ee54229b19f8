//! What the integrators integrate and whom they report to.

/// An error of the system or of the observer. The integrators know nothing of mechanics, so
/// they take any error and report its message as the integration's [`Failure`].
///
/// [`Failure`]: super::outcome::Failure
pub type CallbackError = Box<dyn std::error::Error + Send + Sync>;

/// A system of first-order ordinary differential equations.
pub trait OdeSystem {
    /// Length of the state vector.
    fn dimension(&self) -> usize;
    /// Writes dy/dt at (t, y) into `dydt`. An `Err` stops the integration with its message
    /// (e.g. a singular mass matrix).
    fn rhs(&mut self, t: f64, y: &[f64], dydt: &mut [f64]) -> Result<(), CallbackError>;
    /// Called after each accepted step with the new state: may move it back onto an invariant
    /// manifold (constraints of a closed-loop mechanism). Returns whether `y` changed.
    ///
    /// The integration continues from the projected state, and outputs at the step's end get it;
    /// outputs strictly inside a step still come from the step's interpolant. Not called on the
    /// initial state, which the caller makes consistent. An `Err` stops the integration like an
    /// `Err` from [`OdeSystem::rhs`].
    fn project(&mut self, _t: f64, _y: &mut [f64]) -> Result<bool, CallbackError> {
        Ok(false)
    }

    /// Directions spanning the motions of the state at (t, y), as the columns of a matrix over
    /// the state's leading components (the others do not move along them), or `None` when the
    /// state moves freely. A system constrained to a manifold (a mechanism's closed loops) gives
    /// the manifold's tangent space there: the implicit method differentiates f along these
    /// directions only. It may evaluate the right-hand side at (t, y) once to find them.
    fn tangent_basis(
        &mut self,
        _t: f64,
        _y: &[f64],
    ) -> Result<Option<nalgebra::DMatrix<f64>>, CallbackError> {
        Ok(None)
    }

    /// Whether f does not depend on t: the implicit method then takes ∂f/∂t = 0 instead of
    /// differencing f in time.
    fn autonomous(&self) -> bool {
        false
    }

    /// Writes ∂f/∂y at (t, y), where `dydt` = f(t, y), into `jacobian` (a square of the
    /// dimension), for a system that knows a way cheaper than differencing f along each
    /// component; `Ok(false)` (the default) leaves the implicit method to difference f. Not
    /// asked of a system with a [`OdeSystem::tangent_basis`].
    fn jacobian(
        &mut self,
        _t: f64,
        _y: &[f64],
        _dydt: &[f64],
        _jacobian: &mut nalgebra::DMatrix<f64>,
    ) -> Result<bool, CallbackError> {
        Ok(false)
    }

    /// Whether the step control should forget what the steps before the last
    /// [`OdeSystem::project`] said of the error's trend: an event changed the equations (a
    /// closed-loop mechanism's constraint rows chosen again, a singular passage entered or
    /// left), or the error's growth there says nothing of the steps to come.
    fn breaks_error_trend(&self) -> bool {
        false
    }

    /// Where the step just attempted, ending at (t, y), should end instead, as a fraction of
    /// it in (0, 1): the system passed between the last [`OdeSystem::project`] and y something
    /// that a step's end must see (a closed-loop mechanism, a singular configuration of its
    /// loops). The fixed-step integrator takes the step again, shortened to that fraction,
    /// before accepting it; `None` (the default) accepts it as it is. The adaptive methods do
    /// not ask: their step control already shortens the steps where the constraint forces
    /// grow, and cutting them as well made the parallelogram's drift at 1e-12 larger (3e-12 to
    /// 1e-10 and more, `tests/suite/singular_passages.rs`).
    fn cut_step(&mut self, _t: f64, _y: &[f64]) -> Result<Option<f64>, CallbackError> {
        Ok(None)
    }

    /// Where an adaptive method's step ending at (t, y), accepted by its error control, should
    /// end instead, as a fraction of it, when the system must see something before it: the
    /// step is then taken again so. `None` (the default) accepts it as it is.
    fn cut_adaptive_step(&mut self, _t: f64, _y: &[f64]) -> Result<Option<f64>, CallbackError> {
        Ok(None)
    }

    /// How many event functions the system has (a mechanism's stops): after each step the
    /// integrators locate, on the step's interpolant, the first time one of them crosses from
    /// non-negative to negative, and let [`OdeSystem::handle_event`] act there.
    fn event_count(&self) -> usize {
        0
    }

    /// Writes the event functions at (t, y) into `values` (length [`OdeSystem::event_count`]),
    /// non-negative while nothing happens.
    fn events(&mut self, _t: f64, _y: &[f64], _values: &mut [f64]) -> Result<(), CallbackError> {
        Ok(())
    }

    /// Acts at event `index`, located at time t where the state is y (an impact changes the
    /// velocities); the integration restarts from the changed y. An `Err` stops it like an
    /// `Err` from [`OdeSystem::rhs`].
    fn handle_event(
        &mut self,
        _t: f64,
        _y: &mut [f64],
        _index: usize,
    ) -> Result<(), CallbackError> {
        Ok(())
    }

    /// Observes the state y at output time t, before the integration's observer does: a
    /// system whose outputs are evaluations of its own equations (a run's sampler) observes
    /// with the same state and scratch its steps use. An `Err` stops the integration like one
    /// from the observer.
    fn observe(&mut self, _t: f64, _y: &[f64]) -> Result<(), CallbackError> {
        Ok(())
    }
}

/// Receives the state at each output time; an `Err` stops the integration with its message.
pub type Observer<'o> = dyn FnMut(f64, &[f64]) -> Result<(), CallbackError> + 'o;
