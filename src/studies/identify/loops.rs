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

use crate::dynamics::algorithms::{crba, forward_kinematics, Data};
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

/// A motion is without mass when its kinetic energy at unit rate (nᵀ M n, n of unit length) is
/// at most this fraction of M's largest diagonal entry: round-off of a zero.
const MASSLESS: f64 = 1e-12;

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
            passive: (0..model.velocities())
                .filter(|v| !actuated.contains(v))
                .collect(),
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
            let position = (model.position_of(i))
                .ok_or("a measured coordinate is not a coordinate of its own (a ball or free joint's rate)")?;
            q[position] = u.0[i];
        }
        let zero = vec![0.0; n];
        let mut residual = f64::INFINITY;
        let mut step = vec![0.0; n];
        for _ in 0..NEWTON_STEPS {
            forward_kinematics(model, data, &q, &zero)
                .map_err(|e| SystemError::from(e).to_string())?;
            constraints_into(model, data, &q, &zero, Extent::Rows, &mut self.constraints)
                .map_err(|e| SystemError::from(e).to_string())?;
            residual = self.constraints.residual.amax();
            if residual <= CLOSED {
                break;
            }
            let g = self.constraints.jacobian.dense();
            let inverse = self.passive_inverse(model, data, (&q, Closed::No), &g)?;
            let passive_step = -(inverse * &self.constraints.residual);
            for (k, &i) in self.passive.iter().enumerate() {
                step[i] = passive_step[k];
            }
            // A ball joint's step is a rotation: its quaternion moves along it.
            model.retract(&mut q, &step);
        }
        if residual > 1e3 * CLOSED {
            return Err(format!(
                "the loops do not close at the measured coordinates (a residual of {residual:.1e} is left)"
            ));
        }
        let g = self.constraints.jacobian.dense();
        let inverse = self.passive_inverse(model, data, (&q, Closed::Yes), &g)?;
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

    /// G_p⁺, refused where G_p loses rank along a motion with mass (the measured coordinates
    /// leave a motion free). A motion without mass (a rod's spin about its own axis between two
    /// ball joints, its inertia about the axis zero) is left out: G_p⁺ gives it no rate, and
    /// whatever its rate, it changes no effort. Whether the free motions have mass is decided
    /// at the closed configuration: on the way there (Gauss–Newton's steps, minimum-norm) the
    /// rows' null space mixes them with motions of the closure's error.
    fn passive_inverse(
        &self,
        model: &Model,
        data: &mut Data,
        (q, closed): (&[f64], Closed),
        g: &DMatrix<f64>,
    ) -> Result<DMatrix<f64>, String> {
        let g_p = g.select_columns(&self.passive);
        let decomposition = svd(g_p.clone(), true, true).ok_or("the loops' rows are not finite")?;
        let values = &decomposition.singular_values;
        let floor = RANK_FLOOR * values.max();
        let rank = values.iter().filter(|&&s| s > floor).count();
        let free = self.passive.len() - rank;
        let with_mass = match (free, closed) {
            (0, _) | (_, Closed::No) => 0,
            (_, Closed::Yes) => self.free_with_mass(model, data, q, &g_p, floor)?,
        };
        if with_mass > 0 {
            return Err(format!(
                "the measured efforts' coordinates do not determine the others: the loops leave {with_mass} motion{} with mass free with them held; measure the efforts of independent coordinates (the actuated ones)",
                if with_mass == 1 { "" } else { "s" }
            ));
        }
        decomposition
            .pseudo_inverse(floor)
            .map_err(|e| e.to_string())
    }

    /// How many of the passive motions G_p leaves free have mass: the rank of M restricted to
    /// them, Nᵀ M N, N their basis (G_p's right singular vectors of singular values at most
    /// `floor`, from the SVD of G_p squared with zero rows: a thin SVD of a wide G_p leaves its
    /// null space out), its eigenvalues above round-off of M's largest diagonal entry.
    fn free_with_mass(
        &self,
        model: &Model,
        data: &mut Data,
        q: &[f64],
        g_p: &DMatrix<f64>,
        floor: f64,
    ) -> Result<usize, String> {
        let p = self.passive.len();
        let mut square = DMatrix::zeros(g_p.nrows().max(p), p);
        square.rows_mut(0, g_p.nrows()).copy_from(g_p);
        let decomposition = svd(square, false, true).ok_or("the loops' rows are not finite")?;
        let v_t = decomposition
            .v_t
            .ok_or("the loops' rows have no right singular vectors")?;
        let free: Vec<usize> = (decomposition.singular_values.iter().enumerate())
            .filter(|(_, &s)| s <= floor)
            .map(|(k, _)| k)
            .collect();
        // N over the tree's velocities: the complementary links' coordinates carry no mass.
        let mut basis = DMatrix::zeros(model.nv, free.len());
        for (column, &k) in free.iter().enumerate() {
            for (j, &i) in self.passive.iter().enumerate() {
                if i < model.nv {
                    basis[(i, column)] = v_t[(k, j)];
                }
            }
        }
        let mass =
            crba(model, data, &q[..model.nq]).map_err(|e| SystemError::from(e).to_string())?;
        let scale = mass.diagonal().amax();
        let restricted = basis.transpose() * &mass * &basis;
        let energies = restricted.symmetric_eigenvalues();
        Ok(energies.iter().filter(|&&e| e > MASSLESS * scale).count())
    }
}

/// Whether the loops are closed at the configuration G is taken at.
#[derive(Clone, Copy, PartialEq)]
enum Closed {
    Yes,
    No,
}
