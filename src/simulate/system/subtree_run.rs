//! What a run whose drives are in fully driven subtrees keeps beside the model
//! (`driven_subtrees`).

use nalgebra::DVector;

use crate::dynamics::driven_subtrees::DrivenSubtrees;
use crate::dynamics::model::Model;
use crate::spatial::Force;

/// What a run by driven subtrees keeps beside the model: the subtrees and the buffers of their
/// evaluations.
pub struct SubtreeRun<'m> {
    pub(super) subtrees: &'m DrivenSubtrees,
    /// Per velocity, the generalised force beyond the efforts that imposes a driven one.
    pub(super) efforts: Vec<f64>,
    /// A state at rest, and no force on any body: the least change's passes.
    pub(super) rest: Vec<f64>,
    pub(super) no_external: Vec<Force>,
    /// The changes of the velocities a correction makes.
    pub(super) change: DVector<f64>,
}

impl<'m> SubtreeRun<'m> {
    pub fn new(model: &Model, subtrees: &'m DrivenSubtrees) -> SubtreeRun<'m> {
        SubtreeRun {
            subtrees,
            efforts: vec![0.0; model.velocities()],
            rest: vec![0.0; model.velocities()],
            no_external: vec![Force::zeros(); model.body_count() + 1],
            change: DVector::zeros(model.velocities()),
        }
    }
}
