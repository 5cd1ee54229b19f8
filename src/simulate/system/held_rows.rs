//! The storage of the held rows (`holding`), apart from the code that uses it so that the
//! system holds it without depending on that code.

use nalgebra::{DMatrix, DVector};

use crate::dynamics::dense::Factor;
use crate::dynamics::model::Model;

/// What the held rows of a tree keep between evaluations, so that holding them allocates
/// nothing but when the coordinates held change (at an event): the held velocities, the mass
/// matrix and its factor, the responses P Eᵀ, E P Eᵀ and the forces.
#[derive(Debug)]
pub(super) struct HoldScratch {
    pub(super) rows: Vec<usize>,
    pub(super) mass: DMatrix<f64>,
    pub(super) factor: Factor,
    pub(super) responses: DMatrix<f64>,
    pub(super) coupling: DMatrix<f64>,
    pub(super) forces: DVector<f64>,
}

impl HoldScratch {
    pub(super) fn new(model: &Model) -> HoldScratch {
        HoldScratch {
            rows: Vec::with_capacity(model.stops.len() + model.frictions.len()),
            mass: DMatrix::zeros(0, 0),
            factor: Factor::new(0),
            responses: DMatrix::zeros(0, 0),
            coupling: DMatrix::zeros(0, 0),
            forces: DVector::zeros(0),
        }
    }

    /// Sizes the storage for n velocities and s held rows.
    pub(super) fn size_for(&mut self, n: usize, s: usize) {
        if self.mass.nrows() != n {
            self.mass = DMatrix::zeros(n, n);
            self.factor = Factor::new(n);
        }
        if self.responses.shape() != (n, s) {
            self.responses = DMatrix::zeros(n, s);
            self.coupling = DMatrix::zeros(s, s);
        }
        // The forces are also replaced whole by the paths that allocate (a velocity held twice).
        if self.forces.len() != s {
            self.forces = DVector::zeros(s);
        }
    }
}
