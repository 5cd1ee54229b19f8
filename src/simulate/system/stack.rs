//! The run's constraint stack (`dynamics::rows` documents its rows): its one solve,
//! [`MechanicalSystem::solve_stack`], which every evaluation of the run goes through (the
//! integrator's, the sampler's, the stops' event functions, the reactions), and the response X
//! its first block gives the others. The blocks, in their order:
//!
//! 1. the closed loops' kept rows, solved by their sparse factorisation (`dynamics::loops`:
//!    [`MechanicalSystem::solve_loop_block`], in planar form for a planar mechanism's
//!    integrator), the block's specialised solve: the
//!    accelerations under the efforts, the allowed motions N that give X = N (NᵀMN)⁻¹Nᵀ and,
//!    for the reactions, the loops' multipliers from M a − f ([`MechanicalSystem::
//!    loop_block_multipliers`]). A tree has no such block: its X is M⁻¹, or the mimic
//!    couplings' basis S in S (SᵀMS)⁻¹Sᵀ (formed by its base solve where that takes the
//!    mass matrix, `mass_accelerations`, otherwise when rows need it, `form_response_at`);
//! 2. to 4. the contacts' kept rows, the mimic couplings with loops and the coordinates held
//!    (driven, resting on a stop, stuck by friction), solved together on X
//!    (`holding::solve_rows`, `rows::RowStack::solve`).
//!
//! The same blocks serve the positions and velocities after a step (`stacked`: the loops'
//! projection, then steps of the corrector along X onto the other blocks' rows), the impacts
//! (`impacts`: the stop's row below the others on the same X) and the symplectic integrator,
//! whose RATTLE steps solve the first block's factorisation with their own right-hand sides
//! (`variational`, [`MechanicalSystem::loop_block_at`]).

use nalgebra::DVector;

use super::scratch::mass_storage;
use super::{MechanicalSystem, SystemError};
use crate::dynamics::algorithms::{
    crba_after_kinematics, crba_into, forward_kinematics, rnea_after_kinematics, rnea_forward,
};
use crate::dynamics::loops::planar_rows::planar_constraints_into;
use crate::dynamics::loops::{self, Extent, Factored, Stabilisation};
use crate::dynamics::planar::algebra::PlanarForce;
use crate::dynamics::planar::algorithms as planar_algorithms;
use crate::dynamics::planar::PlanarModel;
use crate::spatial::Force;

/// How the loops' block finds the efforts.
enum Effort {
    /// Evaluated with the forward kinematics of the state, which they leave in `data`.
    Evaluated,
    /// Evaluated on the forward kinematics already in `data`; `loops`: the loops' allowed
    /// motions at the state are in `loop_scratch` for the actuators' laws.
    AfterKinematics { loops: bool },
    /// None: a planar block whose model applies none needs no spatial kinematics.
    Zero,
}

