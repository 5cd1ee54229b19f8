//! Analytical derivatives of inverse dynamics, ∂τ/∂q and ∂τ/∂v of τ = RNEA(q, v, a, f_ext), in one
//! pass out and one pass back: Carpentier & Mansard, "Analytical Derivatives of Rigid Body
//! Dynamics Algorithms", Robotics: Science and Systems, 2018 (the algorithm Pinocchio's
//! `computeRNEADerivatives` implements).
//!
//! Everything is expressed in the fixed frame, where a joint's motion S_j moves every body of its
//! subtree rigidly: a vector attached to such a body changes by S_j × x (a motion), S_j ×* x (a
//! force), an inertia by S_j ×* I − I S_j×. The velocities and accelerations are not attached:
//! with λ the joint's parent body,
//! ∂v_i/∂q_j = S_j × v_i + v_λ × S_j and
//! ∂a_i/∂q_j = S_j × a_i + a_λ × S_j + v_λ × (v_λ × S_j) + (v_λ × S_j) × v_i, so that the force of body i, f_i = I_i a_i + v_i ×* I_i v_i, changes by
//! S_j ×* f_i + B_i ∂V_j + I_i ∂A_j, where ∂V_j = v_λ × S_j, ∂A_j = a_λ × S_j + v_λ × ∂V_j and
//! B_i m = v_i ×* (I_i m) + I_i (m × v_i) + m ×* (I_i v_i) (the paper's Coriolis-like matrix).
//! The rigid part cancels in the generalised force S_kᵀF_k of any joint k of j's subtree, hence:
//!
//! - k in the subtree of j (k = j included): ∂τ_k/∂q_j = S_kᵀ(B^c_k ∂V_j + I^c_k ∂A_j);
//! - k an ancestor of j: ∂τ_k/∂q_j = S_kᵀ(S_j ×* F_j + B^c_j ∂V_j + I^c_j ∂A_j);
//!
//! with I^c, B^c and F the sums over a subtree (composite inertia, Coriolis matrix and force).
//! The velocities likewise: ∂v_i/∂q̇_j = S_j, ∂a_i/∂q̇_j = S_j × v_i + (v_j + v_λ) × S_j, and
//! ∂τ_k/∂q̇_j = S_kᵀ(B^c_m S_j + I^c_m ∂A'_j) with m the deeper of j and k and
//! ∂A'_j = (v_j + v_λ) × S_j.
//!
//! The joints' perturbations are those of their groups: a one-coordinate joint along its
//! coordinate, a spherical or free joint along q · exp(ε e_c) (its velocity being the body's
//! twist), so every joint's motion is its subspace column S_c in the child's frame, constant
//! there. A dof chain evaluated in general (several coordinates, or a law that is not linear)
//! has a subspace that changes with q and a bias Ṡq̇: it is refused (`Unsupported`).
//!
//! A geared rotor R (see `geared`) is a body of the carrier F's subtree (its inertia J ẽẽᵀ is
//! symmetric about its axis, so it turns with F), moved relative to F by n q̇_k along its axis
//! e: a joint without position whose rate is q̇_k. It adds B_R and I_R to F's composites, n eᵀ
//! f_R to τ_k, and a column of velocity derivatives to q̇_k's.
//!
//! External forces are held fixed in the bodies' frames, as RNEA takes them.
//!
//! Forward dynamics' derivatives need the accelerations first (`forward_dynamics`): the same pass
//! out at q̈ = 0 gives the bias forces, a pass back the efforts C(q, v) + g − Jᵀf_ext and, from
//! the composite inertias, the mass matrix M_rc = S_rᵀ I^c S_c (the composite rigid bodies'
//! entries); q̈ = M⁻¹(τ − C − g + Jᵀf_ext) by M's factor along the tree; q̈ then enters the
//! accelerations linearly, a_i += Σ_j S_j q̈_j over i's branch, and the pass back of the
//! derivatives follows. The joints' motions, poses, inertias and Coriolis matrices are formed
//! once, where articulated-body dynamics would form 6 × 6 articulated inertias of its own.

use nalgebra::{DMatrix, DVector, Matrix3, Vector3};
use wide::f64x2;

use super::mass_factor::MassFactor;
use super::{base_acceleration, Data};
use crate::dynamics::joint::{turn_columns_into, Joint, JointType, Kernel};
use crate::dynamics::model::Model;
use crate::kinematics::eval::EvalError;
use crate::spatial::{self, angular, Force, Motion, RigidInertia, Transform};

