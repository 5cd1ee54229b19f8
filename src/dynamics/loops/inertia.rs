//! The reduced equations of the allowed motions N, (NᵀMN) z = Nᵀ(f − Ma₀), formed the cheaper
//! way the tree's structure allows. A closed mechanism has few allowed motions (one for a row
//! of four-bars, three on the Delta): then one pass over the bodies per motion gives each
//! body's motion under it, NᵀMN is the kinetic energy's bilinear form Σ vᵢᵀIᵢwᵢ, and Nᵀ(f − Ma₀)
//! is Nᵀτ less the power of the bodies' forces of inverse dynamics at a₀ along each motion, so
//! that neither the mass matrix nor inverse dynamics' pass back is needed. With many allowed
//! motions, the mass matrix of the composite-rigid-body algorithm (one entry per pair of
//! velocities on a branch) and the generalised forces of inverse dynamics cost less.

use nalgebra::{DMatrix, DVector};

use super::passes::{passes_up_to, BodyPasses};
use crate::dynamics::algorithms::{
    crba_after_kinematics, mass_rows, mass_times, rnea_backward, Data,
};
use crate::dynamics::model::Model;
use crate::dynamics::planar::algebra::{PlanarForce, PlanarMotion};
use crate::dynamics::planar::algorithms::{self as planar, PlanarData};
use crate::dynamics::planar::PlanarModel;

/// What forming the reduced equations keeps between evaluations, so that it allocates nothing
/// once sized.
pub struct ReducedInertia {
    /// Up to how many kept motions the passes are taken (see `passes_up_to`).
    passes_up_to: usize,
    /// The passes: each motion's body motions and the bodies' momenta under it.
    passes: BodyPasses,
    /// The mass matrix, the rows of each of its columns that can be non-zero, M N, inverse
    /// dynamics' generalised forces and f − Ma₀.
    mass: DMatrix<f64>,
    mass_rows: Vec<Vec<usize>>,
    mass_null: DMatrix<f64>,
    inverse: DVector<f64>,
    applied: DVector<f64>,
    /// The passes' body motions in planar form (`planar_by_passes`).
    planar_motions: Vec<PlanarMotion>,
}

/// The reduced equations' two sides, filled by `ReducedInertia::reduced_into`: NᵀMN in the
/// leading count × count block of `mass`, Nᵀ(f − Ma₀) in the first count entries of `force`.
pub struct Reduced<'a> {
    pub mass: &'a mut DMatrix<f64>,
    pub force: &'a mut DVector<f64>,
}

impl ReducedInertia {
    pub fn new(model: &Model) -> ReducedInertia {
        // A tree never forms reduced equations: its scratch holds no mass matrix, whose n²
        // entries (and the rows of its branches) would be most of a long chain's memory.
        let nv = if model.has_loops() { model.nv } else { 0 };
        let mass_rows = match model.has_loops() {
            true => mass_rows(model),
            false => Vec::new(),
        };
        ReducedInertia {
            passes_up_to: passes_up_to(model, &mass_rows),
            passes: BodyPasses::default(),
            mass: DMatrix::zeros(nv, nv),
            mass_rows,
            mass_null: DMatrix::zeros(model.nv, 0),
            inverse: DVector::zeros(model.nv),
            applied: DVector::zeros(model.velocities()),
            planar_motions: Vec::new(),
        }
    }

    /// The reduced equations of the first `count` columns of `null` (over the state's
    /// velocities; only the tree's meet M), with `tau` the efforts' generalised forces (state
    /// length) and `data` holding the forward kinematics and inverse dynamics' pass out at a₀
    /// (`rnea_forward`). By passes when `kept` (the motions every evaluation solves on, which
    /// decide the method, so that it is the same at every evaluation) is small enough. In
    /// planar form with `planar`: the planar model and its scratch, holding the planar
    /// kinematics and pass out.
    #[allow(clippy::too_many_arguments)]
    pub fn reduced_into(
        &mut self,
        model: &Model,
        data: &mut Data,
        null: &DMatrix<f64>,
        (count, kept): (usize, usize),
        tau: &DVector<f64>,
        reduced: Reduced<'_>,
        planar: Option<(&PlanarModel, &mut PlanarData)>,
    ) {
        let by_passes = kept <= self.passes_up_to;
        match planar {
            Some((planar, planar_data)) if by_passes => {
                self.planar_by_passes(model, planar, planar_data, null, count, tau, reduced)
            }
            Some((planar, planar_data)) => {
                planar::rnea_backward(planar, planar_data, &mut self.inverse);
                planar::crba(model, planar, planar_data, &mut self.mass);
                self.reduce_mass_matrix(model, null, count, tau, reduced);
            }
            _ if by_passes => self.by_passes(model, data, null, count, tau, reduced),
            _ => self.with_mass_matrix(model, data, null, count, tau, reduced),
        }
    }

