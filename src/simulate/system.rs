//! The equations of motion as a first-order system y' = f(t, y), with y = (positions,
//! velocities): positions move with the joint velocities (quaternions included), velocities with
//! the accelerations from the articulated-body algorithm under the efforts (trees), or from the
//! constrained equations M v̇ = f + Gᵀλ, G v̇ + γ = 0 (loops), then with every other row
//! (contacts, couplings with loops, coordinates held at rest) solved on the response of those
//! accelerations to forces (`dynamics::rows`, `holding`).

use std::cell::RefCell;

use nalgebra::{DMatrix, DVector};
use std::fmt;
use std::rc::Rc;

mod held_reactions;
mod holding;
mod jacobian;
mod stacked;
mod stop_rows;

use super::constraints::LoopMonitor;
use super::native::NativeDynamics;
use crate::dynamics::algorithms::{
    aba_after_kinematics, aba_into, crba_after_kinematics, forward_kinematics, rnea,
    rnea_after_kinematics, rnea_forward, transmitted_wrenches, Data, DynamicsError,
};
use crate::dynamics::contacts::{self, ContactRows};
use crate::dynamics::efforts::{evaluate_into, Declared, Efforts};
use crate::dynamics::friction::Phase;
use crate::dynamics::loops::{
    self, Extent, LoopError, LoopScratch, ProjectionScratch, Stabilisation, StructureError, Wanted,
    ROW_NAMES,
};
use crate::dynamics::mimics;
use crate::dynamics::model::{DeclaredState, Model, Recovered};
use crate::dynamics::response::Response;
use crate::dynamics::rows::RowStack;
use crate::kinematics::eval::EvalError;
use crate::spatial;

pub struct MechanicalSystem<'m> {
    pub model: &'m Model,
    pub data: Data,
    /// Declared coordinates at the last output, shared with the sampler: recovered angles stay
    /// continuous (a spring on an angle sees 3π/2, not −π/2, after one and a half turns).
    pub reference: Rc<RefCell<Vec<f64>>>,
    /// How the loops are kept closed, and what the run has seen of them.
    pub loops: LoopMonitor,
    /// The power of the non-conservative efforts at the last `derivative`.
    pub power: f64,
    /// Scratch of `derivative` for a tree, kept so that it allocates nothing: the normalised
    /// positions, the accelerations, and the efforts of a mechanism without any.
    positions: Vec<f64>,
    accelerations: DVector<f64>,
    no_efforts: Efforts,
    /// The efforts at the last evaluation, and the declared coordinates and rates they used.
    efforts: Efforts,
    declared: DeclaredState,
    /// Scratch of the constrained equations: the tree's inverse dynamics and Ma − f (for the
    /// multipliers), and the loops' rows, factorisation and solution.
    inverse: DVector<f64>,
    force: DVector<f64>,
    loop_scratch: LoopScratch,
    /// Scratch of the projections: the constraints and factorisations, and the velocities.
    projection: ProjectionScratch,
    velocities: Vec<f64>,
    /// The state of the last evaluation of a mechanism with loops, while `loop_scratch` holds
    /// its rows (empty otherwise): a projection of that state adopts them.
    evaluated: Vec<f64>,
    /// The contact rows kept for the run (decided at the first evaluation, see
    /// `contacts::independent_rows`), their normal rows, and every contact row at the last
    /// evaluation.
    pub contact_rows: Option<Vec<usize>>,
    normal_rows: Vec<usize>,
    contact_state: ContactRows,
    /// Zero velocities or accelerations (tree length), the tree's mass matrix, the basis of
    /// the velocities a tree's mimic couplings allow (`mimics::basis`), and the response X of
    /// the accelerations to generalised forces (`response`), with whether it was formed at the
    /// state of the current evaluation.
    at_rest: Vec<f64>,
    mass: DMatrix<f64>,
    coupled: DMatrix<f64>,
    response: Response,
    response_here: bool,
    /// The rows solved on the response (`rows`): at each evaluation (contacts, couplings with
    /// loops, coordinates held at rest), and in the projections onto the velocity rows and onto
    /// the position rows; the velocities held at the evaluation; a step of the velocities.
    rows: RowStack,
    velocity_stack: RowStack,
    position_stack: RowStack,
    held: Vec<usize>,
    step: DVector<f64>,
    /// The forward dynamics as native code (`simulate --compiled`), in place of the efforts
    /// and the articulated-body algorithm.
    native: Option<&'m NativeDynamics>,
    /// The impacts on the stops so far, in time order.
    pub impacts: Vec<crate::dynamics::stops::Impact>,
    /// Per stop, whether its coordinate rests on it, and the contact force holding it there
    /// at the last evaluation (positive while it pushes the coordinate into its range).
    pub resting: Vec<bool>,
    pub contact: Vec<f64>,
    /// Per joint with friction, its phase (set at the start and at its events), the force
    /// holding it while it sticks at the last evaluation, and the power of the friction then.
    pub phases: Vec<Phase>,
    pub holding: Vec<f64>,
    friction_power: f64,
    /// The friction's changes of phase so far, in time order.
    pub switches: Vec<crate::dynamics::friction::Switch>,
    /// The phases and resting stops shared with another system of the run (the sampler's),
    /// which mirrors them (see `simulate::friction`).
    pub(super) shared_phases: Option<Rc<RefCell<SharedPhases>>>,
}