/// Why the derivatives cannot be computed for a model.
#[derive(Clone, Debug, PartialEq)]
pub enum DerivativeError {
    Evaluation(EvalError),
    /// A joint whose dof chain is evaluated in general (its subspace moves with q): its name.
    Unsupported {
        joint: String,
    },
}

impl From<EvalError> for DerivativeError {
    fn from(e: EvalError) -> Self {
        DerivativeError::Evaluation(e)
    }
}

impl std::fmt::Display for DerivativeError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            DerivativeError::Evaluation(e) => write!(f, "the geometry cannot be evaluated: {e:?}"),
            DerivativeError::Unsupported { joint } => write!(
                f,
                "the dof chain of `{joint}` is neither one rotation nor one translation linear in its coordinate, nor a spherical or free joint: its derivatives are not computed"
            ),
        }
    }
}

/// Whether the derivatives cover joint `k`: its subspace is constant in its child's frame.
fn has_constant_subspace(model: &Model, k: usize) -> bool {
    let joint = &model.joints[k];
    !matches!(
        (&joint.kernel, &joint.kind),
        (Kernel::General, JointType::Chain)
    )
}

/// The first joint the derivatives do not cover, if any (`DerivativeError::Unsupported`).
pub fn check_supported(model: &Model) -> Result<(), DerivativeError> {
    match (model.dynamic_joints.iter()).find(|&&k| !has_constant_subspace(model, k)) {
        Some(&k) => Err(DerivativeError::Unsupported {
            joint: model.joints[k].chain.name.clone(),
        }),
        None => Ok(()),
    }
}

/// What the passes read of the joints at (q, v): their transforms and subspaces in `data`. A
/// weld's, one rotation's or one translation's transform alone (`Joint::update_transform`:
/// their subspaces are constant, and the velocities across them are formed in the fixed frame
/// from the columns), a spherical or free joint's whole state at (q, v) (its transform comes
/// with it). The velocities across the one-coordinate joints in `data` are left as they were.
pub(super) fn joint_frames(
    model: &Model,
    data: &mut Data,
    q: &[f64],
    v: &[f64],
) -> Result<(), EvalError> {
    for &k in &model.dynamic_joints {
        let joint = &model.joints[k];
        let (q, state) = (&q[joint.q_offset..][..joint.nq()], &mut data.states[k]);
        match joint.kernel {
            Kernel::General => joint.update(q, &v[joint.v_offset..][..joint.nv()], state)?,
            _ => joint.update_transform(q, state)?,
        }
    }
    Ok(())
}

/// The derivatives of inverse dynamics and the scratch they are computed in; `new(&model)` once.
pub struct RneaDerivatives {
    /// τ, ∂τ/∂q and ∂τ/∂v (nv × nv, column j the derivative along velocity j) after `compute`.
    pub tau: DVector<f64>,
    pub dtau_dq: DMatrix<f64>,
    pub dtau_dv: DMatrix<f64>,
    /// Per joint, the axis k it turns about when its rotation is the turn about e_k alone
    /// (`turning_axis`).
    turning_axes: Vec<Option<usize>>,
    /// Per body (0 earth), in the fixed frame: pose, velocity, acceleration, then, after the
    /// pass back, the subtree's inertia, Coriolis matrix B and force.
    world: Vec<Transform>,
    velocity: Vec<Motion>,
    acceleration: Vec<Motion>,
    inertia: Vec<RigidInertia>,
    coriolis: Vec<CoriolisMatrix>,
    force: Vec<Force>,
    /// Per velocity, in the fixed frame: S, ∂V = v_λ × S, ∂A = a_λ × S + v_λ × ∂V and
    /// ∂A' = (v_j + v_λ) × S.
    columns: Vec<Motion>,
    dv_dq: Vec<Motion>,
    da_dq: Vec<Motion>,
    da_dv: Vec<Motion>,
    /// Per velocity, what the pass back reads of it (`BackTerms`).
    back_terms: Vec<BackTerms>,
    /// `forward_dynamics`: per body, its subtree's inertia and bias force, and the change of its
    /// acceleration by q̈.
    composite: Vec<RigidInertia>,
    composite_force: Vec<Force>,
    acceleration_change: Vec<Motion>,
}