    /// `by_passes` in planar form: the bodies' planar motions under each allowed motion, their
    /// momenta, and the power of the planar forces of inverse dynamics' pass out.
    #[allow(clippy::too_many_arguments)]
    fn planar_by_passes(
        &mut self,
        model: &Model,
        planar: &PlanarModel,
        data: &PlanarData,
        null: &DMatrix<f64>,
        count: usize,
        tau: &DVector<f64>,
        reduced: Reduced<'_>,
    ) {
        let bodies = model.body_count() + 1;
        let motions = &mut self.planar_motions;
        motions.resize(bodies * count, PlanarMotion::zeros());
        for k in 0..count {
            let motion = null.column(k);
            let own = &mut motions[k * bodies..(k + 1) * bodies];
            planar::body_motions(planar, data, &motion.as_slice()[..model.nv], own);
            // The power along motion k and its kinetic energy's bilinear form with the motions
            // before it, in one pass over the bodies.
            let mut power = 0.0;
            (0..=k).for_each(|l| reduced.mass[(k, l)] = 0.0);
            for joint in &planar.joints {
                let i = joint.child;
                let momentum = match planar.massless[i - 1] {
                    true => PlanarForce::zeros(),
                    false => planar.bodies[i - 1].times(&motions[k * bodies + i]),
                };
                power += motions[k * bodies + i].dot(&data.force[i]);
                for l in 0..=k {
                    reduced.mass[(k, l)] += motions[l * bodies + i].dot(&momentum);
                }
            }
            (0..k).for_each(|l| reduced.mass[(l, k)] = reduced.mass[(k, l)]);
            reduced.force[k] = motion.dot(tau) - power;
        }
    }

    fn by_passes(
        &mut self,
        model: &Model,
        data: &Data,
        null: &DMatrix<f64>,
        count: usize,
        tau: &DVector<f64>,
        reduced: Reduced<'_>,
    ) {
        self.passes.take(model, data, null, count);
        for k in 0..count {
            let motion = null.column(k);
            let mut power = 0.0;
            for &j in &model.dynamic_joints {
                let i = model.joints[j].child;
                power += self.passes.motion(model, k, i).dot(&data.force[i]);
            }
            // The rotors' torques on their carriers are in the bodies' forces; their own
            // efforts on their coordinates are not.
            for (rotor, own) in model.rotors.iter().zip(data.rotor_efforts()) {
                power += motion[rotor.velocity] * own;
            }
            reduced.force[k] = motion.dot(tau) - power;
        }
        for k in 0..count {
            for l in 0..=k {
                let value = self.passes.form(model, null, k, l);
                reduced.mass[(k, l)] = value;
                reduced.mass[(l, k)] = value;
            }
        }
    }

    fn with_mass_matrix(
        &mut self,
        model: &Model,
        data: &mut Data,
        null: &DMatrix<f64>,
        count: usize,
        tau: &DVector<f64>,
        reduced: Reduced<'_>,
    ) {
        rnea_backward(model, data, &mut self.inverse);
        crba_after_kinematics(model, data, &mut self.mass);
        self.reduce_mass_matrix(model, null, count, tau, reduced);
    }

    /// The reduced equations from the generalised forces of inverse dynamics in `inverse` and
    /// the mass matrix in `mass`.
    fn reduce_mass_matrix(
        &mut self,
        model: &Model,
        null: &DMatrix<f64>,
        count: usize,
        tau: &DVector<f64>,
        reduced: Reduced<'_>,
    ) {
        let nv = model.nv;
        self.applied.copy_from(tau);
        let mut tree = self.applied.rows_mut(0, nv);
        tree -= &self.inverse;
        let motions = null.columns(0, count);
        let mut force = reduced.force.rows_mut(0, count);
        force.gemv_tr(1.0, &motions, &self.applied, 0.0);
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
                reduced.mass[(i, k)] = motion.dot(&self.mass_null.column(k));
            }
        }
    }
}
