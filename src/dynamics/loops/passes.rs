//! The kinetic energy's bilinear form among a few joint motions without the mass matrix: one
//! pass out over the bodies per motion gives each body's motion under it (`body_motions`), and
//! xᵀMy = Σᵢ vᵢ(x)ᵀ Iᵢ vᵢ(y) + Σ_r J_r s_r(x) s_r(y) over the bodies and the geared rotors
//! (s_r a rotor's spin rate). Each pass costs one motion transform and one momentum per body,
//! where the mass matrix of the composite-rigid-body algorithm costs an entry per pair of
//! velocities on a branch (Featherstone, Rigid Body Dynamics Algorithms, 2008, §6.2): a
//! serial chain's n², and a product with it as many again.

use nalgebra::DMatrix;

use crate::dynamics::algorithms::{body_motions, rotor_spin, Data};
use crate::dynamics::model::Model;
use crate::dynamics::rotors::Rotor;
use crate::spatial::{Force, Motion};

/// The passes' body motions and the bodies' momenta under them, one block of bodies + 1 per
/// motion, kept between calls so that they allocate nothing once sized.
#[derive(Default)]
pub struct BodyPasses {
    motions: Vec<Motion>,
    momenta: Vec<Force>,
}

impl BodyPasses {
    /// The passes of the first `count` columns of `columns` (their first nv entries, the tree's
    /// velocities), `data` holding the joints' transforms at q.
    pub fn take(&mut self, model: &Model, data: &Data, columns: &DMatrix<f64>, count: usize) {
        let bodies = model.body_count() + 1;
        self.motions.resize(bodies * count, Motion::zeros());
        self.momenta.resize(bodies * count, Force::zeros());
        for k in 0..count {
            let motion = columns.column(k);
            let motions = &mut self.motions[k * bodies..(k + 1) * bodies];
            body_motions(model, data, &motion.as_slice()[..model.nv], motions);
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
    }

    /// Body i's motion under pass k.
    pub fn motion(&self, model: &Model, k: usize, i: usize) -> &Motion {
        &self.motions[k * (model.body_count() + 1) + i]
    }

    /// The kinetic energy's bilinear form between passes k and l, of the same `columns` as
    /// `take`: the bodies' share, then the geared rotors'.
    pub fn form(&self, model: &Model, columns: &DMatrix<f64>, k: usize, l: usize) -> f64 {
        let bodies = model.body_count() + 1;
        let of_bodies = model.dynamic_joints.iter().fold(0.0, |sum, &j| {
            let i = model.joints[j].child;
            sum + self.motions[l * bodies + i].dot(&self.momenta[k * bodies + i])
        });
        let spin = |m: usize, rotor: &Rotor| {
            let motions = &self.motions[m * bodies..(m + 1) * bodies];
            rotor_spin(rotor, motions, columns[(rotor.velocity, m)])
        };
        let of_rotors: f64 = (model.rotors.iter())
            .map(|r| r.inertia * spin(k, r) * spin(l, r))
            .sum();
        of_bodies + of_rotors
    }
}

/// Up to how many motions the passes cost less than the mass matrix: a pass costs about one
/// motion transform and one momentum per body, the composite-rigid-body algorithm about as
/// much per body plus one product per entry of M's lower triangle, and each motion's product
/// with M one per entry again. `mass_rows` lists the rows of each column of M that can be
/// non-zero (`mass_rows`).
pub fn passes_up_to(model: &Model, mass_rows: &[Vec<usize>]) -> usize {
    let bodies = model.dynamic_joints.len().max(1);
    let entries = mass_rows
        .iter()
        .enumerate()
        .map(|(column, rows)| rows.iter().filter(|&&row| row <= column).count())
        .sum::<usize>();
    (bodies + entries) / bodies
}
