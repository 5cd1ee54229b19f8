//! The equations of motion as a first-order system y' = f(t, y), with y = (positions,
//! velocities): positions move with the joint velocities (quaternions included), velocities with
//! the accelerations from the articulated-body algorithm under the efforts (trees), or from the
//! constrained equations M v̇ = f + Gᵀλ, G v̇ + γ = 0 (the loops' block of the constraint
//! stack), then with every other row (contacts, couplings with loops, coordinates held or
//! driven) solved on the response of those accelerations to forces: the whole stack in one
//! call (`stack`, `holding`, `dynamics::rows`).

use nalgebra::DVector;

mod actuated;
mod driven_subtrees;
mod error;
mod friction;
mod held_reactions;
mod holding;
pub mod impacts;
mod jacobian;
mod reference;
pub mod scratch;
pub use error::{NotFiniteCause, SystemError};
mod stack;
mod stacked;
mod states;
mod subtree_run;
mod tangent;

use super::constraints::LoopMonitor;
use super::run_state::RunState;
use crate::dynamics::algorithms::{
    aba_after_kinematics, aba_into, crba_after_kinematics, forward_kinematics,
    rnea_after_kinematics, DynamicsError,
};
use crate::dynamics::contacts;
use crate::dynamics::coupled_aba;
use crate::dynamics::driven_points;
use crate::dynamics::efforts::{evaluate_into, Declared, Efforts};
use crate::dynamics::loops::planar_closure::PlanarClosure;
use crate::dynamics::loops::{self, Extent, LoopError, Stabilisation, StructureError, ROW_NAMES};
use crate::dynamics::model::{Model, Recovered};
use crate::dynamics::planar::algebra::PlanarForce;
use crate::dynamics::planar::{self, PlanarData, PlanarModel};
use crate::integrate::CallbackError;
use crate::prepare::native::NativeDynamics;
use scratch::{mass_storage, Scratch};
use subtree_run::SubtreeRun;

/// The equations of motion of a run: the model (only read), the run's state (`RunState`, what
/// every evaluation reads and the events change), and the scratch of the evaluator in use
/// (`Scratch`); the sampler's own scratch waits in `sampling` while the integrator evaluates.
pub struct MechanicalSystem<'m> {
    pub model: &'m Model,
    pub state: RunState,
    /// Boxed, so that handing it to the outputs and back (`sampling`) moves a pointer.
    pub scratch: Box<Scratch>,
    /// The scratch of the outputs' evaluations (`sampling`), made at their first.
    sampling: Option<Box<Scratch>>,
    /// The forward dynamics as native code (`simulate --compiled`), in place of the efforts
    /// and the articulated-body algorithm.
    native: Option<&'m NativeDynamics>,
    /// The model's planar form, when the right-hand side takes it (`use_planar`).
    planar: Option<&'m PlanarModel>,
    /// The fully driven subtrees, when their drives are run by hybrid dynamics rather than as
    /// rows (`use_driven_subtrees`).
    driven: Option<Box<SubtreeRun<'m>>>,
}