/// The friction's phases and the stops' resting flags of a run, as its integrated system last
/// set them.
#[derive(Clone, Debug, Default)]
pub struct SharedPhases {
    pub phases: Vec<Phase>,
    pub resting: Vec<bool>,
}

impl<'m> MechanicalSystem<'m> {
    pub fn new(
        model: &'m Model,
        reference: Rc<RefCell<Vec<f64>>>,
        stabilisation: Stabilisation,
    ) -> MechanicalSystem<'m> {
        MechanicalSystem {
            model,
            data: Data::new(model),
            reference,
            loops: LoopMonitor::new(stabilisation),
            power: 0.0,
            positions: Vec::new(),
            accelerations: DVector::zeros(model.velocities()),
            no_efforts: Efforts::none(model),
            efforts: Efforts::none(model),
            declared: DeclaredState::default(),
            inverse: DVector::zeros(model.nv),
            force: DVector::zeros(model.velocities()),
            loop_scratch: LoopScratch::new(model),
            projection: ProjectionScratch::new(model),
            velocities: Vec::new(),
            evaluated: Vec::new(),
            contact_rows: None,
            normal_rows: Vec::with_capacity(model.contacts.len()),
            contact_state: ContactRows::new(model),
            at_rest: vec![0.0; model.nv],
            mass: DMatrix::zeros(model.nv, model.nv),
            coupled: mimics::basis(&model.mimics, model.nv),
            response: Response::default(),
            response_here: false,
            rows: RowStack::new(model),
            velocity_stack: RowStack::new(model),
            position_stack: RowStack::new(model),
            held: Vec::with_capacity(model.stops.len() + model.frictions.len()),
            step: DVector::zeros(model.velocities()),
            native: None,
            impacts: Vec::new(),
            resting: vec![false; model.stops.len()],
            contact: vec![0.0; model.stops.len()],
            phases: vec![Phase::Slipping(1.0); model.frictions.len()],
            holding: vec![0.0; model.frictions.len()],
            friction_power: 0.0,
            switches: Vec::new(),
            shared_phases: None,
        }
    }

    /// Evaluates the accelerations with `native` (checked against this system's own evaluation
    /// by `compiled::attach`) from now on. The power of the non-conservative efforts is then not
    /// computed: it is left at zero.
    pub fn use_native(&mut self, native: Option<&'m NativeDynamics>) {
        self.native = native;
    }

    pub fn dimension(&self) -> usize {
        self.model.positions() + self.model.velocities()
    }

    /// Whether the equations of motion do not depend on the time: no effort reads it.
    pub fn autonomous(&self) -> bool {
        let model = self.model;
        !model.has_efforts() || model.effort_tape.as_ref().is_ok_and(|t| !t.reads_time())
    }

    /// The efforts at (t, q, v); leaves the forward kinematics of (q, v) in `data`.
    pub fn efforts(&mut self, t: f64, q: &[f64], v: &[f64]) -> Result<Efforts, SystemError> {
        self.evaluate_efforts(t, q, v)?;
        Ok(self.efforts.clone())
    }

    /// The efforts at (t, q, v) into `self.efforts`, without allocating once its buffers are
    /// sized; leaves the forward kinematics of (q, v) in `data`.
    fn evaluate_efforts(&mut self, t: f64, q: &[f64], v: &[f64]) -> Result<(), SystemError> {
        let model = self.model;
        forward_kinematics(model, &mut self.data, q, v)?;
        let state = &mut self.declared;
        model.declared_into(
            q,
            v,
            &self.reference.borrow(),
            state,
            Recovered::ReadByEfforts,
        )?;
        let declared = Declared {
            model,
            coordinates: &state.coordinates,
            rates: &state.rates,
        };
        Ok(evaluate_into(
            model,
            &mut self.data,
            &declared,
            t,
            &mut self.efforts,
        )?)
    }

    /// Whether this tree's accelerations come from its mass matrix ([`needs_mass_matrix`]).
    fn needs_mass_matrix(&self) -> bool {
        needs_mass_matrix(self.model)
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
            let state = &mut self.contact_state;
            contacts::contact_rows_into(model, &mut self.data, v, true, state);
        }
        let efforts = match model.has_efforts() {
            true => &self.efforts,
            false => &self.no_efforts,
        };
        let (data, bias) = (&mut self.data, &mut self.inverse);
        rnea_after_kinematics(model, data, &self.at_rest, &efforts.external, bias);
        crba_after_kinematics(model, &mut self.data, &mut self.mass);
        for (i, a) in accelerations.iter_mut().enumerate() {
            *a = efforts.tau[i] - self.inverse[i];
        }
        self.friction_power = self.add_friction(v, accelerations);
        self.form_tree_response()?;
        self.response.apply_vector(accelerations);
        Ok(())
    }

    /// Forms the response of a tree at the mass matrix in `mass`: M⁻¹, or S (SᵀMS)⁻¹ Sᵀ with S
    /// the basis of the velocities the mimic couplings allow.
    fn form_tree_response(&mut self) -> Result<(), SystemError> {
        let formed = match self.model.mimics.is_empty() {
            true => self.response.on_tree(&self.mass),
            false => self.response.on_basis(&self.mass, self.coupled.as_view()),
        };
        self.response_here = formed;
        match formed {
            true => Ok(()),
            false => Err(SystemError::SingularMassMatrix),
        }
    }

    /// Forms the response at q when the evaluation did not (`response_here`): with loops, on
    /// the allowed motions of the last constrained solve (which must be at q).
    fn form_response_at(&mut self, q: &[f64]) -> Result<(), SystemError> {
        if self.response_here {
            return Ok(());
        }
        let model = self.model;
        crate::dynamics::algorithms::crba_into(
            model,
            &mut self.data,
            &q[..model.nq],
            &mut self.mass,
        )?;
        if !model.has_loops() {
            return self.form_tree_response();
        }
        let motions = self.loop_scratch.solved_motions();
        self.response_here = self.response.on_basis(&self.mass, motions);
        match self.response_here {
            true => Ok(()),
            false => Err(SystemError::SingularMassMatrix),
        }
    }

    /// The accelerations and constraint forces of a mechanism with loops at (t, q, v), left in
    /// `loop_scratch` with the constraint rows they come from, the efforts in `efforts`;
    /// nothing is allocated once the buffers are sized.
    pub(super) fn solve_constrained(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
        wanted: Wanted,
    ) -> Result<(), SystemError> {
        let model = self.model;
        self.evaluated.clear();
        self.ensure_structure(q)?;
        // The efforts leave the forward kinematics of (q, v) in `data`, which the rows and the
        // recursions start from.
        self.evaluate_efforts(t, q, v)?;
        // The slipping joints' friction acts with the efforts.
        let mut tau = std::mem::take(&mut self.efforts.tau);
        self.friction_power = self.add_friction(v, &mut tau);
        self.efforts.tau = tau;
        let scratch = &mut self.loop_scratch;
        // Only Baumgarte's feedback reads the position rows.
        let extent = match self.loops.stabilisation {
            Stabilisation::Baumgarte(_) => Extent::WithBias,
            _ => Extent::Motion,
        };
        loops::constraints_into(
            model,
            &mut self.data,
            q,
            v,
            extent,
            &mut scratch.constraints,
        )?;
        let structure = &self.loops.structure;
        loops::allowed_motions(structure, self.loops.stabilisation, scratch)
            .map_err(|e| self.loop_error(&e))?;
        // Inverse dynamics' pass out at a₀: the bodies' forces whose power along each allowed
        // motion gives its share of Ma₀ and of the velocity-product forces.
        let scratch = &mut self.loop_scratch;
        let particular = &scratch.particular()[..model.nv];
        rnea_forward(model, &mut self.data, particular, &self.efforts.external);
        let tau = &self.efforts.tau;
        let solved = loops::solve_reduced(model, &mut self.data, tau, structure, scratch);
        solved.map_err(|e| self.loop_error(&e))?;
        if wanted == Wanted::WithMultipliers {
            self.solve_multipliers();
        }
        Ok(())
    }

    /// The multipliers of the accelerations `solve_constrained` left in `loop_scratch`, from
    /// Ma − f: inverse dynamics at those accelerations under the efforts' external forces,
    /// less the efforts' generalised forces (the complementary coordinates, without inertia,
    /// get −τ). `data` holds the forward kinematics of the state.
    pub(super) fn solve_multipliers(&mut self) {
        let model = self.model;
        let scratch = &mut self.loop_scratch;
        let a = &scratch.accelerations.as_slice()[..model.nv];
        let external = &self.efforts.external;
        rnea_after_kinematics(model, &mut self.data, a, external, &mut self.inverse);
        self.force.copy_from(&self.efforts.tau);
        self.force.neg_mut();
        let mut tree = self.force.rows_mut(0, model.nv);
        tree += &self.inverse;
        loops::multipliers(&self.force, scratch);
    }

    /// dy/dt at (t, y), or why it cannot be computed.
    pub fn derivative(&mut self, t: f64, y: &[f64], dydt: &mut [f64]) -> Result<(), SystemError> {
        let mut q = std::mem::take(&mut self.positions);
        let v = self.model.split_state_into(y, &mut q);
        let result = self.derivative_at(t, &q, v, dydt);
        self.positions = q;
        if result.is_ok() && self.model.has_loops() {
            self.evaluated.extend_from_slice(y);
        }
        result
    }

    fn derivative_at(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
        dydt: &mut [f64],
    ) -> Result<(), SystemError> {
        let model = self.model;
        self.friction_power = 0.0;
        self.response_here = false;
        let mut accelerations = std::mem::take(&mut self.accelerations);
        if accelerations.len() != model.velocities() {
            // Only after a failed evaluation, which took the scratch away.
            accelerations = DVector::zeros(model.velocities());
        }
        // Where the native code refuses (a singular mass matrix, a value not finite), the
        // evaluation below says why.
        let native = self
            .native
            .is_some_and(|native| native.accelerations(t, q, v, accelerations.as_mut_slice()));
        if native {
            // The accelerations are written.
        } else if model.has_loops() {
            self.solve_constrained(t, q, v, Wanted::Accelerations)?;
            accelerations.copy_from(&self.loop_scratch.accelerations);
        } else if self.needs_mass_matrix() {
            self.mass_accelerations(t, q, v, &mut accelerations)?;
        } else if model.has_efforts() {
            // ABA goes on from the kinematics the efforts were computed from.
            self.evaluate_efforts(t, q, v)?;
            let (tau, external) = (self.efforts.tau.as_slice(), &self.efforts.external);
            if let Err(e) =
                aba_after_kinematics(model, &mut self.data, tau, external, &mut accelerations)
            {
                return Err(self.dynamics_error(&e));
            }
        } else {
            // Without efforts to evaluate, ABA needs no world poses: skip the kinematics.
            let (tau, external) = (self.no_efforts.tau.as_slice(), &self.no_efforts.external);
            if let Err(e) = aba_into(
                model,
                &mut self.data,
                q,
                v,
                tau,
                external,
                &mut accelerations,
            ) {
                return Err(self.dynamics_error(&e));
            }
        }
        // The contacts, the couplings with loops and the coordinates held at rest, solved on the
        // response together.
        self.solve_rows(q, v, &mut accelerations)?;
        let efforts = if model.has_efforts() || model.has_loops() || model.has_contacts() {
            &self.efforts
        } else {
            &self.no_efforts
        };
        self.power = if native {
            0.0
        } else {
            efforts.power + self.friction_power
        };
        if let Some(k) = accelerations.iter().position(|a| !a.is_finite()) {
            let joint = model
                .joints
                .iter()
                .find(|j| (j.v_offset..j.v_offset + j.nv()).contains(&k));
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
        for joint in &model.joints {
            let range = joint.q_offset..joint.q_offset + joint.nq();
            joint.position_rate(
                &q[range.clone()],
                &v[joint.v_offset..joint.v_offset + joint.nv()],
                &mut dq[range],
            );
        }
        dq[model.nq..].copy_from_slice(&v[model.nv..]);
        dv.copy_from_slice(accelerations.as_slice());
        self.accelerations = accelerations;
        Ok(())
    }

    /// The tangent space of the loops' constraints at y, for the implicit method's Jacobian:
    /// for each allowed motion n of the velocities (the massive ones the equations of motion
    /// solve on) that leaves the resting stops' coordinates at rest, the state's direction
    /// (q̇(n), 0) that moves the positions along it and (0, n) that moves the velocities along
    /// it. `None` for a tree, whose state moves freely.
    /// Evaluates the equations of motion at y once (their solve finds the allowed motions).
    pub fn tangent_basis(
        &mut self,
        t: f64,
        y: &[f64],
    ) -> Result<Option<DMatrix<f64>>, SystemError> {
        let model = self.model;
        if !model.has_loops() {
            return Ok(None);
        }
        let mut dydt = vec![0.0; self.dimension()];
        self.derivative(t, y, &mut dydt)?;
        let (q, _) = model.split_state(y);
        let motions = self.motions_off_bounds(self.loop_scratch.solved_motions().into_owned());
        let (positions, velocities) = (model.positions(), model.velocities());
        let count = motions.ncols();
        let mut basis = DMatrix::zeros(positions + velocities, 2 * count);
        for k in 0..count {
            let motion = motions.column(k);
            let mut column = basis.column_mut(k);
            let rates = column.as_mut_slice();
            for joint in &model.joints {
                let range = joint.q_offset..joint.q_offset + joint.nq();
                let v_range = joint.v_offset..joint.v_offset + joint.nv();
                joint.position_rate(
                    &q[range.clone()],
                    &motion.as_slice()[v_range],
                    &mut rates[range],
                );
            }
            for (i, rate) in motion.iter().enumerate().skip(model.nv) {
                rates[model.nq + i - model.nv] = *rate;
            }
            basis
                .view_mut((positions, count + k), (velocities, 1))
                .copy_from(&motion);
        }
        Ok(Some(basis))
    }

    /// Keeps the loops closed or the contacts kept after a step (`keep_rows`), with the
    /// resting stops' bounds in mechanisms with them (`keep_on_bounds`); nothing for a tree.
    /// Whether y moved.
    pub fn keep_closed(&mut self, t: f64, y: &mut [f64]) -> Result<bool, SystemError> {
        let moved = self.keep_rows(t, y)?;
        Ok(self.keep_on_bounds(y)? || moved)
    }

    /// Keeps the loops closed after a step (see `LoopMonitor::keep`), then the rows beyond
    /// them, the contacts' and the couplings' (`keep_stacked`); nothing for a tree without.
    fn keep_rows(&mut self, t: f64, y: &mut [f64]) -> Result<bool, SystemError> {
        let model = self.model;
        if !model.has_loops() {
            return self.keep_stacked(t, y);
        }
        let free = &self.loops.structure.free;
        let quality = self.loop_scratch.take_free_quality(free);
        self.projection.offer_free_quality(quality);
        self.loop_scratch.refresh();
        let (mut q, mut v) = (
            std::mem::take(&mut self.positions),
            std::mem::take(&mut self.velocities),
        );
        v.clear();
        v.extend_from_slice(model.split_state_into(y, &mut q));
        if self.evaluated == y {
            let choice = &self.loops.structure.choice;
            (self.loop_scratch).hand_over(&mut self.projection, choice);
        }
        self.evaluated.clear();
        let state = (&mut q[..], &mut v[..]);
        let kept = self
            .loops
            .keep(model, &mut self.data, t, state, &mut self.projection);
        self.projection.offer_free_quality(None);
        if kept.as_ref().is_ok_and(|&moved| moved) {
            y[..q.len()].copy_from_slice(&q);
            y[q.len()..].copy_from_slice(&v);
        }
        (self.positions, self.velocities) = (q, v);
        let moved = kept?;
        if let Some((time, row, left)) = self.loops.opened {
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

    /// Sets the rates of the complementary ball joints' angles in y (for outputs).
    pub fn ball_rates(&mut self, y: &mut [f64]) -> Result<(), SystemError> {
        let model = self.model;
        let (mut q, v) = model.split_state(y);
        let mut v = v.to_vec();
        if loops::seat_ball_angles(model, &mut self.data, &mut q, &mut v, true)? {
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
        let mut q = std::mem::take(&mut self.positions);
        let v = model.split_state_into(y, &mut q);
        let measured =
            (self.loops).measure(model, &mut self.data, t, (&q, v), &mut self.projection);
        self.positions = q;
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
        loops::close_configuration(model, &mut self.data, &mut q)?;
        self.loops
            .start(model, &mut self.data, &q, &v)
            .map_err(|e| self.structure_error(&e))?;
        let choice = &self.loops.structure.choice;
        loops::project(model, &mut self.data, choice, &mut q, &mut v)?;
        y[..q.len()].copy_from_slice(&q);
        y[q.len()..].copy_from_slice(&v);
        self.keep_stacked(0.0, y)?;
        Ok(())
    }

    /// The wrench each join transmits to its second body, at the join, in the fixed axes
    /// (moment, then force): the tree's joins from inverse dynamics with the accelerations of the
    /// motion and the loops' forces, then the loops' from their multipliers. The coordinates
    /// held at rest (resting stops, sticking joints) are held as the run holds them, their
    /// forces in their joins' reactions as a link effort is.
    pub fn reactions(&mut self, t: f64, q: &[f64], v: &[f64]) -> Result<Vec<f64>, SystemError> {
        let model = self.model;
        let (accelerations, mut external, multipliers) = if model.has_loops() {
            let touching = self.loops_reactions_solve(t, q, v)?;
            let solution = &self.loop_scratch;
            let (c, multipliers) = (&solution.constraints, &solution.multipliers);
            let on_bodies = loops::constraint_forces(model, &self.data, c, multipliers);
            let external: Vec<_> = self
                .efforts
                .external
                .iter()
                .zip(&on_bodies)
                .map(|(a, b)| a + b)
                .collect();
            let accelerations = solution.accelerations.clone();
            let mut multipliers = multipliers.clone();
            if let Some(forces) = touching {
                multipliers = DVector::from_iterator(
                    multipliers.len() + forces.len(),
                    multipliers.iter().chain(forces.iter()).copied(),
                );
            }
            (accelerations, external, Some(multipliers))
        } else if model.has_contacts() {
            let accelerations = self.solve_every_row(t, q, v)?;
            let forces = &self.rows.contact_forces;
            let on_bodies =
                contacts::contact_body_forces(model, &self.data, &self.contact_state, forces);
            let external: Vec<_> = (self.efforts.external.iter().zip(&on_bodies))
                .map(|(a, b)| a + b)
                .collect();
            let forces = contacts::contact_reactions(forces);
            (accelerations, external, Some(forces))
        } else {
            // The accelerations of the run's own equations: with the geared rotors, the mimic
            // couplings, the friction's phases and the coordinates held at rest.
            let mut rates = vec![0.0; self.dimension()];
            self.derivative_at(t, q, v, &mut rates)?;
            let a = DVector::from_column_slice(&rates[model.positions()..]);
            let efforts = self.efforts(t, q, v)?;
            (a, efforts.external, None)
        };
        // The link efforts act across their joints: they are not part of the reaction.
        external.truncate(model.body_count() + 1);
        rnea(
            model,
            &mut self.data,
            q,
            v,
            &accelerations.as_slice()[..model.nv],
            &external,
        )?;
        let transmitted = transmitted_wrenches(model, &self.data, &external);
        let mut reactions = Vec::with_capacity(6 * (model.joints.len() + model.loops.len()));
        for joint in &model.joints {
            let frame = self.data.world[joint.child] * joint.on_child;
            let about_origin =
                spatial::force_to_parent(&self.data.world[joint.child], &transmitted[joint.child]);
            let at_join = spatial::force_to_child(
                &spatial::Pose::translation(
                    frame.translation.x,
                    frame.translation.y,
                    frame.translation.z,
                ),
                &about_origin,
            );
            // The tree carries the child; a join written from the child's side has it first.
            let on_second = if joint.first_on_parent {
                at_join
            } else {
                -at_join
            };
            reactions.extend_from_slice(on_second.as_slice());
        }
        if let Some(multipliers) = multipliers {
            reactions.extend_from_slice(multipliers.as_slice());
        }
        Ok(reactions)
    }

    /// Decides the loops' structure at q if no run started them (`start_loops`): a state
    /// evaluated on its own, closed.
    pub(super) fn ensure_structure(&mut self, q: &[f64]) -> Result<(), SystemError> {
        if self.loops.started() {
            return Ok(());
        }
        let rest = vec![0.0; self.model.velocities()];
        self.loops
            .start(self.model, &mut self.data, q, &rest)
            .map_err(|e| self.structure_error(&e))
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

/// Why the equations of motion cannot be evaluated at a state.
#[derive(Clone, Debug, PartialEq)]
pub enum SystemError {
    /// An effort or expression has no value there.
    Evaluation(EvalError),
    /// An effort drives a motion that moves no mass; `velocity` names the coordinate it moves
    /// most.
    MasslessMotion { velocity: String },
    /// `join` carries no inertia along its motion (nor do `body` and the bodies beyond it).
    SingularInertia { join: String, body: String },
    /// The mass matrix could not be factorised.
    SingularMassMatrix,
    /// The acceleration of `join` is not finite.
    AccelerationNotFinite { join: String, cause: NotFiniteCause },
    /// The loops are exactly at a singular configuration: the constraint `row` of the
    /// complementary link `join` is no longer independent of the others.
    SingularConfiguration { join: String, row: &'static str },
    /// A projection could not close the loops at `time`: `row` of `join` stays open by `left`
    /// (radians, or metres per metre of the mechanism's size).
    LoopsOpen {
        time: f64,
        join: String,
        row: &'static str,
        left: f64,
    },
    /// The run starts at a singular configuration, where `row` of `join` is implied by the other
    /// constraints though it is not at the closed configurations around it.
    SingularStart { join: String, row: &'static str },
    /// The kept rows of the contacts stopped being independent: `row` of `contact`.
    SingularContact { contact: String, row: &'static str },
    /// An impact on a stop could not be resolved, or left a coordinate resting on its stop.
    Impact(String),
}

/// What made an acceleration infinite or NaN.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NotFiniteCause {
    /// The efforts are finite: the state itself grew too large.
    StateTooLarge,
    /// An effort evaluated to NaN or infinity.
    EffortNotANumber,
}

impl From<EvalError> for SystemError {
    fn from(error: EvalError) -> Self {
        SystemError::Evaluation(error)
    }
}

impl fmt::Display for SystemError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SystemError::Evaluation(EvalError::Missing(_)) => {
                write!(f, "an effort needs a value that was not given")
            }
            SystemError::Evaluation(EvalError::NotGeometric(what)) => {
                write!(f, "an expression cannot depend on {what} there")
            }
            SystemError::Evaluation(EvalError::NotFinite) => {
                write!(f, "the geometry is not a finite number at this state")
            }
            SystemError::MasslessMotion { velocity } => write!(
                f,
                "an effort drives a motion that moves no mass (it moves `{velocity}` most): give the bodies it moves mass or inertia"
            ),
            SystemError::SingularInertia { join, body } => write!(
                f,
                "the mass matrix is singular: join `{join}` carries no inertia along its motion (body `{body}` and the bodies beyond it)"
            ),
            SystemError::SingularMassMatrix => write!(f, "the mass matrix is singular"),
            SystemError::SingularConfiguration { join, row } => write!(
                f,
                "the loops reached a singular configuration: the {row} constraint of `{join}` is no longer independent of the others"
            ),
            SystemError::LoopsOpen { time, join, row, left } => write!(
                f,
                "the loops came open at t = {time}: projecting the state back left the {row} constraint of `{join}` open by {left:.1e} (relative to the mechanism's size); the integration strayed too far from the loops: use a tighter tolerance or a smaller step"
            ),
            SystemError::SingularStart { join, row } => write!(
                f,
                "the loops start at a singular configuration (the {row} constraint of `{join}` is implied by the others here, not at the configurations around it), where the motion may leave along several branches: start away from it, or give initial values on one branch"
            ),
            SystemError::SingularContact { contact, row } => write!(
                f,
                "the contacts reached a singular configuration: the {row} row of `{contact}` is no longer independent of the other contacts' rows"
            ),
            SystemError::Impact(message) => f.write_str(message),
            SystemError::AccelerationNotFinite { join, cause } => {
                write!(f, "the acceleration of join `{join}` is not finite: {cause}")
            }
        }
    }
}

impl fmt::Display for NotFiniteCause {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            NotFiniteCause::StateTooLarge => "the state became too large",
            NotFiniteCause::EffortNotANumber => {
                "an effort is not a number (a square root or logarithm of a negative value, a division by zero)"
            }
        })
    }
}

impl std::error::Error for SystemError {}

/// Whether the accelerations of a tree need the mass matrix rather than the articulated-body
/// algorithm: geared rotors (which ABA counts as well; runs have taken them through M, whose
/// results the examples' expected outputs hold), mimic couplings (eliminated through M),
/// joint friction (held through M while sticking) or contacts (whose rows are solved on M⁻¹).
fn needs_mass_matrix(model: &Model) -> bool {
    let extended = !model.rotors.is_empty()
        || !model.mimics.is_empty()
        || !model.frictions.is_empty()
        || model.has_contacts();
    !model.has_loops() && extended
}