impl RneaDerivatives {
    pub fn new(model: &Model) -> RneaDerivatives {
        let (n, nv) = (model.body_count(), model.nv);
        RneaDerivatives {
            tau: DVector::zeros(nv),
            dtau_dq: DMatrix::zeros(nv, nv),
            dtau_dv: DMatrix::zeros(nv, nv),
            turning_axes: model.joints.iter().map(turning_axis).collect(),
            world: vec![Transform::identity(); n + 1],
            velocity: vec![Motion::zeros(); n + 1],
            acceleration: vec![Motion::zeros(); n + 1],
            inertia: vec![RigidInertia::zeros(); n + 1],
            coriolis: vec![CoriolisMatrix::zeros(); n + 1],
            force: vec![Force::zeros(); n + 1],
            columns: vec![Motion::zeros(); nv],
            dv_dq: vec![Motion::zeros(); nv],
            da_dq: vec![Motion::zeros(); nv],
            da_dv: vec![Motion::zeros(); nv],
            back_terms: vec![BackTerms::default(); nv],
            composite: vec![RigidInertia::zeros(); n + 1],
            composite_force: vec![Force::zeros(); n + 1],
            acceleration_change: vec![Motion::zeros(); n + 1],
        }
    }

    /// τ, ∂τ/∂q and ∂τ/∂v at (q, v, a) under the external forces `external` (one per body, in
    /// its frame; index 0 unused), as `rnea` takes them. Derivatives along q are in the joints'
    /// tangent spaces (one per velocity).
    pub fn compute(
        &mut self,
        model: &Model,
        data: &mut Data,
        q: &[f64],
        v: &[f64],
        a: &[f64],
        external: &[Force],
    ) -> Result<(), DerivativeError> {
        self.compute_with_base(model, data, (q, v, a), external, base_acceleration(model))
    }

    /// `compute` with the base's acceleration `base` in place of the one that stands for
    /// gravity (zero for the mass matrix's derivatives).
    pub(super) fn compute_with_base(
        &mut self,
        model: &Model,
        data: &mut Data,
        (q, v, a): (&[f64], &[f64], &[f64]),
        external: &[Force],
        base: Motion,
    ) -> Result<(), DerivativeError> {
        check_supported(model)?;
        joint_frames(model, data, q, v)?;
        self.after_kinematics(model, data, (v, a), external, base);
        Ok(())
    }

    /// `compute_with_base` when `data` already holds the joints' transforms and subspaces at q
    /// (after `joint_frames` or `aba_into`, say) and the model's joints are covered
    /// (`check_supported`).
    pub(super) fn after_kinematics(
        &mut self,
        model: &Model,
        data: &Data,
        (v, a): (&[f64], &[f64]),
        external: &[Force],
        base: Motion,
    ) {
        self.acceleration[0] = base;
        self.pass_out(model, data, v, a, external);
        // Without rotors the pass back writes every entry of the tree's pattern once (the others
        // stay zero from `new`); the rotors add to some before it.
        let rotors = !model.rotors.is_empty();
        self.tau.as_mut_slice().fill(0.0);
        if rotors {
            self.dtau_dq.as_mut_slice().fill(0.0);
            self.dtau_dv.as_mut_slice().fill(0.0);
        }
        self.add_rotors(model, v, a);
        if rotors {
            self.pass_back::<true>(model, Layout::Columns);
        } else {
            self.pass_back::<false>(model, Layout::Columns);
        }
    }

