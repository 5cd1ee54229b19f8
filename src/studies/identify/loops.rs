//! The state of a mechanism with closed loops from its measured independent coordinates, and
//! the projection of its inverse dynamics on them, for `lsdc identify`.
//!
//! With u the coordinates whose efforts are measured (the actuated ones, which must be
//! independent coordinates of the loops) and p the others, the loops' rows φ(q) = 0 and their
//! rates G v = 0, G = [G_u G_p], give at each sample: the passive positions by Gauss–Newton on
//! φ from the previous sample's (minimum-norm steps δ_p = −G_p⁺ φ, u held), then the
//! velocities v_p = −G_p⁺ G_u u̇ and accelerations v̇_p = −G_p⁺ (G_u ü + γ), γ = Ġ v. The
//! velocities the loops allow are v = X u̇ with X = [I; −G_p⁺ G_u] (E X = I, G X = 0), and
//! premultiplying M v̇ + h = Eᵀ τ + Gᵀ λ by Xᵀ leaves τ = Xᵀ (M v̇ + h) (the reduced model of
//! `dynamics::reduced_model`, the seed's Z and M): the efforts of the actuated coordinates are
//! Xᵀ times RNEA's along the tree, and so linear in the bodies' inertial parameters with the
//! regressor's columns projected, Xᵀ Y. Khalil & Dombre, Modeling, Identification and Control
//! of Robots (2002), §12.6, identify closed-loop robots so.

use nalgebra::{DMatrix, DVector};

use crate::dynamics::algorithms::{forward_kinematics, Data};
use crate::dynamics::loops::{constraints_into, Constraints, Extent};
use crate::dynamics::model::Model;
use crate::linalg::svd;
use crate::simulate::system::SystemError;

/// Gauss–Newton on the passive positions stops when the rows' largest residual is at most
/// this (lengths in the model's units, rotations in radians), or after `NEWTON_STEPS` steps.
const CLOSED: f64 = 1e-13;
const NEWTON_STEPS: usize = 30;

/// Singular values of G_p at most this fraction of the largest are zero: the measured
/// coordinates then do not determine the others.
const RANK_FLOOR: f64 = 1e-9;

/// The loops' state at the samples, and where the last one closed.
pub struct LoopState {
    /// The velocities whose efforts are measured (u), and the others (p).
    actuated: Vec<usize>,
    passive: Vec<usize>,
    constraints: Constraints,
    /// The positions of the last sample: where the next one's Gauss–Newton starts.
    q: Vec<f64>,
}

/// The full state at one sample and X.
pub struct ClosedSample {
    pub q: Vec<f64>,
    pub v: Vec<f64>,
    pub a: Vec<f64>,
    /// X, the state's velocities × actuated: the velocities the loops allow per actuated rate.
    pub motions: DMatrix<f64>,
}

impl LoopState {
    /// From the program's closed start `start` (the state's positions: the tree's, then the
    /// complementary links'), for the measured velocities `actuated`.
    pub fn new(model: &Model, start: &[f64], actuated: &[usize]) -> LoopState {
        LoopState {
            actuated: actuated.to_vec(),
            passive: (0..model.velocities()).filter(|v| !actuated.contains(v)).collect(),
            constraints: Constraints::new(model),
            q: start.to_vec(),
        }
    }

    /// The closed state with the actuated coordinates' measured positions, rates and
    /// accelerations (`u`, each nv long: only the actuated entries are read): the state's
    /// positions, velocities and accelerations (the complementary links' after the tree's),
    /// X over the state's velocities.
    pub fn close(
        &mut self,
        model: &Model,
        data: &mut Data,
        u: (&[f64], &[f64], &[f64]),
    ) -> Result<ClosedSample, String> {
        let (n, m) = (model.velocities(), self.actuated.len());
        let mut q = self.q.clone();
        for &i in &self.actuated {
            q[i] = u.0[i];
        }
        let zero = vec![0.0; n];
        let mut residual = f64::INFINITY;
        for _ in 0..NEWTON_STEPS {
            forward_kinematics(model, data, &q, &zero).map_err(|e| SystemError::from(e).to_string())?;
            constraints_into(model, data, &q, &zero, Extent::Rows, &mut self.constraints)
                .map_err(|e| SystemError::from(e).to_string())?;
            residual = self.constraints.residual.amax();
            if residual <= CLOSED {
                break;
            }
            let g = self.constraints.jacobian.dense();
            let inverse = self.passive_inverse(&g)?;
            let step = -(inverse * &self.constraints.residual);
            for (k, &i) in self.passive.iter().enumerate() {
                q[i] += step[k];
            }
        }
        if residual > 1e3 * CLOSED {
            return Err(format!(
                "the loops do not close at the measured coordinates (a residual of {residual:.1e} is left)"
            ));
        }
        let g = self.constraints.jacobian.dense();
        let inverse = self.passive_inverse(&g)?;
        let g_u = g.select_columns(&self.actuated);
        // X = [I; −G_p⁺ G_u], by the velocities' order.
        let coupling = -(&inverse * &g_u);
        let mut motions = DMatrix::zeros(n, m);
        for (k, &i) in self.actuated.iter().enumerate() {
            motions[(i, k)] = 1.0;
        }
        for (k, &i) in self.passive.iter().enumerate() {
            motions.row_mut(i).copy_from(&coupling.row(k));
        }
        let rates = DVector::from_iterator(m, self.actuated.iter().map(|&i| u.1[i]));
        let v: Vec<f64> = (&motions * &rates).iter().copied().collect();
        forward_kinematics(model, data, &q, &v).map_err(|e| SystemError::from(e).to_string())?;
        constraints_into(model, data, &q, &v, Extent::WithBias, &mut self.constraints)
            .map_err(|e| SystemError::from(e).to_string())?;
        let accelerations = DVector::from_iterator(m, self.actuated.iter().map(|&i| u.2[i]));
        let passive = -(&inverse * (&g_u * &accelerations + &self.constraints.bias));
        let mut a = vec![0.0; n];
        for (k, &i) in self.actuated.iter().enumerate() {
            a[i] = accelerations[k];
        }
        for (k, &i) in self.passive.iter().enumerate() {
            a[i] = passive[k];
        }
        self.q.clone_from(&q);
        Ok(ClosedSample { q, v, a, motions })
    }

    /// G_p⁺, refused where G_p loses rank (the measured coordinates leave a motion free).
    fn passive_inverse(&self, g: &DMatrix<f64>) -> Result<DMatrix<f64>, String> {
        let g_p = g.select_columns(&self.passive);
        let decomposition = svd(g_p, true, true).ok_or("the loops' rows are not finite")?;
        let values = &decomposition.singular_values;
        let floor = RANK_FLOOR * values.max();
        let rank = values.iter().filter(|&&s| s > floor).count();
        if rank < self.passive.len() {
            return Err(format!(
                "the measured efforts' coordinates do not determine the others: the loops leave {} motion{} of the mechanism free with them held; measure the efforts of independent coordinates (the actuated ones)",
                self.passive.len() - rank,
                if self.passive.len() - rank == 1 { "" } else { "s" }
            ));
        }
        decomposition
            .pseudo_inverse(floor)
            .map_err(|e| e.to_string())
    }
}
