//! The dynamics at many states given as rows of flat arrays (a NumPy array of N states, row
//! after row): RNEA, CRBA, ABA and the bodies' Jacobians, each quantity alone, one state after
//! another on one scratch, with no per-state allocation of the caller's. The numbers are those
//! of `lsdc eval` (`batch.rs`), computed by the same functions in the same order: the program's
//! efforts at time 0 included, the angles of spherical and free joints recovered from the
//! prepared start.
//!
//! A state that cannot be evaluated stops the batch with its index (from 0) and the reason:
//! its input (lengths, a number that is not finite, a quaternion that is not unit), or the
//! quantity itself (ABA where the mass matrix is singular).

use super::batch::{check_length, check_state, forward_dynamics, inverse_dynamics, StateError};
use super::batch::{position_names, StatesError};
use crate::dynamics::algorithms::{crba, forward_kinematics};
use crate::dynamics::loops::Stabilisation;
use crate::prepare::Prepared;
use crate::simulate::system::MechanicalSystem;
use crate::spatial::Motion;

/// The dynamics of one prepared mechanism at states given as arrays: the scratch of its
/// evaluations, reused from state to state.
pub struct StateBatch<'p> {
    system: MechanicalSystem<'p>,
    /// The bodies' motions for one unit velocity (the Jacobians' columns), reused.
    motions: Vec<Motion>,
}

/// The rows of a flat array of `width` columns, after checking it divides into them.
fn rows<'a>(
    quantity: &'static str,
    values: &'a [f64],
    width: usize,
    count: usize,
) -> Result<std::slice::Chunks<'a, f64>, StatesError> {
    if values.len() != width * count {
        let error = StateError::Length {
            quantity,
            given: values.len() / count.max(1),
            expected: width,
        };
        return Err(StatesError::State { index: 0, error });
    }
    // A zero-width row (a mechanism without velocities) still counts as a row per state.
    Ok(values.chunks(width.max(1)))
}