    /// Forward dynamics at (v, τ) with its inverse dynamics' derivatives at the accelerations:
    /// the mass matrix into `mass` (between a velocity and its ancestors only), its factor into
    /// `factor`, q̈ into `accelerations` by a solve with the factor (a product by M⁻¹ is cheaper
    /// but put ∂q̈/∂q 1.1e-12 from the dual numbers' on a random tree) and M⁻¹ into
    /// `mass_inverse` (solved in `mass`'s storage, which then holds scratch), then τ, ∂τ/∂q and
    /// ∂τ/∂v at q̈ (the module's documentation). `data` holds the joints' transforms
    /// at q; the model has no geared rotor (their efforts are not linear in the pass out's
    /// terms as written here). ∂τ/∂q and ∂τ/∂v are left by rows in the factor's order (entry
    /// (r, c) at place(c) + place(r) nv, `MassFactor::places`), as the solves with M's factor
    /// take them (`MassFactor::solve_rows_negated_into`). False if the mass matrix is not
    /// positive definite.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn forward_dynamics(
        &mut self,
        model: &Model,
        data: &Data,
        (v, tau): (&[f64], &[f64]),
        external: &[Force],
        factor: &mut MassFactor,
        mass: &mut DMatrix<f64>,
        mass_inverse: &mut DMatrix<f64>,
        accelerations: &mut DVector<f64>,
    ) -> bool {
        debug_assert!(model.rotors.is_empty());
        self.acceleration[0] = base_acceleration(model);
        accelerations.as_mut_slice().fill(0.0);
        self.pass_out(model, data, v, accelerations.as_slice(), external);
        self.bias_and_mass(model, mass);
        if !factor.factor(mass) {
            return false;
        }
        for ((a, given), bias) in accelerations.iter_mut().zip(tau).zip(&self.tau) {
            *a = given - bias;
        }
        factor.solve(accelerations.as_mut_slice());
        factor.inverse_into_using(mass_inverse, mass.as_mut_slice());
        self.add_accelerations(model, accelerations.as_slice());
        self.tau.as_mut_slice().fill(0.0);
        // The pass back writes every entry of the tree's pattern, the only ones the solves read
        // (the last call's solves left the others of each tree's block dense: not cleared).
        self.pass_back::<false>(model, Layout::Rows(factor.places()));
        true
    }

    /// After the pass out at q̈ = 0: the bias efforts into `tau` and the mass matrix from the
    /// composite inertias, summed apart (the pass back of the derivatives sums its own).
    fn bias_and_mass(&mut self, model: &Model, mass: &mut DMatrix<f64>) {
        self.composite.copy_from_slice(&self.inertia);
        self.composite_force.copy_from_slice(&self.force);
        for &k in model.dynamic_joints.iter().rev() {
            let joint = &model.joints[k];
            let (i, parent) = (joint.child, joint.dynamic_parent);
            let (inertia, force) = (self.composite[i], self.composite_force[i]);
            let branch = model.branch_velocities(k);
            for row in joint.v_offset..joint.v_offset + joint.nv() {
                let s = self.columns[row];
                self.tau[row] = s.dot(&force);
                let momentum = inertia.times(&s);
                for &column in branch {
                    mass[(row, column)] = momentum.dot(&self.columns[column]);
                }
            }
            if parent != 0 {
                self.composite[parent] += inertia;
                self.composite_force[parent] += force;
            }
        }
    }

    /// The accelerations `a` added to a pass out made at q̈ = 0: each body's acceleration by
    /// Σ S_j a_j over its branch, its force by its inertia times that, and each column's ∂A by
    /// the change of its parent's acceleration crossed with S.
    fn add_accelerations(&mut self, model: &Model, a: &[f64]) {
        self.acceleration_change[0] = Motion::zeros();
        for &k in &model.dynamic_joints {
            let joint = &model.joints[k];
            let (i, parent) = (joint.child, joint.dynamic_parent);
            let parent_change = self.acceleration_change[parent];
            let mut change = parent_change;
            let own = joint.v_offset..joint.v_offset + joint.nv();
            let (columns, rates) = (&self.columns[own.clone()], &a[own.clone()]);
            for ((s, rate), da) in columns.iter().zip(rates).zip(&mut self.da_dq[own]) {
                change += s * *rate;
                *da += spatial::cross_motion(&parent_change, s);
            }
            self.acceleration_change[i] = change;
            self.acceleration[i] += change;
            self.force[i] += self.inertia[i].times(&change);
        }
    }

    /// Poses, velocities, accelerations, inertias, Coriolis matrices and forces of the bodies
    /// in the fixed frame, and the columns' ∂V, ∂A and ∂A'.
    fn pass_out(&mut self, model: &Model, data: &Data, v: &[f64], a: &[f64], external: &[Force]) {
        for &k in &model.dynamic_joints {
            let joint = &model.joints[k];
            let (i, parent) = (joint.child, joint.dynamic_parent);
            let state = &data.states[k];
            // A turn formed in place: built apart and then copied in, it was read back before
            // its stores had landed (9 % of the pass out); a general product likewise (5 % of
            // Panda's derivatives).
            let (before, after) = self.world.split_at_mut(i);
            match self.turning_axes[k] {
                Some(axis) => turned_into(&before[parent], &state.transform, axis, &mut after[0]),
                None => before[parent].compose_into(&state.transform, &mut after[0]),
            }
            let world = &after[0];
            let (parent_velocity, parent_acceleration) =
                (self.velocity[parent], self.acceleration[parent]);
            let mut own_velocity = Motion::zeros();
            let mut own_acceleration = Motion::zeros();
            for (c, column) in state.subspace.columns().iter().enumerate() {
                let index = joint.v_offset + c;
                let s = match joint.axis_rotation() {
                    Some((axis, scale)) => world.axis_motion_to_parent(axis, scale),
                    None => world.motion_to_parent(column),
                };
                self.columns[index] = s;
                own_velocity += s * v[index];
                own_acceleration += s * a[index];
                self.dv_dq[index] = spatial::cross_motion(&parent_velocity, &s);
            }
            let velocity = parent_velocity + own_velocity;
            self.velocity[i] = velocity;
            let own = joint.v_offset..joint.v_offset + joint.nv();
            // With one velocity, v_j = v_λ + S q̇ and S × S = 0: v_j × S q̇ = ∂V q̇, and
            // ∂A' = 2 v_λ × S = 2 ∂V (two cross products of 6-vectors fewer per joint).
            let single = joint.nv() == 1;
            let velocity_product = if single {
                self.dv_dq[own.start] * v[own.start]
            } else {
                spatial::cross_motion(&velocity, &own_velocity)
            };
            self.acceleration[i] = parent_acceleration + own_acceleration + velocity_product;
            for index in own {
                let (s, dv) = (self.columns[index], self.dv_dq[index]);
                self.da_dq[index] = spatial::cross_motion(&parent_acceleration, &s)
                    + spatial::cross_motion(&parent_velocity, &dv);
                self.da_dv[index] = if single {
                    dv * 2.0
                } else {
                    spatial::cross_motion(&(velocity + parent_velocity), &s)
                };
            }
            let body = &model.dynamic_bodies[i - 1];
            if body.massless {
                self.inertia[i] = RigidInertia::zeros();
                self.coriolis[i] = CoriolisMatrix::zeros();
                self.force[i] = Force::zeros();
            } else {
                let inertia = body.rigid.to_parent(world);
                let motions = spatial::paired(&velocity, &self.acceleration[i]);
                let [momentum, inertial] = spatial::unpaired(&inertia.times_paired(&motions));
                self.inertia[i] = inertia;
                // Formed where it stays: returned through the stack, it was read back before
                // its stores had landed (8 % of the pass out on Talos).
                self.coriolis[i].form(&inertia, &velocity, &momentum);
                self.force[i] = inertial + spatial::cross_force(&velocity, &momentum);
            }
            // Most calls have no external force: none moved to the fixed frame then.
            if external[i] != Force::zeros() {
                self.force[i] -= world.force_to_parent(&external[i]);
            }
        }
    }

    /// The geared rotors as bodies of their carriers' subtrees (the module's documentation): their
    /// inertias, Coriolis matrices and forces added to their carriers', their own efforts n eᵀf_R
    /// on their coordinates with those efforts' derivatives, and the derivatives along their
    /// rates of their carriers' ancestors' efforts. Before the pass back, which sums them.
    fn add_rotors(&mut self, model: &Model, v: &[f64], a: &[f64]) {
        for rotor in &model.rotors {
            let carrier = rotor.carrier;
            let world = &self.world[carrier];
            let local_axis = spatial::twist(rotor.axis, Vector3::zeros());
            // The axis as a motion (n e: the rotor's motion per unit rate) and as a moment (its
            // inertia J ẽẽᵀ, a pure moment about the axis whatever the point).
            let axis = world.motion_to_parent(&local_axis) * rotor.ratio;
            let direction = world.rotation * rotor.axis;
            let inertia = RigidInertia {
                mass: 0.0,
                first: Vector3::zeros(),
                rotational: direction * direction.transpose() * rotor.inertia,
            };
            let (carrier_velocity, carrier_acceleration) =
                (self.velocity[carrier], self.acceleration[carrier]);
            let own = axis * v[rotor.velocity];
            let velocity = carrier_velocity + own;
            let acceleration = carrier_acceleration
                + axis * a[rotor.velocity]
                + spatial::cross_motion(&carrier_velocity, &own);
            let momentum = inertia.times(&velocity);
            let coriolis = CoriolisMatrix::new(&inertia, &velocity, &momentum);
            let force = inertia.times(&acceleration) + spatial::cross_force(&velocity, &momentum);
            let row = rotor.velocity;
            self.tau[row] += axis.dot(&force);
            // Its own effort along the motions of the joints that carry it, …
            let (sensitivity, momentum_of_axis) =
                (coriolis.transpose_times(&axis), inertia.times(&axis));
            let carried = self.carrier_branch(model, carrier);
            for &column in carried {
                self.dtau_dq[(row, column)] += sensitivity.dot(&angular(&self.dv_dq[column]))
                    + momentum_of_axis.dot(&self.da_dq[column]);
                self.dtau_dv[(row, column)] += sensitivity.dot(&angular(&self.columns[column]))
                    + momentum_of_axis.dot(&self.da_dv[column]);
            }
            // … and the efforts of the joints that carry it along its rate (its own effort's
            // part, n eᵀ(B_R n e + I_R (v_R + v_F) × n e), vanishes: I_R is a moment about e).
            let rate_change = coriolis.times(&axis)
                + inertia.times(&spatial::cross_motion(
                    &(velocity + carrier_velocity),
                    &axis,
                ));
            for &carrying in carried {
                self.dtau_dv[(carrying, row)] += self.columns[carrying].dot(&rate_change);
            }
            if carrier != 0 {
                self.inertia[carrier] += inertia;
                self.coriolis[carrier] += coriolis;
                self.force[carrier] += force;
            }
        }
    }

    /// The velocities of the joints that move body `carrier` (none for earth).
    fn carrier_branch<'m>(&self, model: &'m Model, carrier: usize) -> &'m [usize] {
        match carrier {
            0 => &[],
            body => model.branch_velocities(body - 1),
        }
    }

    /// Sums the composites from the leaves and fills τ, ∂τ/∂q and ∂τ/∂v (the module's
    /// documentation): per joint, its rows along its own and its ancestors' columns, and its
    /// ancestors' rows along its columns, each entry of the tree's pattern once: written, or
    /// added to what the rotors gave (`ACCUMULATE`), at its place in `layout`.
    ///
    /// Each entry of ∂τ/∂q is computed beside the same entry of ∂τ/∂v, as one pair of dot
    /// products with the same weights (`paired_dot`): a row's Bᵀs and I s against a column's
    /// (∂V, ∂A) and (S, ∂A'), an ancestor's S against a column's two changes of force. The
    /// pairs are stored side by side so that the processor does both at once, two wide.
    fn pass_back<const ACCUMULATE: bool>(&mut self, model: &Model, layout: Layout) {
        let nv = model.nv;
        let put = |entries: &mut [f64], at: usize, value: f64| {
            let entry = &mut entries[at];
            *entry = if ACCUMULATE { *entry + value } else { value };
        };
        for (velocity, terms) in self.back_terms.iter_mut().enumerate() {
            (terms.row_at, terms.column_at) = match layout {
                Layout::Columns => (velocity, velocity * nv),
                Layout::Rows(places) => (places[velocity] * nv, places[velocity]),
            };
            let (s, dv) = (&self.columns[velocity], &self.dv_dq[velocity]);
            let (da, da_dv) = (&self.da_dq[velocity], &self.da_dv[velocity]);
            for m in 0..3 {
                terms.pairs[m] = f64x2::new([dv[m], s[m]]);
            }
            for m in 0..6 {
                terms.pairs[3 + m] = f64x2::new([da[m], da_dv[m]]);
            }
        }
        for &k in model.dynamic_joints.iter().rev() {
            let joint = &model.joints[k];
            let (i, parent) = (joint.child, joint.dynamic_parent);
            // Read where they are: copied out whole, they were read back before the stores of
            // the child's sums into them had landed.
            let (inertia, coriolis, force) = (&self.inertia[i], &self.coriolis[i], &self.force[i]);
            let own = joint.v_offset..joint.v_offset + joint.nv();
            let branch = model.branch_velocities(k);
            for row in own.clone() {
                let s = self.columns[row];
                self.tau[row] += s.dot(force);
                let (sensitivity, momentum) = (coriolis.transpose_times(&s), inertia.times(&s));
                let weights = [
                    sensitivity.x,
                    sensitivity.y,
                    sensitivity.z,
                    momentum[0],
                    momentum[1],
                    momentum[2],
                    momentum[3],
                    momentum[4],
                    momentum[5],
                ];
                let row_at = self.back_terms[row].row_at;
                for &column in branch {
                    let terms = &self.back_terms[column];
                    let [by_position, by_rate] = paired_dot(&weights, &terms.pairs);
                    let at = row_at + terms.column_at;
                    put(self.dtau_dq.as_mut_slice(), at, by_position);
                    put(self.dtau_dv.as_mut_slice(), at, by_rate);
                }
            }
            for column in own.clone() {
                // The two changes of force side by side (lane 0 along the position, lane 1
                // along the rate): S ×* F + B ∂V + I ∂A and B S + I ∂A'.
                let s = self.columns[column];
                let turning = spatial::cross_force(&s, force);
                let by_coriolis = coriolis.times_paired(&spatial::paired(&self.dv_dq[column], &s));
                let accelerations = spatial::paired(&self.da_dq[column], &self.da_dv[column]);
                let by_inertia = inertia.times_paired(&accelerations);
                let changes: [f64x2; 6] = std::array::from_fn(|m| {
                    f64x2::new([turning[m], 0.0]) + by_coriolis[m] + by_inertia[m]
                });
                // The branch lists the joint's own velocities first, then its ancestors'.
                let column_at = self.back_terms[column].column_at;
                for &row in &branch[joint.nv()..] {
                    let s_row: &[f64; 6] = self.columns[row].as_ref();
                    let [by_position, by_rate] = paired_dot(s_row, &changes);
                    let at = self.back_terms[row].row_at + column_at;
                    put(self.dtau_dq.as_mut_slice(), at, by_position);
                    put(self.dtau_dv.as_mut_slice(), at, by_rate);
                }
            }
            if parent != 0 {
                let (inertia, coriolis, force) = (self.inertia[i], self.coriolis[i], self.force[i]);
                self.inertia[parent] += inertia;
                self.coriolis[parent] += coriolis;
                self.force[parent] += force;
            }
        }
    }
}

