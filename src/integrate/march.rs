//! One method's integration between two of its steps, as the resumable integration
//! (`stepping::Integration`) holds it: what every method provides, and the span of a step.

use super::evaluator::{Evaluator, Halt};
use super::outcome::Stats;
use super::output::Outputs;
use super::settings::Settings;
use super::system::Observer;

/// Where the steps go: from `t0` (the integration's start, for the rounding of t) to `t_end`,
/// which the last step lands on exactly, under `settings`.
pub(super) struct Problem<'a> {
    pub(super) t0: f64,
    pub(super) t_end: f64,
    pub(super) settings: &'a Settings,
}

/// One method's integration between two steps.
pub(super) trait Marching {
    /// The current point of the solution.
    fn time(&self) -> f64;
    fn state(&self) -> &[f64];
    /// The current state, to change between two steps (then `restart`).
    fn state_mut(&mut self) -> &mut [f64];
    /// Prepares the first step from the current point, the start (dy/dt there, say).
    fn start(&mut self, eval: &mut Evaluator, problem: &Problem) -> Result<(), Halt>;
    /// Takes one step from the current point (attempts rejected on the way included), landing
    /// exactly on `problem.t_end` if it reaches it, and delivers the outputs the step passes.
    fn step(
        &mut self,
        eval: &mut Evaluator,
        problem: &Problem,
        outputs: &mut Outputs,
        observer: &mut Observer,
    ) -> Result<(), Halt>;
    /// Starts again from the current point, whose derivative changed (an effort set between
    /// two steps): nothing the last step left of it (its end derivative, its error's trend)
    /// is reused.
    fn restart(&mut self, eval: &mut Evaluator) -> Result<(), Halt>;
    /// Adds to `stats` what the method counts beside the evaluator (its stiffness check, its
    /// switches).
    fn count(&self, stats: &mut Stats);
}