impl<'p> StateBatch<'p> {
    /// The dynamics of `prepared`'s model (the tree of a mechanism with loops, as `lsdc eval`).
    pub fn new(prepared: &'p Prepared) -> StateBatch<'p> {
        let model = &prepared.model;
        let reference = prepared.coordinates.clone();
        StateBatch {
            system: MechanicalSystem::new(model, reference, Stabilisation::None),
            motions: vec![Motion::zeros(); model.body_count() + 1],
        }
    }

    /// The number of positions (q's entries), of velocities (v's), and their names.
    pub fn dimensions(&self) -> (usize, usize) {
        (self.system.model.nq, self.system.model.nv)
    }

    /// The names of q's entries, as `lsdc eval` gives them.
    pub fn position_names(&self) -> Vec<String> {
        position_names(self.system.model)
    }

    /// The names of v's entries (and of a's, τ's and the mass matrix's rows).
    pub fn velocity_names(&self) -> Vec<String> {
        let model = self.system.model;
        (0..model.nv).map(|i| model.velocity_name(i)).collect()
    }

    /// The names of the bodies, in the order of [`StateBatch::jacobians`]' `body` index.
    pub fn body_names(&self) -> &[String] {
        &self.system.model.body_names
    }

    /// Inverse dynamics at `count` states: `q` (count × nq), `v` and `a` (count × nv), row
    /// after row; the generalised forces into `tau` (count × nv).
    pub fn rnea(
        &mut self,
        count: usize,
        (q, v, a): (&[f64], &[f64], &[f64]),
        tau: &mut [f64],
    ) -> Result<(), StatesError> {
        let (nq, nv) = self.dimensions();
        let states = (rows("q", q, nq, count)?.zip(rows("v", v, nv, count)?))
            .zip(rows("a", a, nv, count)?)
            .zip(tau.chunks_mut(nv.max(1)));
        for (index, (((q, v), a), out)) in states.enumerate() {
            let at = |error| StatesError::State { index, error };
            check_state(self.system.model, q, v).map_err(at)?;
            check_length("a", a, nv).map_err(at)?;
            let found = self.with_efforts(q, v, "rnea", |system, efforts| {
                inverse_dynamics(system, q, v, a, efforts)
            });
            out.copy_from_slice(&found.map_err(at)?);
        }
        Ok(())
    }

    /// Forward dynamics at `count` states: `q` (count × nq), `v` and `tau` (count × nv), row
    /// after row; the accelerations into `a` (count × nv).
    pub fn aba(
        &mut self,
        count: usize,
        (q, v, tau): (&[f64], &[f64], &[f64]),
        a: &mut [f64],
    ) -> Result<(), StatesError> {
        let (nq, nv) = self.dimensions();
        let states = (rows("q", q, nq, count)?.zip(rows("v", v, nv, count)?))
            .zip(rows("tau", tau, nv, count)?)
            .zip(a.chunks_mut(nv.max(1)));
        for (index, (((q, v), tau), out)) in states.enumerate() {
            let at = |error| StatesError::State { index, error };
            check_state(self.system.model, q, v).map_err(at)?;
            check_length("tau", tau, nv).map_err(at)?;
            let found = self.with_efforts(q, v, "aba", |system, efforts| {
                forward_dynamics(system, q, v, tau, efforts)
            });
            out.copy_from_slice(&found.map_err(at)?);
        }
        Ok(())
    }

    /// The mass matrix at `count` positions `q` (count × nq), into `mass` (count × nv × nv,
    /// each matrix by rows).
    pub fn crba(&mut self, count: usize, q: &[f64], mass: &mut [f64]) -> Result<(), StatesError> {
        let (nq, nv) = self.dimensions();
        let zero = vec![0.0; nv];
        let states = rows("q", q, nq, count)?.zip(mass.chunks_mut((nv * nv).max(1)));
        for (index, (q, out)) in states.enumerate() {
            let at = |error| StatesError::State { index, error };
            check_state(self.system.model, q, &zero).map_err(at)?;
            let model = self.system.model;
            let matrix = crba(model, &mut self.system.scratch.data, q)
                .map_err(|e| at(StateError::Geometry(e.into())))?;
            for (r, row) in out.chunks_mut(nv.max(1)).enumerate().take(nv) {
                for (c, entry) in row.iter_mut().enumerate() {
                    *entry = matrix[(r, c)];
                }
            }
        }
        Ok(())
    }

    /// The Jacobian of body `body` (an index into [`StateBatch::body_names`]) at `count`
    /// positions `q` (count × nq), into `jacobian` (count × 6 × nv, by rows): column j is the
    /// body's spatial velocity when velocity j is 1 and the others 0, in the body's own frame,
    /// angular velocity first, then the velocity of the body's origin (Featherstone's body
    /// Jacobian; Pinocchio's `LOCAL` frame).
    pub fn jacobians(
        &mut self,
        count: usize,
        q: &[f64],
        body: usize,
        jacobian: &mut [f64],
    ) -> Result<(), StatesError> {
        let (nq, nv) = self.dimensions();
        let zero = vec![0.0; nv];
        let mut unit = vec![0.0; nv];
        let states = rows("q", q, nq, count)?.zip(jacobian.chunks_mut((6 * nv).max(1)));
        for (index, (q, out)) in states.enumerate() {
            let at = |error| StatesError::State { index, error };
            check_state(self.system.model, q, &zero).map_err(at)?;
            let model = self.system.model;
            forward_kinematics(model, &mut self.system.scratch.data, q, &zero)
                .map_err(|e| at(StateError::Geometry(e.into())))?;
            for j in 0..nv {
                unit[j] = 1.0;
                self.unit_motions(&unit);
                unit[j] = 0.0;
                let column = &self.motions[body + 1];
                for (r, entry) in column.iter().enumerate() {
                    out[r * nv + j] = *entry;
                }
            }
        }
        Ok(())
    }

    /// Every body's motion in its own frame when the joints move with velocities `x`, from the
    /// joint states of the forward kinematics (every joint, massless bodies' too): one pass out
    /// from the root, v_i = X_i v_parent + S_i x_i (Featherstone, "Rigid Body Dynamics
    /// Algorithms", 2008, §4.1).
    fn unit_motions(&mut self, x: &[f64]) {
        let (model, data) = (self.system.model, &self.system.scratch.data);
        self.motions[0] = Motion::zeros();
        for (k, joint) in model.joints.iter().enumerate() {
            let state = &data.states[k];
            let own = state
                .subspace
                .apply(&x[joint.v_offset..joint.v_offset + joint.nv()]);
            let parent = state
                .transform
                .motion_to_child(&self.motions[joint.dynamic_parent]);
            self.motions[joint.child] = parent + own;
        }
    }

    /// `quantity` computed from the program's efforts at (q, v) (at time 0, as `lsdc eval`),
    /// which leave the forward kinematics of the state in the scratch.
    fn with_efforts(
        &mut self,
        q: &[f64],
        v: &[f64],
        quantity: &'static str,
        compute: impl FnOnce(
            &mut MechanicalSystem<'p>,
            &crate::dynamics::efforts::Efforts,
        ) -> Result<Vec<f64>, crate::simulate::system::SystemError>,
    ) -> Result<Vec<f64>, StateError> {
        let model = self.system.model;
        let q_full = [q, &vec![0.0; model.nc]].concat();
        let v_full = [v, &vec![0.0; model.nc]].concat();
        let unavailable = |error| StateError::Unavailable { quantity, error };
        let efforts = self.system.efforts(0.0, &q_full, &v_full);
        let efforts = efforts.map_err(unavailable)?;
        compute(&mut self.system, &efforts).map_err(unavailable)
    }
}