/// The axis e_k a joint turns about when its transform's rotation is that turn alone: a
/// rotation about x, y or z from a join frame parallel to its parent's (R_P = 1, as every
/// joint of Talos's URDF), none on the child (see `Kernel::Rotation`).
fn turning_axis(joint: &Joint) -> Option<usize> {
    match &joint.kernel {
        Kernel::Rotation {
            terms,
            aligned: Some(k),
            after: None,
            ..
        } if terms[0] == Matrix3::identity() => Some(*k),
        _ => None,
    }
}

/// `parent * joint` into `out` for a joint whose rotation is a turn about e_k (`turning_axis`): the
/// parent's rotation with its two other columns turned by the angle whose cosine and sine the
/// joint's rotation holds (12 products instead of the product's 27; the same sums, the
/// product's other terms being products by exact zeros and ones).
fn turned_into(parent: &Transform, joint: &Transform, k: usize, out: &mut Transform) {
    let (i, j) = ((k + 1) % 3, (k + 2) % 3);
    let (cos, sin) = (joint.rotation[(i, i)], joint.rotation[(j, i)]);
    turn_columns_into(&parent.rotation, k, sin, cos, &mut out.rotation);
    out.translation = parent.rotation * joint.translation + parent.translation;
}

/// Σ_m w_m p_m for pairs p_m: two dot products with the same weights (each w_m in both lanes),
/// as one two-wide product and sum per term. Written out with `f64x2`: the compiler had left
/// the plain-array form as two scalar chains. The terms are summed in two chains, the even
/// ones and the odd ones, added at the end: one chain of N dependent sums kept the processor
/// waiting on it, where two of half the length let it overlap more entries. N ≥ 2.
#[inline(always)]
fn paired_dot<const N: usize>(weights: &[f64; N], pairs: &[f64x2; N]) -> [f64; 2] {
    const {
        assert!(
            N >= 2,
            "paired_dot starts a chain at each of the first two terms"
        )
    };
    let mut even = f64x2::splat(weights[0]) * pairs[0];
    let mut odd = f64x2::splat(weights[1]) * pairs[1];
    for m in (2..N).step_by(2) {
        even += f64x2::splat(weights[m]) * pairs[m];
        if m + 1 < N {
            odd += f64x2::splat(weights[m + 1]) * pairs[m + 1];
        }
    }
    (even + odd).to_array()
}

