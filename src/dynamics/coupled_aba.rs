//! A tree's mimic couplings on the articulated-body algorithm's accelerations, without the mass
//! matrix: the couplings' forces by the range-space method (Featherstone, "Rigid Body Dynamics
//! Algorithms", 2008, §8.5). Each coupling q_f = m q_l + o is the acceleration row
//! E_k a = a_f − m a_l = 0; with a₀ the accelerations ABA gives without the couplings,
//!
//!   a = a₀ + M⁻¹Eᵀλ,   (E M⁻¹ Eᵀ) λ = −E a₀,
//!
//! the same accelerations as the eliminated form S (SᵀMS)⁻¹ Sᵀ (τ − b) of `mimics` (the
//! couplings' forces are what the elimination leaves out), to round-off. Each column M⁻¹Eᵀ e_k
//! is two passes over the joints on the articulated inertias ABA left (`mass_solve_after_aba`),
//! where the eliminated form costs the mass matrix, the bias forces and a dense factor: on
//! Panda (two fingers coupled) an evaluation by CRBA, RNEA and SᵀMS took 35 k instructions
//! against ABA's 18 k.
//!
//! The follower's acceleration is then set to m times its leader's, as the elimination gives
//! it: q_f − m q_l − o is a linear invariant of the equations of motion only while the
//! accelerations keep the coupling exactly, which the round-off of λ would not.

use nalgebra::{DMatrix, DVector};

use super::algorithms::mass_solve::{mass_solve_after_aba, MassSolveScratch};
use super::algorithms::Data;
use super::dense::Factor;
use super::model::Model;

/// What `couple_after_aba` keeps between evaluations: one unit force Eᵀe_k, the responses
/// M⁻¹Eᵀ (a column per coupling), E M⁻¹ Eᵀ, its factor, λ and the passes' storage.
#[derive(Clone, Debug)]
pub struct CouplingScratch {
    force: Vec<f64>,
    responses: DMatrix<f64>,
    coupling: DMatrix<f64>,
    factor: Factor,
    multipliers: DVector<f64>,
    passes: MassSolveScratch,
}

impl CouplingScratch {
    pub fn new(model: &Model) -> CouplingScratch {
        let couplings = model.mimics.len();
        CouplingScratch {
            force: vec![0.0; model.nv],
            responses: DMatrix::zeros(model.nv, couplings),
            coupling: DMatrix::zeros(couplings, couplings),
            factor: Factor::new(couplings),
            multipliers: DVector::zeros(couplings),
            passes: MassSolveScratch::default(),
        }
    }
}

/// Adds the couplings' forces to the accelerations `a` (the tree's velocities first) that ABA
/// gave at the configuration `data` holds, its articulated inertias still there. False where
/// E M⁻¹ Eᵀ is not positive definite (a coupled motion without inertia). Not for a model with
/// geared rotors (ABA's passes take their joints by other steps).
pub fn couple_after_aba(
    model: &Model,
    data: &Data,
    a: &mut [f64],
    scratch: &mut CouplingScratch,
) -> bool {
    let nv = model.nv;
    let row = |x: &[f64], k: usize| {
        let mimic = &model.mimics[k];
        x[mimic.velocity] - mimic.multiplier * x[mimic.leader_velocity]
    };
    for (k, mimic) in model.mimics.iter().enumerate() {
        scratch.force.fill(0.0);
        scratch.force[mimic.velocity] = 1.0;
        scratch.force[mimic.leader_velocity] -= mimic.multiplier;
        let response = &mut scratch.responses.as_mut_slice()[k * nv..(k + 1) * nv];
        mass_solve_after_aba(model, data, &scratch.force, response, &mut scratch.passes);
    }
    let couplings = model.mimics.len();
    for k in 0..couplings {
        let response = &scratch.responses.as_slice()[k * nv..(k + 1) * nv];
        for i in 0..couplings {
            scratch.coupling[(i, k)] = row(response, i);
        }
        scratch.multipliers[k] = -row(a, k);
    }
    if !scratch.factor.factor(&scratch.coupling) {
        return false;
    }
    scratch.factor.solve_vector_mut(&mut scratch.multipliers);
    for (k, &lambda) in scratch.multipliers.iter().enumerate() {
        let response = &scratch.responses.as_slice()[k * nv..(k + 1) * nv];
        for (a, r) in a.iter_mut().zip(response) {
            *a += r * lambda;
        }
    }
    for mimic in &model.mimics {
        a[mimic.velocity] = mimic.multiplier * a[mimic.leader_velocity];
    }
    true
}