impl<'m> MechanicalSystem<'m> {
    /// The equations of motion of `model` for a run starting at the declared coordinates
    /// `reference`.
    pub fn new(
        model: &'m Model,
        reference: Vec<f64>,
        stabilisation: Stabilisation,
    ) -> MechanicalSystem<'m> {
        MechanicalSystem {
            model,
            state: RunState::new(model, reference),
            scratch: Box::new(Scratch::new(model, stabilisation)),
            sampling: None,
            native: None,
            planar: None,
            driven: None,
        }
    }

    /// Whether an evaluation computes efforts: the program applies some, or a caller set inputs
    /// (`RunState::inputs`: a stepped run's, a linearisation's).
    fn reads_efforts(&self) -> bool {
        self.model.has_efforts() || self.state.inputs.any()
    }

    /// Runs `evaluate` with the outputs' scratch in place of the integrator's: the outputs'
    /// evaluations read and change the same run state, but leave the integrator's caches (its
    /// last evaluation, its kept rows) as its steps left them. The outputs' monitor starts from
    /// the loops' structure as the integrator's stood when it was prepared (`prepare_sampling`), and never sets rows
    /// aside (`LoopMonitor::samples_outputs`).
    pub fn sampling<R>(&mut self, evaluate: impl FnOnce(&mut Self) -> R) -> R {
        self.prepare_sampling();
        let mut scratch = self.sampling.take().expect("prepared");
        std::mem::swap(&mut self.scratch, &mut scratch);
        let result = evaluate(self);
        std::mem::swap(&mut self.scratch, &mut scratch);
        self.sampling = Some(scratch);
        result
    }

    /// Makes the outputs' scratch if it is not made yet, its monitor of the loops from the
    /// integrator's as it stands (a run prepares it once the loops are started).
    pub fn prepare_sampling(&mut self) {
        if self.sampling.is_none() {
            let loops = &self.scratch.loops;
            let mut scratch = Box::new(Scratch::new(self.model, loops.stabilisation));
            scratch.loops = loops.for_outputs();
            let forced = self.scratch.loop_scratch.forced_method();
            scratch.loop_scratch.force_method(forced);
            let closure = self.scratch.projection.plane_closure().cloned();
            scratch.projection.close_in_plane(closure);
            self.sampling = Some(scratch);
        }
    }

    /// Evaluates the loops' translation rows in `planar`, the model's planar form, for the
    /// projections and the residuals they report (`loops::planar_closure`): their round-off
    /// then does not grow with the chain's extent. The right-hand side's form is another
    /// matter (`use_planar`).
    pub fn close_in_plane(&mut self, planar: Option<&PlanarModel>) {
        let closure = planar.and_then(|planar| PlanarClosure::new(self.model, planar));
        if let Some(sampling) = &mut self.sampling {
            sampling.projection.close_in_plane(closure.clone());
        }
        self.scratch.projection.close_in_plane(closure);
    }

    /// Solves the loops by `method` wherever it applies, or by the rule of
    /// `loops::range_space::method_for` with `None` (`Prepared::loop_method`): for comparisons.
    pub fn force_loop_method(&mut self, method: Option<loops::Method>) {
        self.scratch.loop_scratch.force_method(method);
        if let Some(sampling) = &mut self.sampling {
            sampling.loop_scratch.force_method(method);
        }
    }

    /// The method the last evaluation solved the loops by.
    #[cfg_attr(not(lsdc_internals), allow(dead_code))]
    pub fn loop_method(&self) -> loops::Method {
        self.scratch.loop_scratch.method()
    }

    /// Evaluates the accelerations with `native` (checked against this system's own evaluation
    /// by `compiled::attach`) from now on. The power of the non-conservative efforts is then not
    /// computed: it is left at zero.
    pub fn use_native(&mut self, native: Option<&'m NativeDynamics>) {
        self.native = native;
    }

    /// Evaluates the right-hand side in `planar`, the model's planar form
    /// (`dynamics::planar::decide`), from now on, or in the spatial form with `None`: the run's
    /// integrator's evaluations. The outputs' own evaluations, the reactions and the
    /// projections keep the spatial form.
    pub fn use_planar(&mut self, planar: Option<&'m PlanarModel>) {
        self.planar = planar;
        self.scratch.planar = planar.map(|_| Box::new(PlanarData::new(self.model)));
    }

    /// Whether the right-hand side takes the model's planar form.
    pub fn uses_planar(&self) -> bool {
        self.planar_here().is_some()
    }

    /// The planar form the right-hand side takes here: when this scratch has the planar one
    /// and neither native code nor the driven subtrees' hybrid dynamics (spatial algebra)
    /// computes the accelerations instead.
    fn planar_here(&self) -> Option<&'m PlanarModel> {
        let on =
            self.scratch.planar.is_some() && self.native.is_none() && !self.drives_by_subtrees();
        self.planar.filter(|_| on)
    }

    pub fn dimension(&self) -> usize {
        self.model.positions() + self.model.velocities()
    }

    /// Whether the equations of motion do not depend on the time: no effort reads it (an
    /// input's law may).
    pub fn autonomous(&self) -> bool {
        let model = self.model;
        let program =
            !model.has_efforts() || model.effort_tape.as_ref().is_ok_and(|t| !t.reads_time());
        let actuators = model
            .actuation
            .as_ref()
            .is_none_or(|a| !a.tape.reads_time());
        program && actuators && self.state.inputs.law.is_none()
    }

    /// The efforts at (t, q, v); leaves the forward kinematics of (q, v) in `data`.
    pub fn efforts(&mut self, t: f64, q: &[f64], v: &[f64]) -> Result<Efforts, SystemError> {
        self.evaluate_efforts(t, q, v)?;
        Ok(self.scratch.efforts.clone())
    }

    /// The efforts at (t, q, v) into `self.scratch.efforts`, without allocating once its buffers are
    /// sized; leaves the forward kinematics of (q, v) in `data`.
    fn evaluate_efforts(&mut self, t: f64, q: &[f64], v: &[f64]) -> Result<(), SystemError> {
        forward_kinematics(self.model, &mut self.scratch.data, q, v)?;
        self.efforts_after_kinematics(t, q, v, false)
    }

    /// `evaluate_efforts` with the forward kinematics of (q, v) already in `data`;
    /// `loops_solved`: the loops' allowed motions at (q, v) are in `loop_scratch` (the
    /// actuators' laws that read the model in their coordinates take it from them).
    fn efforts_after_kinematics(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
        loops_solved: bool,
    ) -> Result<(), SystemError> {
        let model = self.model;
        let state = &mut self.scratch.declared;
        // An input's law reads every declared coordinate.
        let recovered = match self.state.inputs.law {
            Some(_) => Recovered::Every,
            None => Recovered::ReadByEfforts,
        };
        model.declared_into((t, q, v), &self.state.reference, state, recovered)?;
        let declared = Declared {
            model,
            coordinates: &state.coordinates,
            rates: &state.rates,
            states: &self.state.states,
        };
        self.scratch.external_is_zero = false;
        let efforts = &mut self.scratch.efforts;
        evaluate_into(model, &mut self.scratch.data, &declared, t, efforts)?;
        self.actuate(t, q, v, loops_solved)?;
        let (state, efforts) = (&self.scratch.declared, &mut self.scratch.efforts);
        if self.state.inputs.any() {
            let read = (&state.coordinates[..], &state.rates[..]);
            efforts.power += (self.state.inputs).add_to(t, read, v, &mut efforts.tau);
        }
        Ok(())
    }

    /// Whether this tree's accelerations come from its mass matrix ([`needs_mass_matrix`]), or
    /// from it in the planar form when the tree has mimic couplings (the planar ABA leaves no
    /// articulated inertias to solve their forces on).
    fn needs_mass_matrix(&self) -> bool {
        let model = self.model;
        needs_mass_matrix(model) || (!model.mimics.is_empty() && self.planar_here().is_some())
    }

    /// The accelerations of a tree by the articulated-body algorithm under the efforts (on the
    /// kinematics they were evaluated on; without efforts, on the joints' motions alone), the
    /// joints' viscous friction −c q̇ among the generalised forces (joints without dry friction
    /// have no phases: `needs_mass_matrix`), then the mimic couplings' forces (`coupled_aba`).
    fn articulated_accelerations(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
        accelerations: &mut DVector<f64>,
    ) -> Result<(), SystemError> {
        let model = self.model;
        let reads_efforts = self.reads_efforts();
        if reads_efforts {
            self.evaluate_efforts(t, q, v)?;
        }
        // The efforts' generalised forces, with the friction's when there is any.
        let mut with_friction = std::mem::take(&mut self.scratch.tau_with_friction);
        if !model.frictions.is_empty() {
            with_friction.copy_from(match reads_efforts {
                true => &self.scratch.efforts.tau,
                false => &self.scratch.no_efforts.tau,
            });
            self.scratch.friction_power = self.add_friction(v, &mut with_friction);
        }
        let scratch = &mut self.scratch;
        let efforts = match reads_efforts {
            true => &scratch.efforts,
            false => &scratch.no_efforts,
        };
        let tau = match model.frictions.is_empty() {
            true => efforts.tau.as_slice(),
            false => with_friction.as_slice(),
        };
        let solved = match reads_efforts {
            // ABA goes on from the kinematics the efforts were computed from.
            true => aba_after_kinematics(
                model,
                &mut scratch.data,
                tau,
                &efforts.external,
                accelerations,
            ),
            // Without efforts to evaluate, ABA needs no world poses: skip the kinematics.
            false => aba_into(
                model,
                &mut scratch.data,
                q,
                v,
                tau,
                &efforts.external,
                accelerations,
            ),
        };
        self.scratch.tau_with_friction = with_friction;
        if let Err(e) = solved {
            return Err(self.dynamics_error(&e));
        }
        let scratch = &mut self.scratch;
        if !model.mimics.is_empty()
            && !coupled_aba::couple_after_aba(
                model,
                &scratch.data,
                accelerations.as_mut_slice(),
                &mut scratch.coupling,
            )
        {
            return Err(SystemError::SingularMassMatrix);
        }
        Ok(())
    }

    /// The accelerations of a tree from its mass matrix, before the rows (`solve_rows`): M from
    /// CRBA and the bias b from RNEA (both count the rotors), the slipping joints' friction
    /// added to the efforts τ, a₀ = X (τ − b) with X the response (M⁻¹, or with the mimic
    /// couplings kept); the friction's power in `friction_power`. The contacts' rows at (q, v)
    /// are left in `contact_state`.
    fn mass_accelerations(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
        accelerations: &mut DVector<f64>,
    ) -> Result<(), SystemError> {
        let model = self.model;
        self.evaluate_efforts(t, q, v)?;
        if model.has_contacts() {
            self.contact_rows_here(v, true)?;
        }
        let efforts = match self.reads_efforts() {
            true => &self.scratch.efforts,
            false => &self.scratch.no_efforts,
        };
        let planar = self.planar_here();
        let (data, bias) = (&mut self.scratch.data, &mut self.scratch.inverse);
        match (planar, self.scratch.planar.as_deref_mut()) {
            (Some(planar), Some(planar_data)) => {
                planar::algorithms::kinematics(planar, planar_data, (q, v), false);
                planar_data.set_external(planar, &efforts.external);
                planar::algorithms::rnea_forward(planar, planar_data, &self.scratch.at_rest);
                planar::algorithms::rnea_backward(planar, planar_data, bias);
                let mass = mass_storage(&mut self.scratch.mass, model.nv);
                planar::algorithms::crba(model, planar, planar_data, mass);
            }
            _ => {
                rnea_after_kinematics(model, data, &self.scratch.at_rest, &efforts.external, bias);
                let mass = mass_storage(&mut self.scratch.mass, model.nv);
                crba_after_kinematics(model, &mut self.scratch.data, mass);
            }
        }
        for (i, a) in accelerations.iter_mut().enumerate() {
            *a = efforts.tau[i] - self.scratch.inverse[i];
        }
        self.scratch.friction_power = self.add_friction(v, accelerations);
        self.form_tree_response()?;
        self.scratch.response.apply_vector(accelerations);
        Ok(())
    }

    /// The accelerations of a planar tree by the planar articulated-body algorithm, under the
    /// efforts (evaluated on the spatial kinematics they read, when the model has any).
    fn planar_tree_accelerations(
        &mut self,
        planar: &PlanarModel,
        t: f64,
        (q, v): (&[f64], &[f64]),
        accelerations: &mut DVector<f64>,
    ) -> Result<(), SystemError> {
        let reads_efforts = self.reads_efforts();
        let efforts = match reads_efforts {
            true => {
                self.evaluate_efforts(t, q, v)?;
                &self.scratch.efforts
            }
            false => &self.scratch.no_efforts,
        };
        let planar_data = self.scratch.planar.as_deref_mut();
        let planar_data = planar_data.expect("a scratch in planar form has the planar scratch");
        planar::algorithms::kinematics(planar, planar_data, (q, v), false);
        match reads_efforts {
            true => planar_data.set_external(planar, &efforts.external),
            false => planar_data.external.fill(PlanarForce::zeros()),
        }
        let tau = efforts.tau.as_slice();
        let solved = planar::algorithms::aba(planar, planar_data, tau, accelerations);
        solved.map_err(|e| self.dynamics_error(&e))
    }

    /// The contacts' rows at the state whose kinematics the scratch holds, into its
    /// `contact_state` (with γ when `with_bias`). A disc that lies flat, or passed lying flat
    /// since the last rows, has no contact point: the run ends there.
    pub(super) fn contact_rows_here(
        &mut self,
        v: &[f64],
        with_bias: bool,
    ) -> Result<(), SystemError> {
        let state = &mut self.scratch.contact_state;
        contacts::contact_rows_into(self.model, &mut self.scratch.data, v, with_bias, state);
        match state.flat_disc {
            Some(k) => Err(SystemError::DiscFlat {
                contact: self.model.contacts[k].name.clone(),
            }),
            None => Ok(()),
        }
    }

    /// The position drives' rows at time `t` and the state whose forward kinematics the
    /// scratch holds (velocities `v`), into its `point_state` (with γ when `with_bias`).
    pub(super) fn point_rows_here(&mut self, t: f64, v: &[f64], with_bias: bool) {
        let scratch = &mut self.scratch;
        driven_points::point_rows_into(
            self.model,
            &mut scratch.data,
            t,
            v,
            with_bias,
            &mut scratch.law_values,
            &mut scratch.point_state,
        );
    }

    /// Forms the response of a tree at the mass matrix in `mass`: M⁻¹, or S (SᵀMS)⁻¹ Sᵀ with S
    /// the basis of the velocities the mimic couplings allow.
    fn form_tree_response(&mut self) -> Result<(), SystemError> {
        let formed = match self.model.mimics.is_empty() {
            true => self.scratch.response.on_tree(&self.scratch.mass),
            false => self
                .scratch
                .response
                .on_basis(&self.scratch.mass, self.scratch.coupled.as_view()),
        };
        self.scratch.response_here = formed;
        match formed {
            true => Ok(()),
            false => Err(SystemError::SingularMassMatrix),
        }
    }

    /// dy/dt at (t, y), or why it cannot be computed.
    pub fn derivative(&mut self, t: f64, y: &[f64], dydt: &mut [f64]) -> Result<(), SystemError> {
        if self.native_derivative(t, y, dydt) {
            return Ok(());
        }
        let mut q = std::mem::take(&mut self.scratch.positions);
        let v = self.model.split_state_into(y, &mut q);
        let result = self.derivative_at(t, &q, v, dydt);
        self.scratch.positions = q;
        // The planar rows are not the rows a projection continues from (`hand_over`).
        if result.is_ok() && self.model.has_loops() && self.planar_here().is_none() {
            self.scratch.evaluated.extend_from_slice(y);
        }
        result
    }

    /// dy/dt at (t, y) from the native code alone, where it is the whole evaluation
    /// (`compiled::attach`), with no row to solve after it at this state (no coordinate held:
    /// `holds_nothing`). Then y splits into the positions and velocities as they are, the
    /// positions' rates are the velocities (through the quaternions' kinematics for ball
    /// joints), and the accelerations are the native code's: what `derivative_at` computes there, without
    /// the scratch it takes and gives back and the stack it finds empty. False where the native
    /// code refused (a value not finite: `derivative_at` says why) or does not serve alone.
    fn native_derivative(&mut self, t: f64, y: &[f64], dydt: &mut [f64]) -> bool {
        let model = self.model;
        let Some(native) = self.native else {
            return false;
        };
        if model.has_contacts() || !self.holds_nothing() || !self.native_keeps_the_rows(native) {
            return false;
        }
        let (q, v) = y.split_at(model.positions());
        let (dq, dv) = dydt.split_at_mut(model.positions());
        if !native.accelerations(t, q, v, dv) {
            return false;
        }
        if model.nq == model.nv {
            dq.copy_from_slice(v);
        } else {
            // Quaternions move along the rotation, from their unit length as the simulator's
            // own evaluation takes them.
            let mut positions = std::mem::take(&mut self.scratch.positions);
            model.split_state_into(y, &mut positions);
            model.position_rates(&positions, v, dq);
            self.scratch.positions = positions;
        }
        let scratch = &mut self.scratch;
        (scratch.friction_power, scratch.drive_power, scratch.power) = (0.0, 0.0, 0.0);
        scratch.response_here = false;
        true
    }

    /// Whether `native` solves the loops on the rows this run keeps now (`kept_rows_solve`):
    /// the rows chosen at the start, not chosen again nor set aside for a passage since, the
    /// same motions without mass held at rest, and the loops kept by projection (Baumgarte's
    /// feedback changes the accelerations). Always for a tree.
    fn native_keeps_the_rows(&self, native: &NativeDynamics) -> bool {
        if !self.model.has_loops() {
            return true;
        }
        let loops = &self.scratch.loops;
        let held = self.scratch.loop_scratch.left_at_rest(&loops.structure);
        loops.stabilisation == Stabilisation::Projection
            && native
                .kept_rows
                .as_ref()
                .is_some_and(|rows| *rows == loops.structure.choice.rows)
            && native.held == held
    }

    fn derivative_at(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
        dydt: &mut [f64],
    ) -> Result<(), SystemError> {
        let model = self.model;
        self.scratch.friction_power = 0.0;
        self.scratch.drive_power = 0.0;
        self.scratch.response_here = false;
        let mut accelerations = std::mem::take(&mut self.scratch.accelerations);
        if accelerations.len() != model.velocities() {
            // Only after a failed evaluation, which took the scratch away.
            accelerations = DVector::zeros(model.velocities());
        }
        // Where the native code refuses (a singular mass matrix, a value not finite), the
        // evaluation below says why.
        // With loops, the native code is taken in `native_derivative` or not at all (the
        // loops' block below would solve them again).
        let native = !model.has_loops()
            && self
                .native
                .is_some_and(|native| native.accelerations(t, q, v, accelerations.as_mut_slice()));
        if native || model.has_loops() {
            // The accelerations are written, or are the loops' block's (`solve_stack`).
        } else if self.drives_by_subtrees() {
            self.subtree_accelerations(t, q, v, &mut accelerations)?;
        } else if let Some(planar) = self.planar_here().filter(|_| !self.needs_mass_matrix()) {
            self.planar_tree_accelerations(planar, t, (q, v), &mut accelerations)?;
        } else if self.needs_mass_matrix() {
            self.mass_accelerations(t, q, v, &mut accelerations)?;
        } else {
            self.articulated_accelerations(t, q, v, &mut accelerations)?;
        }
        // The constraint stack (`stack`): the loops' block by its sparse factorisation, then
        // the rows of the contacts, the couplings with loops and the coordinates held or
        // driven, on the response of the loops' block or of the tree's base solve above: the
        // one place every evaluation of the run solves constraint rows.
        self.solve_stack(t, q, v, &mut accelerations)?;
        let efforts = if self.reads_efforts() || model.has_loops() || model.has_contacts() {
            &self.scratch.efforts
        } else {
            &self.scratch.no_efforts
        };
        self.scratch.power = if native {
            0.0
        } else {
            efforts.power + self.scratch.friction_power + self.scratch.drive_power
        };
        if let Some(k) = accelerations.iter().position(|a| !a.is_finite()) {
            let joint = model.joint_of_velocity(k);
            let join = joint.map_or("?".to_string(), |j| j.chain.name.clone());
            let efforts_finite = efforts.tau.iter().all(|x| x.is_finite())
                && efforts
                    .external
                    .iter()
                    .all(|f| f.iter().all(|x| x.is_finite()));
            let cause = if efforts_finite {
                NotFiniteCause::StateTooLarge
            } else {
                NotFiniteCause::EffortNotANumber
            };
            return Err(SystemError::AccelerationNotFinite { join, cause });
        }
        let (dq, dv) = dydt.split_at_mut(model.positions());
        model.position_rates(q, v, dq);
        dv.copy_from_slice(accelerations.as_slice());
        self.scratch.accelerations = accelerations;
        Ok(())
    }

    /// Keeps the loops closed, and the stack's other rows kept, after a step (`keep_rows`,
    /// the resting stops' bounds among them); nothing for a tree without such rows. Whether y
    /// moved.
    pub fn keep_closed(&mut self, t: f64, y: &mut [f64]) -> Result<bool, SystemError> {
        self.keep_rows(t, y)
    }

    /// Keeps the loops closed after a step (see `LoopMonitor::keep`), then the rows beyond
    /// them, the contacts' and the couplings' (`keep_stacked`); nothing for a tree without.
    fn keep_rows(&mut self, t: f64, y: &mut [f64]) -> Result<bool, SystemError> {
        let model = self.model;
        if !model.has_loops() {
            return self.keep_stacked(t, y);
        }
        let free = &self.scratch.loops.structure.free;
        let quality = self.scratch.loop_scratch.take_free_quality(free);
        // The range-space method works on the rows, not on the free coordinates: they are
        // watched only where its motions were found for a caller that works on them.
        let null_space = self.scratch.loop_scratch.method() == loops::Method::NullSpace;
        self.scratch.loops.watches_free = null_space || quality.is_some();
        self.scratch.projection.offer_free_quality(quality);
        self.scratch.loop_scratch.refresh();
        let (mut q, mut v) = (
            std::mem::take(&mut self.scratch.positions),
            std::mem::take(&mut self.scratch.velocities),
        );
        v.clear();
        v.extend_from_slice(model.split_state_into(y, &mut q));
        if self.scratch.evaluated == y {
            let choice = &self.scratch.loops.structure.choice;
            (self.scratch.loop_scratch).hand_over(&mut self.scratch.projection, choice);
        }
        self.scratch.evaluated.clear();
        let state = (&mut q[..], &mut v[..]);
        let scratch = &mut self.scratch;
        let (data, projection) = (&mut scratch.data, &mut scratch.projection);
        let findings = &mut self.state.loops;
        let kept = (scratch.loops).keep(model, data, t, state, projection, findings);
        self.scratch.projection.offer_free_quality(None);
        if kept.as_ref().is_ok_and(|&moved| moved) {
            y[..q.len()].copy_from_slice(&q);
            y[q.len()..].copy_from_slice(&v);
        }
        (self.scratch.positions, self.scratch.velocities) = (q, v);
        let moved = kept?;
        if let Some((time, row, left)) = self.scratch.loops.opened {
            return Err(SystemError::LoopsOpen {
                time,
                join: model.loops[row / 6].name.clone(),
                row: ROW_NAMES[row % 6],
                left,
            });
        }
        let stacked = self.keep_stacked(t, y)?;
        Ok(moved || stacked)
    }

    /// Where a step ending at y, which crossed a singular configuration of the loops since the
    /// last state kept (`LoopMonitor::crossing`), should end instead, as a fraction of it: the
    /// passage is met at a step's end, where it is set aside (`LoopMonitor::keep`), rather than
    /// jumped across by a step whose stages come unseen as near it as round-off allows.
    pub fn cut_at_passage(&mut self, _t: f64, y: &[f64]) -> Result<Option<f64>, SystemError> {
        match self.scratch.loops.watches_crossings() {
            true => self.ask_at_step_end(y, LoopMonitor::crossing),
            false => Ok(None),
        }
    }

    /// Where a step ending at y in a passage, its rows set aside already independent again well
    /// past `PASSAGE_LEFT` (`LoopMonitor::leaving`), should end instead, as a fraction of it.
    pub fn leave_passage_soon(&mut self, _t: f64, y: &[f64]) -> Result<Option<f64>, SystemError> {
        match self.scratch.loops.cuts_passage() {
            true => self.ask_at_step_end(y, LoopMonitor::leaving),
            false => Ok(None),
        }
    }

    /// What the loops' monitor answers `ask` with the rows at the step's end y.
    fn ask_at_step_end(
        &mut self,
        y: &[f64],
        ask: fn(&mut LoopMonitor, &loops::ConstraintJacobian) -> Option<f64>,
    ) -> Result<Option<f64>, SystemError> {
        let model = self.model;
        if !model.has_loops() {
            return Ok(None);
        }
        let mut q = std::mem::take(&mut self.scratch.positions);
        let v = model.split_state_into(y, &mut q);
        let scratch = &mut self.scratch;
        let rows = scratch
            .crossing_rows
            .get_or_insert_with(|| loops::Constraints::new(model));
        let found = forward_kinematics(model, &mut scratch.data, &q, v)
            .and_then(|()| {
                loops::constraints_into(model, &mut scratch.data, &q, v, Extent::Rows, rows)
            })
            .map(|()| ask(&mut scratch.loops, &rows.jacobian));
        self.scratch.positions = q;
        Ok(found?)
    }

    /// Sets the rates of the complementary ball joints' angles in y (for outputs).
    pub fn ball_rates(&mut self, y: &mut [f64]) -> Result<(), SystemError> {
        let model = self.model;
        let (mut q, v) = model.split_state(y);
        let mut v = v.to_vec();
        if loops::seat_ball_angles(model, &mut self.scratch.data, &mut q, &mut v, true)? {
            y[q.len()..].copy_from_slice(&v);
        }
        Ok(())
    }

    /// Records the loops' residuals at y without moving it.
    pub fn measure_loops(&mut self, t: f64, y: &[f64]) -> Result<(), SystemError> {
        let model = self.model;
        if !model.has_loops() {
            return Ok(());
        }
        let mut q = std::mem::take(&mut self.scratch.positions);
        let v = model.split_state_into(y, &mut q);
        let scratch = &mut self.scratch;
        let (data, projection) = (&mut scratch.data, &mut scratch.projection);
        let findings = &mut self.state.loops;
        let measured = (scratch.loops).measure(model, data, t, (&q, v), projection, findings);
        self.scratch.positions = q;
        Ok(measured?)
    }

    /// Closes the loops of the initial state at round-off, decides their structure (see
    /// `loops::Structure`) and projects the velocities onto them; for contacts, closes their
    /// gaps and projects the velocities onto their rows.
    pub fn start_loops(&mut self, y: &mut [f64]) -> Result<(), SystemError> {
        let model = self.model;
        if !model.has_loops() {
            // The gaps closed and the starting velocities made to roll, by the smallest change
            // in the kinetic metric.
            return self.keep_stacked(0.0, y).map(|_| ());
        }
        let (mut q, v) = model.split_state(y);
        let mut v = v.to_vec();
        loops::close_configuration(model, &mut self.scratch.data, &mut q)?;
        let findings = &mut self.state.loops;
        let scratch = &mut self.scratch;
        let started = (scratch.loops).start(model, &mut scratch.data, (&q, &v), findings);
        started.map_err(|e| self.structure_error(&e))?;
        let choice = &self.scratch.loops.structure.choice;
        loops::project(model, &mut self.scratch.data, choice, &mut q, &mut v)?;
        y[..q.len()].copy_from_slice(&q);
        y[q.len()..].copy_from_slice(&v);
        self.keep_stacked(0.0, y)?;
        Ok(())
    }

    /// Decides the loops' structure at q if no run started them (`start_loops`): a state
    /// evaluated on its own, closed.
    pub(super) fn ensure_structure(&mut self, q: &[f64]) -> Result<(), SystemError> {
        if self.scratch.loops.started() {
            return Ok(());
        }
        let rest = vec![0.0; self.model.velocities()];
        let (model, findings, scratch) = (self.model, &mut self.state.loops, &mut self.scratch);
        let started = (scratch.loops).start(model, &mut scratch.data, (q, &rest), findings);
        started.map_err(|e| self.structure_error(&e))
    }

    pub(super) fn loop_error(&self, error: &LoopError) -> SystemError {
        match error {
            LoopError::MasslessMotion { velocity } => SystemError::MasslessMotion {
                velocity: self.model.velocity_name(*velocity),
            },
            LoopError::Singular { row } => SystemError::SingularConfiguration {
                join: self.model.loops[row / 6].name.clone(),
                row: ROW_NAMES[row % 6],
            },
        }
    }

    fn structure_error(&self, error: &StructureError) -> SystemError {
        match error {
            StructureError::Evaluation(e) => SystemError::Evaluation(e.clone()),
            StructureError::SingularStart { row } => SystemError::SingularStart {
                join: self.model.loops[row / 6].name.clone(),
                row: ROW_NAMES[row % 6],
            },
        }
    }

    /// The error of a dynamics algorithm, naming the joint and body it is about.
    pub fn dynamics_error(&self, error: &DynamicsError) -> SystemError {
        match error {
            DynamicsError::Evaluation(e) => SystemError::Evaluation(e.clone()),
            DynamicsError::Singular { joint, body } => SystemError::SingularInertia {
                join: self.model.joints[*joint].chain.name.clone(),
                body: self.model.body_names[body - 1].clone(),
            },
        }
    }
}

/// Observes an output of a run: the run's system (its state and the outputs' scratch, see
/// `MechanicalSystem::sampling`), the output's time and the integrator's state there.
pub type RunObserver<'o, 'm> =
    dyn FnMut(&mut MechanicalSystem<'m>, f64, &[f64]) -> Result<(), CallbackError> + 'o;

/// Whether the accelerations of a tree need the mass matrix rather than the articulated-body
/// algorithm: geared rotors (which ABA counts as well; runs have taken them through M, whose
/// results the examples' expected outputs hold), dry friction or a driven joint's friction
/// (held through M while sticking, or by the drive's row) or contacts (whose rows are solved
/// on M⁻¹). Viscous friction alone is a generalised force, and mimic couplings take their
/// forces on ABA's articulated inertias (`coupled_aba`).
fn needs_mass_matrix(model: &Model) -> bool {
    let phased = |f: &crate::dynamics::friction::Friction| f.dry != 0.0 || f.driven;
    let extended =
        !model.rotors.is_empty() || model.frictions.iter().any(phased) || model.has_contacts();
    !model.has_loops() && extended
}