/// What the pass back reads of a velocity besides its S (`columns`): as a column,
/// (ω(∂V), ω(S)) then (∂A, ∂A') entry by entry, the pairs a row's Bᵀs and I s weigh, and where
/// its column starts in ∂τ/∂q's and ∂τ/∂v's entries; as a row, where its row starts (`Layout`):
/// entry (r, c) at `row_at` of r + `column_at` of c.
#[derive(Clone, Copy, Default)]
struct BackTerms {
    pairs: [f64x2; 9],
    row_at: usize,
    column_at: usize,
}

/// Where the pass back puts entry (r, c) of ∂τ/∂q and ∂τ/∂v: at r + c nv (nalgebra's order,
/// by columns), or by rows in the order of a mass matrix's factor (`MassFactor::places`), at
/// place(c) + place(r) nv.
#[derive(Clone, Copy)]
enum Layout<'a> {
    Columns,
    Rows(&'a [usize]),
}

/// B m = v ×* (I m) + I (m × v) + m ×* h for a body of inertia I, velocity v = [ω; u] and
/// momentum h = I v = [n; f], all in one frame: the change of its force v ×* I v + I a when its
/// velocity changes by m and its acceleration by m × v. With I = [J ĉ; ĉᵀ m·1] (c the first
/// moment) the blocks multiplying m's linear part cancel (f = m u − c × ω), leaving
/// B = [ω̂J + (ω̂J)ᵀ − c uᵀ − u cᵀ + 2 (u·c) 1 − n̂, 0; −2 ((ω × c)^ + m û), 0]:
/// a 3 × 3 block above and a skew one below, kept as the vector b = −2 (ω × c + m u) it
/// crosses with (b̂ w = b × w, b̂ᵀ x = x × b); sums of such matrices stay of that form for a
/// subtree.
#[derive(Clone, Copy, Debug)]
struct CoriolisMatrix {
    top: Matrix3<f64>,
    bottom: Vector3<f64>,
}