impl MechanicalSystem<'_> {
    /// Solves every constraint row of the run at (t, q, v), block by block (see the module's
    /// documentation), into the accelerations `a`: with loops, their block's (what `a` held is
    /// not read); on a tree, from the accelerations of its base solve in `a`. Records the
    /// contacts' forces, the held forces and the drives' efforts.
    pub(super) fn solve_stack(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
        a: &mut DVector<f64>,
    ) -> Result<(), SystemError> {
        if self.model.has_loops() {
            self.solve_loop_block(t, q, v)?;
            a.copy_from(&self.scratch.loop_scratch.accelerations);
        }
        self.solve_rows(t, q, v, a)
    }

    /// The response X formed at (t, q, v) without the rows' solve (for the projections and
    /// the impacts): with loops, on the allowed motions of their block solved there; on a
    /// tree, M⁻¹ or on the mimic couplings' basis. The forward kinematics of (q, v) are left
    /// in `data`.
    pub(super) fn form_stack_response(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
    ) -> Result<(), SystemError> {
        let model = self.model;
        self.scratch.response_here = false;
        if model.has_loops() {
            self.solve_loop_block(t, q, v)?;
            self.form_response_at(q)?;
            forward_kinematics(model, &mut self.scratch.data, q, v)?;
        } else {
            forward_kinematics(model, &mut self.scratch.data, q, v)?;
            let mass = mass_storage(&mut self.scratch.mass, model.nv);
            crba_after_kinematics(model, &mut self.scratch.data, mass);
            self.form_tree_response()?;
        }
        Ok(())
    }

    /// Forms the response at q when the evaluation did not (`response_here`): with loops, on
    /// the allowed motions of the last solve of their block (which must be at q).
    pub(super) fn form_response_at(&mut self, q: &[f64]) -> Result<(), SystemError> {
        if self.scratch.response_here {
            return Ok(());
        }
        let model = self.model;
        crba_into(
            model,
            &mut self.scratch.data,
            &q[..model.nq],
            mass_storage(&mut self.scratch.mass, model.nv),
        )?;
        if !model.has_loops() {
            return self.form_tree_response();
        }
        let structure = &self.scratch.loops.structure;
        self.scratch.loop_scratch.ensure_motions(structure);
        let motions = self.scratch.loop_scratch.solved_motions();
        self.scratch.response_here = self.scratch.response.on_basis(&self.scratch.mass, motions);
        match self.scratch.response_here {
            true => Ok(()),
            false => Err(SystemError::SingularMassMatrix),
        }
    }

    /// The loops' block: the accelerations and the allowed motions of a mechanism with loops at
    /// (t, q, v) under the efforts (the slipping joints' friction among them), left in
    /// `loop_scratch` with the constraint rows they come from, the efforts in `efforts`;
    /// nothing is allocated once the buffers are sized.
    pub(super) fn solve_loop_block(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
    ) -> Result<(), SystemError> {
        let model = self.model;
        self.scratch.evaluated.clear();
        self.ensure_structure(q)?;
        let stabilisation = self.scratch.loops.stabilisation;
        // Baumgarte's feedback reads the position rows, which the planar rows leave out.
        let baumgarte = matches!(stabilisation, Stabilisation::Baumgarte(_));
        if let Some(planar) = self.planar_here().filter(|_| !baumgarte) {
            return self.solve_planar_loop_block(planar, t, q, v);
        }
        // The forward kinematics of (q, v), which the rows, the efforts and the recursions
        // start from.
        forward_kinematics(model, &mut self.scratch.data, q, v)?;
        let scratch = &mut self.scratch.loop_scratch;
        scratch.choose_method(&self.scratch.loops.structure);
        // Only Baumgarte's feedback reads the position rows.
        let extent = match baumgarte {
            true => Extent::WithBias,
            false => Extent::Motion,
        };
        loops::constraints_into(
            model,
            &mut self.scratch.data,
            q,
            v,
            extent,
            &mut scratch.constraints,
        )?;
        let structure = &self.scratch.loops.structure;
        let allowed = loops::allowed_motions(structure, self.scratch.loops.stabilisation, scratch);
        allowed.map_err(|e| self.loop_error(&e))?;
        // The efforts after the allowed motions: the actuators' laws that read the model in
        // their coordinates take it from them, unless Baumgarte's feedback is in the particular
        // acceleration.
        self.efforts_with_friction(t, (q, v), Effort::AfterKinematics { loops: !baumgarte })?;
        let scratch = &mut self.scratch.loop_scratch;
        if scratch.method() == loops::Method::RangeSpace {
            let external = &self.scratch.efforts.external;
            let tree = loops::Tree::Spatial(&mut self.scratch.data, external);
            let tau = &self.scratch.efforts.tau;
            let structure = &self.scratch.loops.structure;
            let solved = loops::solve_range_space(model, tree, tau, structure, scratch);
            return solved.map_err(|e| self.loop_error(&e));
        }
        // Inverse dynamics' pass out at a₀: the bodies' forces whose power along each allowed
        // motion gives its share of Ma₀ and of the velocity-product forces.
        let scratch = &mut self.scratch.loop_scratch;
        let particular = &scratch.particular()[..model.nv];
        rnea_forward(
            model,
            &mut self.scratch.data,
            particular,
            &self.scratch.efforts.external,
        );
        let tau = &self.scratch.efforts.tau;
        let solve = (&self.scratch.loops.structure, None);
        let solved = loops::solve_reduced(model, &mut self.scratch.data, tau, solve, scratch);
        solved.map_err(|e| self.loop_error(&e))
    }

    /// `solve_loop_block` in the model's planar form: the planar kinematics, the loops' three
    /// rows in the plane each (`loops::planar_rows`), the same solve on the kept rows, and
    /// the reduced equations from the planar recursions. The efforts are evaluated on the
    /// spatial kinematics they read, when the model has any.
    fn solve_planar_loop_block(
        &mut self,
        planar: &PlanarModel,
        t: f64,
        q: &[f64],
        v: &[f64],
    ) -> Result<(), SystemError> {
        let model = self.model;
        let reads_efforts = self.reads_efforts();
        let evaluation = match reads_efforts {
            true => Effort::Evaluated,
            false => Effort::Zero,
        };
        self.efforts_with_friction(t, (q, v), evaluation)?;
        let planar_data = self.scratch.planar.as_deref_mut();
        let planar_data = planar_data.expect("a scratch in planar form has the planar scratch");
        planar_algorithms::kinematics(planar, planar_data, (q, v), true);
        match reads_efforts {
            true => planar_data.set_external(planar, &self.scratch.efforts.external),
            false => planar_data.external.fill(PlanarForce::zeros()),
        }
        let scratch = &mut self.scratch.loop_scratch;
        let state = (q, v);
        planar_constraints_into(model, planar, planar_data, state, &mut scratch.constraints);
        let structure = &self.scratch.loops.structure;
        scratch.choose_method(structure);
        let allowed = loops::allowed_motions(structure, self.scratch.loops.stabilisation, scratch);
        if let Err(e) = allowed {
            return Err(self.loop_error(&e));
        }
        let tau = &self.scratch.efforts.tau;
        if scratch.method() == loops::Method::RangeSpace {
            let tree = loops::Tree::Planar(planar, planar_data);
            let solved = loops::solve_range_space(model, tree, tau, structure, scratch);
            return solved.map_err(|e| self.loop_error(&e));
        }
        let particular = &scratch.particular()[..model.nv];
        planar_algorithms::rnea_forward(planar, planar_data, particular);
        let tau = &self.scratch.efforts.tau;
        let solve = (structure, Some((planar, planar_data)));
        let solved = loops::solve_reduced(model, &mut self.scratch.data, tau, solve, scratch);
        solved.map_err(|e| self.loop_error(&e))
    }

    /// The efforts at (t, q, v) into `efforts`, the slipping joints' friction added to their
    /// generalised forces, as `evaluation` says.
    fn efforts_with_friction(
        &mut self,
        t: f64,
        (q, v): (&[f64], &[f64]),
        evaluation: Effort,
    ) -> Result<(), SystemError> {
        match evaluation {
            Effort::Evaluated => self.evaluate_efforts(t, q, v)?,
            Effort::AfterKinematics { loops } => self.efforts_after_kinematics(t, q, v, loops)?,
            Effort::Zero => {
                let efforts = &mut self.scratch.efforts;
                efforts.tau.fill(0.0);
                if !self.scratch.external_is_zero {
                    efforts.external.fill(Force::zeros());
                    self.scratch.external_is_zero = true;
                }
                efforts.power = 0.0;
            }
        }
        let mut tau = std::mem::take(&mut self.scratch.efforts.tau);
        self.scratch.friction_power = self.add_friction(v, &mut tau);
        self.scratch.efforts.tau = tau;
        Ok(())
    }

    /// The loops' block's multipliers at the accelerations `a` of the whole stack (every row
    /// solved), into `loop_scratch`, from M a − f: inverse dynamics at those accelerations
    /// under the efforts' external forces, less the efforts' generalised forces (the
    /// complementary coordinates, without inertia, get −τ). The other blocks' forces must be
    /// among the efforts (`stack_reactions`); `data` holds the forward kinematics of the
    /// state.
    pub(super) fn loop_block_multipliers(&mut self, a: &DVector<f64>) {
        let model = self.model;
        let scratch = &mut self.scratch.loop_scratch;
        scratch.accelerations.copy_from(a);
        let a = &scratch.accelerations.as_slice()[..model.nv];
        let external = &self.scratch.efforts.external;
        rnea_after_kinematics(
            model,
            &mut self.scratch.data,
            a,
            external,
            &mut self.scratch.inverse,
        );
        self.scratch.force.copy_from(&self.scratch.efforts.tau);
        self.scratch.force.neg_mut();
        let mut tree = self.scratch.force.rows_mut(0, model.nv);
        tree += &self.scratch.inverse;
        loops::multipliers(&self.scratch.force, scratch);
    }

    /// The loops' block at q for a solve with other right-hand sides than the equations of
    /// motion's (the symplectic integrator's RATTLE steps): the position values of every loop
    /// row (6 per loop) and the kept rows (the structure's choice) in their sparse
    /// factorisation. The structure is decided at q if no run decided it.
    pub(in crate::simulate) fn loop_block_at(
        &mut self,
        q: &[f64],
    ) -> Result<(DVector<f64>, Factored), SystemError> {
        self.ensure_structure(q)?;
        let rest = vec![0.0; self.model.velocities()];
        let c = loops::constraints(self.model, &mut self.scratch.data, q, &rest, Extent::Rows)?;
        let factored = Factored::new(&c.jacobian, &self.scratch.loops.structure.choice);
        Ok((c.residual, factored))
    }
}
