//! The reduced mass matrix NᵀMN of the allowed motions N, formed the cheaper way the tree's
//! structure allows: by one pass over the bodies per motion (each body's motion under it, then
//! the kinetic energy's bilinear form Σ v_iᵀ I_i w_i), or from the mass matrix M of the
//! composite-rigid-body algorithm and its products with each motion. A closed mechanism has
//! few allowed motions (one for a row of four-bars, three on the Delta): the passes then cost a
//! fraction of building M, whose entries number one per pair of velocities on a branch.

use nalgebra::DMatrix;

use crate::dynamics::algorithms::{
    body_motions, crba_after_kinematics, mass_rows, mass_times, Data,
};
use crate::dynamics::model::Model;
use crate::spatial::{Force, Motion};

/// What forming NᵀMN keeps between evaluations, so that it allocates nothing once sized.
pub struct ReducedInertia {
    /// Up to how many kept motions the passes are taken (see `passes_up_to`).
    passes_up_to: usize,
    /// The passes: each motion's body motions and the bodies' momenta under it, one block of
    /// bodies + 1 per motion.
    motions: Vec<Motion>,
    momenta: Vec<Force>,
    /// The mass matrix, the rows of each of its columns that can be non-zero, and M N.
    mass: DMatrix<f64>,
    mass_rows: Vec<Vec<usize>>,
    mass_null: DMatrix<f64>,
}

impl ReducedInertia {
    pub fn new(model: &Model) -> ReducedInertia {
        let mass_rows = mass_rows(model);
        ReducedInertia {
            passes_up_to: passes_up_to(model, &mass_rows),
            motions: Vec::new(),
            momenta: Vec::new(),
            mass: DMatrix::zeros(model.nv, model.nv),
            mass_rows,
            mass_null: DMatrix::zeros(model.nv, 0),
        }
    }

    /// NᵀMN of the first `count` columns of `null` (over the state's velocities; only the
    /// tree's meet M) into the leading count × count block of `reduced`, by passes when `kept`
    /// (the motions every evaluation solves on, which decide the method, so that it is the same
    /// at every evaluation) is small enough. `data` holds the forward kinematics of the state.
    pub fn reduced_mass_into(
        &mut self,
        model: &Model,
        data: &mut Data,
        null: &DMatrix<f64>,
        count: usize,
        kept: usize,
        reduced: &mut DMatrix<f64>,
    ) {
        if kept <= self.passes_up_to {
            self.by_passes(model, data, null, count, reduced);
        } else {
            self.from_mass_matrix(model, data, null, count, reduced);
        }
    }

    fn by_passes(
        &mut self,
        model: &Model,
        data: &Data,
        null: &DMatrix<f64>,
        count: usize,
        reduced: &mut DMatrix<f64>,
    ) {
        let bodies = model.body_count() + 1;
        self.motions.resize(bodies * count, Motion::zeros());
        self.momenta.resize(bodies * count, Force::zeros());
        for k in 0..count {
            let motions = &mut self.motions[k * bodies..(k + 1) * bodies];
            body_motions(model, data, &null.column(k).as_slice()[..model.nv], motions);
            for &j in &model.dynamic_joints {
                let i = model.joints[j].child;
                let body = &model.dynamic_bodies[i - 1];
                self.momenta[k * bodies + i] = if body.massless {
                    Force::zeros()
                } else {
                    body.rigid.times(&motions[i])
                };
            }
        }
        for k in 0..count {
            for l in 0..=k {
                let value = model.dynamic_joints.iter().fold(0.0, |sum, &j| {
                    let i = model.joints[j].child;
                    sum + self.motions[l * bodies + i].dot(&self.momenta[k * bodies + i])
                });
                reduced[(k, l)] = value;
                reduced[(l, k)] = value;
            }
        }
    }

    fn from_mass_matrix(
        &mut self,
        model: &Model,
        data: &mut Data,
        null: &DMatrix<f64>,
        count: usize,
        reduced: &mut DMatrix<f64>,
    ) {
        crba_after_kinematics(model, data, &mut self.mass);
        let nv = model.nv;
        if self.mass_null.ncols() < count {
            self.mass_null = DMatrix::zeros(nv, count);
        }
        // Column by column (matrix-vector products): a matrix product would pack its operands
        // into buffers it allocates on every call.
        for k in 0..count {
            let motion = null.column(k);
            let mut product = self.mass_null.column_mut(k);
            let x = &motion.as_slice()[..nv];
            mass_times(&self.mass, &self.mass_rows, x, product.as_mut_slice());
        }
        for k in 0..count {
            for i in 0..count {
                let motion = null.view((0, i), (nv, 1));
                reduced[(i, k)] = motion.dot(&self.mass_null.column(k));
            }
        }
    }
}

/// Up to how many motions the passes cost less than the mass matrix: a pass costs about one
/// motion transform and one momentum per body, the composite-rigid-body algorithm about as
/// much per body plus one product per entry of M's lower triangle, and each motion's product
/// with M one per entry again.
fn passes_up_to(model: &Model, mass_rows: &[Vec<usize>]) -> usize {
    let bodies = model.dynamic_joints.len().max(1);
    let entries = mass_rows
        .iter()
        .enumerate()
        .map(|(column, rows)| rows.iter().filter(|&&row| row <= column).count())
        .sum::<usize>();
    (bodies + entries) / bodies
}