impl CoriolisMatrix {
    fn zeros() -> CoriolisMatrix {
        CoriolisMatrix {
            top: Matrix3::zeros(),
            bottom: Vector3::zeros(),
        }
    }

    fn new(inertia: &RigidInertia, velocity: &Motion, momentum: &Force) -> CoriolisMatrix {
        let mut matrix = CoriolisMatrix::zeros();
        matrix.form(inertia, velocity, momentum);
        matrix
    }

    /// `new` in place.
    fn form(&mut self, inertia: &RigidInertia, velocity: &Motion, momentum: &Force) {
        let (w, u) = (spatial::angular(velocity), spatial::linear(velocity));
        let c = inertia.first;
        // P = ω̂J − c uᵀ column by column (ω̂ times a column is a cross product: no products
        // by the skew matrix's zeros), then top = P + Pᵀ + 2 (u·c) 1 − n̂.
        let j = &inertia.rotational;
        let half = Matrix3::from_columns(&[
            w.cross(&j.column(0).into_owned()) - c * u.x,
            w.cross(&j.column(1).into_owned()) - c * u.y,
            w.cross(&j.column(2).into_owned()) - c * u.z,
        ]);
        self.top = half + half.transpose() + Matrix3::identity() * (2.0 * u.dot(&c))
            - spatial::skew(&spatial::angular(momentum));
        self.bottom = -2.0 * (w.cross(&c) + u * inertia.mass);
    }

    /// B m (a force): only m's angular part counts.
    fn times(&self, m: &Motion) -> Force {
        let w = spatial::angular(m);
        spatial::twist(self.top * w, self.bottom.cross(&w))
    }

    /// `times` for two motions at once, side by side in two lanes (`spatial::paired`):
    /// only their angular parts count.
    fn times_paired(&self, m: &spatial::Paired) -> spatial::Paired {
        let w = [m[0], m[1], m[2]];
        let [t0, t1, t2] = spatial::matrix_times_paired(&self.top, &w);
        let [b0, b1, b2] = spatial::cross_paired(&self.bottom, &w);
        [t0, t1, t2, b0, b1, b2]
    }

    /// Bᵀ s, as a motion's angular part to dot with (its linear part is zero: a dot product
    /// with a motion m is one with m's angular part).
    fn transpose_times(&self, s: &Motion) -> Vector3<f64> {
        self.top.tr_mul(&spatial::angular(s)) + spatial::linear(s).cross(&self.bottom)
    }
}

impl std::ops::AddAssign for CoriolisMatrix {
    fn add_assign(&mut self, other: CoriolisMatrix) {
        self.top += other.top;
        self.bottom += other.bottom;
    }
}
