//! The recursive algorithms, each `algorithm(&model, &mut data, ...)`: forward kinematics and
//! velocities, inverse dynamics (RNEA: one pass out, one back), the mass matrix (CRBA) and
//! forward dynamics (ABA: three passes). Bodies without mass cost nothing. Geared rotors enter
//! all three (`geared`). RNEA is linear in the bodies' inertial parameters: its regressor is
//! `regressor`.

pub mod aba_derivatives;
pub mod crba_derivatives;
mod geared;
pub(crate) mod hybrid;
mod mass_factor;
pub(crate) mod mass_solve;
pub mod regressor;
pub mod rnea_derivatives;

use nalgebra::{DMatrix, DVector, Matrix6, Vector3, Vector6};

use super::compiled::EffortScratch;
use super::joint::JointState;
use super::model::Model;
use super::scalar::DynamicsScalar;
use crate::kinematics::eval::EvalError;
use crate::spatial::{self, constant, Force, Inertia, Motion, Pose, Real, RigidInertia, Transform};

/// Scratch space for the algorithms; `Data::new(&model)` once, reuse for every call.
///
/// RNEA and ABA compute in the scalar `T` (`DynamicsScalar`): `f64`, or dual numbers that
/// differentiate them (`Data::with_scalar`). The mass matrix, the efforts and the geared
/// rotors' rows are computed in `f64` only; their scratch is there whatever `T`.
pub struct Data<T: Real = f64> {
    pub states: Vec<JointState<T>>,
    /// World pose, velocity and acceleration of body i at index i (0 is earth), in body frame.
    pub world: Vec<Pose<T>>,
    pub velocity: Vec<Motion<T>>,
    pub acceleration: Vec<Motion<T>>,
    pub force: Vec<Force<T>>,
    /// CRBA's poses, composite inertias and motion columns in the fixed frame.
    mass_scratch: MassScratch,
    articulated: Vec<Inertia<T>>,
    bias: Vec<Force<T>>,
    coriolis: Vec<Motion<T>>,
    /// ABA per joint: U = I S (one force per velocity), D⁻¹ = (Sᵀ U)⁻¹ and u = τ − Sᵀ p.
    u: Vec<[Force<T>; 6]>,
    d_inverse: Vec<Matrix6<T>>,
    u_vector: Vec<Vector6<T>>,
    /// Where the efforts' tape is evaluated.
    pub efforts: EffortScratch,
    /// Geared rotors (empty without any): the bodies' motions for one unit velocity, that unit
    /// velocity, each rotor's row w of spin rates per velocity (rotors × nv), and each rotor's
    /// own effort n ε·τ_r and torque τ_r on its carrier, in the carrier's frame (see
    /// `add_rotors_to_mass`, `add_rotor_torques`).
    rotor_motions: Vec<Motion>,
    rotor_unit: Vec<f64>,
    rotor_rows: DMatrix<f64>,
    rotor_own: Vec<T>,
    rotor_torques: Vec<Vector3<T>>,
    /// ABA with geared rotors: per joint, the rotor it drives (empty without any); per rotor,
    /// U_R = I_R S_R and its velocity-product acceleration relative to its carrier's
    /// (`Data::aba_rotor_step` in `geared`).
    rotor_of_joint: Vec<Option<usize>>,
    rotor_u: Vec<Force<T>>,
    rotor_coriolis: Vec<Motion<T>>,
}

#[derive(Clone, Debug, PartialEq)]
pub enum DynamicsError {
    Evaluation(EvalError),
    /// The articulated inertia of a joint is singular: the bodies it carries have no inertia
    /// along some of its motions (joint index, body number).
    Singular {
        joint: usize,
        body: usize,
    },
}

impl From<EvalError> for DynamicsError {
    fn from(e: EvalError) -> Self {
        DynamicsError::Evaluation(e)
    }
}

impl Data {
    pub fn new(model: &Model) -> Data {
        Data::with_scalar(model)
    }
}

impl<T: Real> Data<T> {
    /// Per geared rotor, its own effort n ε·τ_r on its coordinate at the last pass out of
    /// inverse dynamics (`rnea_forward`).
    pub fn rotor_efforts(&self) -> &[T] {
        &self.rotor_own
    }

    /// Scratch for the algorithms in the scalar `T` (`Data::new` for `f64`).
    pub fn with_scalar(model: &Model) -> Data<T> {
        let n = model.body_count();
        let geared = !model.rotors.is_empty();
        Data {
            states: model.joints.iter().map(|j| j.new_state()).collect(),
            world: vec![Pose::identity(); n + 1],
            velocity: vec![Motion::zeros(); n + 1],
            acceleration: vec![Motion::zeros(); n + 1],
            force: vec![Force::zeros(); n + 1],
            mass_scratch: MassScratch::new(model),
            articulated: vec![Inertia::zeros(); n + 1],
            bias: vec![Force::zeros(); n + 1],
            coriolis: vec![Motion::zeros(); n + 1],
            u: vec![[Force::zeros(); 6]; n + 1],
            d_inverse: vec![Matrix6::zeros(); n + 1],
            u_vector: vec![Vector6::zeros(); n + 1],
            efforts: EffortScratch::default(),
            rotor_motions: vec![Motion::zeros(); if geared { n + 1 } else { 0 }],
            rotor_unit: vec![0.0; if geared { model.nv } else { 0 }],
            rotor_rows: DMatrix::zeros(model.rotors.len(), model.nv),
            rotor_own: vec![T::zero(); model.rotors.len()],
            rotor_torques: vec![Vector3::zeros(); model.rotors.len()],
            rotor_of_joint: rotors_of_joints(model),
            rotor_u: vec![Force::zeros(); model.rotors.len()],
            rotor_coriolis: vec![Motion::zeros(); model.rotors.len()],
        }
    }
}

/// Per joint, the geared rotor it drives; empty when the model has none.
fn rotors_of_joints(model: &Model) -> Vec<Option<usize>> {
    if model.rotors.is_empty() {
        return Vec::new();
    }
    let mut rotors = vec![None; model.joints.len()];
    for (r, rotor) in model.rotors.iter().enumerate() {
        rotors[rotor.joint] = Some(r);
    }
    rotors
}

/// The geared rotor joint `k` drives, if any.
fn rotor_of<T: Real>(data: &Data<T>, k: usize) -> Option<usize> {
    data.rotor_of_joint.get(k).copied().flatten()
}

fn slice<T>(values: &[T], offset: usize, count: usize) -> &[T] {
    &values[offset..offset + count]
}

/// Joint states, world poses and body velocities at (q, v).
pub fn forward_kinematics<T: DynamicsScalar>(
    model: &Model,
    data: &mut Data<T>,
    q: &[T],
    v: &[T],
) -> Result<(), EvalError> {
    for k in 0..model.joints.len() {
        joint_motion(model, data, k, q, v)?;
        let joint = &model.joints[k];
        let state = &mut data.states[k];
        joint.fill_pose(state);
        data.world[joint.child] = data.world[joint.dynamic_parent] * state.pose;
    }
    Ok(())
}

/// What the recursive algorithms need of the kinematics: the states and body velocities of the
/// joints they visit at (q, v), without the world poses (RNEA and ABA leave `data.world` and the
/// merged bodies as they were).
fn joint_motions<T: DynamicsScalar>(
    model: &Model,
    data: &mut Data<T>,
    q: &[T],
    v: &[T],
) -> Result<(), EvalError> {
    joint_states(model, data, q, v)?;
    for &k in &model.dynamic_joints {
        body_velocity(model, data, k);
    }
    Ok(())
}

/// The joints' own states (transforms, subspaces, velocities across them) at (q, v), without
/// the bodies' velocities in their own frames (`joint_motions`): the derivatives form theirs in
/// the fixed frame.
fn joint_states<T: DynamicsScalar>(
    model: &Model,
    data: &mut Data<T>,
    q: &[T],
    v: &[T],
) -> Result<(), EvalError> {
    // Independent of one another, they overlap in the processor.
    for &k in &model.dynamic_joints {
        let joint = &model.joints[k];
        joint.update(
            slice(q, joint.q_offset, joint.nq()),
            slice(v, joint.v_offset, joint.nv()),
            &mut data.states[k],
        )?;
    }
    Ok(())
}

fn joint_motion<T: DynamicsScalar>(
    model: &Model,
    data: &mut Data<T>,
    k: usize,
    q: &[T],
    v: &[T],
) -> Result<(), EvalError> {
    let joint = &model.joints[k];
    joint.update(
        slice(q, joint.q_offset, joint.nq()),
        slice(v, joint.v_offset, joint.nv()),
        &mut data.states[k],
    )?;
    body_velocity(model, data, k);
    Ok(())
}

/// The velocity of joint k's child and its velocity-product acceleration, from its parent's.
fn body_velocity<T: Real>(model: &Model, data: &mut Data<T>, k: usize) {
    let joint = &model.joints[k];
    let state = &data.states[k];
    let (i, parent) = (joint.child, joint.dynamic_parent);
    data.velocity[i] = state.transform.motion_to_child(&data.velocity[parent]) + state.velocity;
    data.coriolis[i] = state.bias + spatial::cross_motion(&data.velocity[i], &state.velocity);
}

/// Fills `data.acceleration` with the bodies' accelerations when every joint acceleration is
/// zero (the velocity-product terms alone); `data` must hold the forward kinematics of (q, v).
pub fn bias_accelerations<T: Real>(model: &Model, data: &mut Data<T>) {
    for (k, joint) in model.joints.iter().enumerate() {
        let (i, parent) = (joint.child, joint.dynamic_parent);
        data.acceleration[i] = data.states[k]
            .transform
            .motion_to_child(&data.acceleration[parent])
            + data.coriolis[i];
    }
}

/// The acceleration given to the base (earth) so that the bodies feel the gravity field: an
/// upward acceleration g is the same as a downward field −g (Einstein's elevator). The bodies'
/// accelerations in `Data` after RNEA and ABA include it.
fn base_acceleration<T: Real>(model: &Model) -> Motion<T> {
    let g = model.gravity;
    Motion::new(0.0, 0.0, 0.0, -g.x, -g.y, -g.z).cast()
}

/// Inverse dynamics: the generalised forces that give accelerations `a` at (q, v) under the
/// external forces `external` (one per body, in its frame; index 0 unused).
pub fn rnea<T: DynamicsScalar>(
    model: &Model,
    data: &mut Data<T>,
    q: &[T],
    v: &[T],
    a: &[T],
    external: &[Force<T>],
) -> Result<DVector<T>, EvalError> {
    let mut tau = DVector::zeros(model.nv);
    rnea_into(model, data, q, v, a, external, &mut tau)?;
    Ok(tau)
}

/// RNEA writing the generalised forces into `tau` (length nv).
#[allow(clippy::too_many_arguments)]
pub fn rnea_into<T: DynamicsScalar>(
    model: &Model,
    data: &mut Data<T>,
    q: &[T],
    v: &[T],
    a: &[T],
    external: &[Force<T>],
    tau: &mut DVector<T>,
) -> Result<(), EvalError> {
    joint_motions(model, data, q, v)?;
    rnea_after_kinematics(model, data, a, external, tau);
    Ok(())
}

/// `rnea_into` when `data` already holds the forward kinematics of (q, v)
/// (`forward_kinematics`): the joints' states are not computed again.
pub fn rnea_after_kinematics<T: Real>(
    model: &Model,
    data: &mut Data<T>,
    a: &[T],
    external: &[Force<T>],
    tau: &mut DVector<T>,
) {
    rnea_forward(model, data, a, external);
    rnea_backward(model, data, tau);
}

/// RNEA's pass out, when `data` holds the forward kinematics: each body's acceleration under
/// the joint accelerations `a` (and gravity), and in `data.force` the force it needs beyond
/// the external one, I aᵢ + vᵢ × I vᵢ − fᵢ (in its frame), geared rotors' torques on their
/// carriers included (`add_rotor_torques`). Their power along any motion of the joints x is
/// xᵀ times the generalised forces, less the rotors' own efforts on their coordinates:
/// Σ vᵢ(x)·Fᵢ = xᵀτ − Σ x_r n ε·τ_r (`body_motions`, `Data::rotor_efforts`).
pub fn rnea_forward<T: Real>(model: &Model, data: &mut Data<T>, a: &[T], external: &[Force<T>]) {
    let base = base_acceleration(model);
    for &k in &model.dynamic_joints {
        let joint = &model.joints[k];
        let (i, parent) = (joint.child, joint.dynamic_parent);
        let state = &data.states[k];
        let joint_acceleration = state.subspace.apply(slice(a, joint.v_offset, joint.nv()));
        let parent_acceleration = if parent == 0 {
            &base
        } else {
            &data.acceleration[parent]
        };
        data.acceleration[i] = state.transform.motion_to_child(parent_acceleration)
            + joint_acceleration
            + data.coriolis[i];
        let body = &model.dynamic_bodies[i - 1];
        data.force[i] = if body.massless {
            -external[i]
        } else {
            let momentum = body.rigid.times(&data.velocity[i]);
            body.rigid.times(&data.acceleration[i])
                + spatial::cross_force(&data.velocity[i], &momentum)
                - external[i]
        };
    }
    data.add_rotor_torques(model, a);
}

/// RNEA's pass back: the generalised forces `tau` (length nv) from the bodies' forces that
/// `rnea_forward` left in `data.force` (which it accumulates from child to parent), and the
/// geared rotors' own efforts on their coordinates.
pub fn rnea_backward<T: Real>(model: &Model, data: &mut Data<T>, tau: &mut DVector<T>) {
    for &k in model.dynamic_joints.iter().rev() {
        let joint = &model.joints[k];
        let (i, parent) = (joint.child, joint.dynamic_parent);
        let state = &data.states[k];
        state.subspace.project(
            &data.force[i],
            &mut tau.as_mut_slice()[joint.v_offset..joint.v_offset + joint.nv()],
        );
        if parent != 0 {
            let transmitted = state.transform.force_to_parent(&data.force[i]);
            data.force[parent] += transmitted;
        }
    }
    for (rotor, effort) in model.rotors.iter().zip(&data.rotor_own) {
        tau[rotor.velocity] += *effort;
    }
}

/// The wrench each joint transmits to its child (and the bodies beyond), in the child's frame,
/// after `rnea` with the same external forces: every body counts, merged welds included, so a
/// weld's reaction is its own, and so does each geared rotor's torque on its carrier (the rate
/// of its spin's angular momentum, which the carrier's bearings and the gear supply: a moment
/// alone, the rotor's mass being the carrier's). `data` must also hold the forward kinematics
/// of the state.
pub fn transmitted_wrenches(model: &Model, data: &Data, external: &[Force]) -> Vec<Force> {
    let n = model.body_count();
    let mut acceleration = data.acceleration.clone();
    let mut force = vec![Force::zeros(); n + 1];
    let mut merged = vec![true; model.joints.len()];
    for &k in &model.dynamic_joints {
        merged[k] = false;
    }
    // Earth's acceleration as the recursions have it: −g, the weights' field.
    acceleration[0] = base_acceleration(model);
    for (k, joint) in model.joints.iter().enumerate() {
        let i = joint.child;
        if merged[k] {
            // A merged body moves with its anchor (earth for a base welded to it): its
            // transform is its pose there.
            acceleration[i] = data.states[k]
                .transform
                .motion_to_child(&acceleration[joint.dynamic_parent]);
        }
        let body = &model.bodies[i - 1];
        force[i] = if body.massless {
            -external[i]
        } else {
            let momentum = body.inertia * data.velocity[i];
            body.inertia * acceleration[i] + spatial::cross_force(&data.velocity[i], &momentum)
                - external[i]
        };
    }
    for (rotor, torque) in model.rotors.iter().zip(&data.rotor_torques) {
        // A rotor's carrier is not merged into another body (E0453).
        if rotor.carrier != 0 {
            force[rotor.carrier] += pure_moment(torque);
        }
    }
    for (k, joint) in model.joints.iter().enumerate().rev() {
        if joint.parent != 0 {
            // The child's pose in its parent: through the parent's pose in their common anchor.
            let in_parent = model.anchor_offsets[joint.parent].inverse() * data.states[k].transform;
            let transmitted = in_parent.force_to_parent(&force[joint.child]);
            force[joint.parent] += transmitted;
        }
    }
    force
}

/// The motion of every body (in its own frame, index = body, 0 for earth) when the joints
/// move with velocities `x` (length nv) from the state whose joint transforms `data` holds:
/// one pass out from the root, v_i = X_i v_parent + S_i x_i. `motions` has one entry per body
/// and earth. With the bodies' inertias, xᵀMy = Σ v_i(x)ᵀ I_i v_i(y): the mass matrix's
/// bilinear form, without the mass matrix.
pub fn body_motions<T: Real>(model: &Model, data: &Data<T>, x: &[T], motions: &mut [Motion<T>]) {
    motions[0] = Motion::zeros();
    for &k in &model.dynamic_joints {
        let joint = &model.joints[k];
        let state = &data.states[k];
        let (i, parent) = (joint.child, joint.dynamic_parent);
        let own = state.subspace.apply(slice(x, joint.v_offset, joint.nv()));
        motions[i] = if parent == 0 {
            own
        } else {
            state.transform.motion_to_child(&motions[parent]) + own
        };
    }
}

/// Forward dynamics: the accelerations under generalised forces `tau` and external forces.
pub fn aba<T: DynamicsScalar>(
    model: &Model,
    data: &mut Data<T>,
    q: &[T],
    v: &[T],
    tau: &[T],
    external: &[Force<T>],
) -> Result<DVector<T>, DynamicsError> {
    let mut accelerations = DVector::zeros(model.nv);
    aba_into(model, data, q, v, tau, external, &mut accelerations)?;
    Ok(accelerations)
}

/// ABA writing the accelerations into `accelerations` (length nv).
#[allow(clippy::too_many_arguments)]
pub fn aba_into<T: DynamicsScalar>(
    model: &Model,
    data: &mut Data<T>,
    q: &[T],
    v: &[T],
    tau: &[T],
    external: &[Force<T>],
    accelerations: &mut DVector<T>,
) -> Result<(), DynamicsError> {
    joint_motions(model, data, q, v)?;
    aba_after_kinematics(model, data, tau, external, accelerations)
}

/// ABA when `data` already holds the forward kinematics of the state (`forward_kinematics`,
/// which the efforts need first): the joints' motions are not computed a second time.
pub fn aba_after_kinematics<T: Real>(
    model: &Model,
    data: &mut Data<T>,
    tau: &[T],
    external: &[Force<T>],
    accelerations: &mut DVector<T>,
) -> Result<(), DynamicsError> {
    aba_body_terms(model, data, external);
    for &k in model.dynamic_joints.iter().rev() {
        let joint = &model.joints[k];
        match (rotor_of(data, k), joint.axis_rotation()) {
            (Some(r), _) => data.aba_rotor_step(model, k, r, tau[joint.v_offset])?,
            (None, Some(axis)) => {
                aba_backward_axis_step(model, data, k, axis, tau[joint.v_offset])?
            }
            (None, None) => {
                aba_backward_step(model, data, k, slice(tau, joint.v_offset, joint.nv()))?
            }
        }
    }
    let base = base_acceleration(model);
    for &k in &model.dynamic_joints {
        aba_forward_step(
            model,
            data,
            k,
            &base,
            accelerations,
            JointAcceleration::Solved,
        );
    }
    Ok(())
}

/// ABA's first pass: each body's own inertia as its articulated inertia, and its bias force
/// (the velocity product v ×* I v less the external force), before the backward pass.
fn aba_body_terms<T: Real>(model: &Model, data: &mut Data<T>, external: &[Force<T>]) {
    for &k in &model.dynamic_joints {
        let i = model.joints[k].child;
        let body = &model.dynamic_bodies[i - 1];
        data.articulated[i] = body.inertia.cast();
        data.bias[i] = if body.massless {
            -external[i]
        } else {
            let momentum = body.rigid.times(&data.velocity[i]);
            spatial::cross_force(&data.velocity[i], &momentum) - external[i]
        };
    }
}

/// Whether ABA's forward pass solves a joint's accelerations or reads them as given (hybrid
/// dynamics, `hybrid.rs`).
#[derive(Clone, Copy, PartialEq, Eq)]
enum JointAcceleration {
    Solved,
    Known,
}

/// One joint of ABA's forward pass: the child's acceleration from its parent's, with the
/// joint's q̈ = D⁻¹ (u − Uᵀ a) written into `accelerations` (the rotor's term included), or,
/// for a `Known` joint, read from it.
fn aba_forward_step<T: Real>(
    model: &Model,
    data: &mut Data<T>,
    k: usize,
    base: &Motion<T>,
    accelerations: &mut DVector<T>,
    joint_acceleration: JointAcceleration,
) {
    let joint = &model.joints[k];
    let (i, parent) = (joint.child, joint.dynamic_parent);
    let state = &data.states[k];
    let n = joint.nv();
    let parent_acceleration = if parent == 0 {
        base
    } else {
        &data.acceleration[parent]
    };
    let a = state.transform.motion_to_child(parent_acceleration) + data.coriolis[i];
    let out = &mut accelerations.as_mut_slice()[joint.v_offset..joint.v_offset + n];
    if joint_acceleration == JointAcceleration::Solved {
        let mut rhs = Vector6::zeros();
        for c in 0..n {
            rhs[c] = data.u_vector[i][c] - data.u[i][c].dot(&a);
        }
        if let Some(r) = rotor_of(data, k) {
            rhs[0] -= data.rotor_acceleration_term(model, k, r, parent_acceleration, &a);
        }
        for (r, o) in out.iter_mut().enumerate() {
            // From −0, as `Iterator::sum` of f64 starts.
            *o = (0..n).fold(-T::zero(), |sum, c| {
                sum + data.d_inverse[i][(r, c)] * rhs[c]
            });
        }
    }
    data.acceleration[i] = a + state.subspace.apply(out);
}

/// One joint of ABA's backward pass: U, D⁻¹ and u, then the articulated inertia and bias
/// handed to the parent. Works in place in `data` (these blocks are a few hundred bytes each).
fn aba_backward_step<T: Real>(
    model: &Model,
    data: &mut Data<T>,
    k: usize,
    tau: &[T],
) -> Result<(), DynamicsError> {
    let joint = &model.joints[k];
    let (i, parent) = (joint.child, joint.dynamic_parent);
    let Data {
        states,
        articulated,
        bias,
        coriolis,
        u,
        d_inverse,
        u_vector,
        ..
    } = data;
    let state = &states[k];
    let subspace = &state.subspace;
    let n = subspace.len();
    let inertia = articulated[i];
    let (u, d_inverse, u_vector) = (&mut u[i], &mut d_inverse[i], &mut u_vector[i]);
    for (uc, s) in u.iter_mut().zip(subspace.columns()) {
        *uc = inertia * s;
    }
    if n == 1 {
        let d = subspace.column(0).dot(&u[0]);
        if !(d.abs() > constant(1e-300) && d.is_finite()) {
            return Err(DynamicsError::Singular { joint: k, body: i });
        }
        d_inverse[(0, 0)] = d.recip();
    } else if n > 1 {
        // D padded with the identity beyond n, so the fixed-size inverse serves every joint.
        let mut d = Matrix6::identity();
        for r in 0..n {
            for c in 0..n {
                d[(r, c)] = subspace.column(r).dot(&u[c]);
            }
        }
        match d.try_inverse().filter(|inv| {
            inv.iter().all(|x| x.is_finite()) && d.determinant().abs() > constant(1e-300)
        }) {
            Some(inv) => *d_inverse = inv,
            None => return Err(DynamicsError::Singular { joint: k, body: i }),
        }
    }
    for c in 0..n {
        u_vector[c] = tau[c] - subspace.column(c).dot(&bias[i]);
    }
    if parent != 0 {
        // Ia − U D⁻¹ Uᵀ and pa + Ia c + U D⁻¹ u, with W = U D⁻¹.
        let mut reduced = inertia;
        let mut correction = Force::zeros();
        for c in 0..n {
            let w: Force<T> = (0..n).fold(Force::zeros(), |sum, r| sum + u[r] * d_inverse[(r, c)]);
            reduced -= w * u[c].transpose();
            correction += w * u_vector[c];
        }
        let handed = bias[i] + reduced * coriolis[i] + correction;
        articulated[parent] += state.transform.inertia_to_parent(&reduced);
        bias[parent] += state.transform.force_to_parent(&handed);
    }
    Ok(())
}

/// `aba_backward_step` for a joint whose subspace is one axis column [s e_k; 0] (a revolute
/// about x, y or z with no frame on the child, as URDF's: `Joint::axis_rotation`), without the
/// products by the column's zeros (as CRBA's axis columns): U = I S is column k of I times s,
/// D = s² I_kk and u = τ − s p_k. The reduced inertia Ia − U Uᵀ/D is symmetric: its entries
/// on and above the diagonal are computed and mirrored. Equal to the general step to
/// round-off.
fn aba_backward_axis_step<T: Real>(
    model: &Model,
    data: &mut Data<T>,
    k: usize,
    (axis, scale): (usize, f64),
    tau: T,
) -> Result<(), DynamicsError> {
    let joint = &model.joints[k];
    let (i, parent) = (joint.child, joint.dynamic_parent);
    let s: T = constant(scale);
    // The child's articulated inertia is read in place (the parent's, before it, is written):
    // no copy of its 36 entries.
    let (before, after) = data.articulated.split_at_mut(i);
    let inertia = &after[0];
    let u: Force<T> = inertia.column(axis) * s;
    let d = u[axis] * s;
    if !(d.abs() > constant(1e-300) && d.is_finite()) {
        return Err(DynamicsError::Singular { joint: k, body: i });
    }
    let d_inverse = d.recip();
    let u_scalar = tau - data.bias[i][axis] * s;
    data.u[i][0] = u;
    data.d_inverse[i][(0, 0)] = d_inverse;
    data.u_vector[i][0] = u_scalar;
    if parent != 0 {
        // Ia − W Uᵀ and pa + Ia c + W u, with W = U D⁻¹: every entry of `reduced` is written.
        let w = u * d_inverse;
        let mut reduced = Inertia::<T>::zeros();
        for column in 0..6 {
            for row in 0..=column {
                let value = inertia[(row, column)] - w[row] * u[column];
                reduced[(row, column)] = value;
                reduced[(column, row)] = value;
            }
        }
        let transform = &data.states[k].transform;
        let handed = data.bias[i] + reduced * data.coriolis[i] + w * u_scalar;
        before[parent] += transform.inertia_to_parent(&reduced);
        data.bias[parent] += transform.force_to_parent(&handed);
    }
    Ok(())
}

// Geared rotors (see `rotors`; their terms of CRBA, RNEA and ABA are in `geared`): their
// spin and its energy.

/// The rate of a one-coordinate joint, from its state's motion S q̇.
fn joint_rate<T: Real>(data: &Data<T>, joint: usize) -> T {
    let state = &data.states[joint];
    let column = state.subspace.column(0);
    column.dot(&state.velocity) / column.norm_squared()
}

fn angular<T: Real>(motion: &Motion<T>) -> Vector3<T> {
    motion.fixed_rows::<3>(0).into_owned()
}

/// The rotor's spin rate ε·ω_B + n q̇ from the body velocities in `data`.
fn spin<T: Real>(rotor: &super::rotors::Rotor, data: &Data<T>) -> T {
    rotor_spin(rotor, &data.velocity, joint_rate(data, rotor.joint))
}

/// The rotors' kinetic energy, ½ J (ε·ω_B + n q̇)² each, from the kinematics in `data`.
pub fn rotor_kinetic_energy(model: &Model, data: &Data) -> f64 {
    let spin_energy = |r: &super::rotors::Rotor| 0.5 * r.inertia * spin(r, data).powi(2);
    model.rotors.iter().map(spin_energy).sum()
}

/// A rotor's spin rate ε·ω_B + n q̇ under a motion of the joints whose body motions are
/// `motions` (`body_motions`) and whose rate of the rotor's coordinate is `rate`.
pub fn rotor_spin<T: Real>(rotor: &super::rotors::Rotor, motions: &[Motion<T>], rate: T) -> T {
    rotor.axis.cast().dot(&angular(&motions[rotor.carrier])) + rate * constant(rotor.ratio)
}

/// Adds the rotors' J w wᵀ to the mass matrix, `data` holding the joint transforms at q.
pub fn add_rotors_to_mass(model: &Model, data: &mut Data, mass: &mut DMatrix<f64>) {
    data.add_rotor_inertias(model, mass);
}

/// A force that is a moment alone.
fn pure_moment<T: Real>(moment: &Vector3<T>) -> Force<T> {
    spatial::twist(*moment, Vector3::zeros())
}

// The mass matrix.
// The joint-space mass matrix M(q) by composite rigid bodies (Featherstone, "Rigid Body
// Dynamics Algorithms", 2008, §6.2), in the fixed frame: each body's inertia is moved to the
// fixed frame once (10 numbers: mass, first moment, rotational inertia about the origin,
// `RigidInertia`), composites are then plain sums, and every entry is a dot product of a
// joint's motion column (in the fixed frame) with a composite momentum: no force is carried
// from joint to joint.
//
// Measured against the local-frame form (Featherstone's Table 6.2, Pinocchio's
// `Convention::LOCAL`: composites summed from the leaves, each moved to its parent's frame, and
// the force set I_c S of a joint's subtree moved up once per ancestor) on UR5, Panda and Talos:
// about the same instructions per call, but 1.07 to 1.14 times the CPU time, 1.24 to 1.28 times
// with the unit axes of URDF joints read as one entry (BENCHMARKS.md, "Peers"). Here the bodies'
// moves to the fixed frame depend only on their world transforms (a short chain of 3 × 3
// products), so the processor overlaps them; in the local form each composite waits for all of
// its children's. Each body's move to the fixed frame splits its rotational inertia as
// Pinocchio's `Symmetric3::rotate` does (`RigidInertia::to_parent_by_split`), and the pass from
// the leaves both completes the composites and writes the columns; with the one-rotation joints'
// transforms written in place (`Joint::update_transform`), 12 % fewer instructions per call on
// UR5 and Talos (BENCHMARKS.md, "CRBA: the inertias' split").

/// CRBA's scratch: per body its pose and composite inertia in the fixed frame, per velocity its
/// motion column in the fixed frame.
pub struct MassScratch {
    world_transform: Vec<Transform>,
    composite: Vec<RigidInertia>,
    world_columns: Vec<Motion>,
}

impl MassScratch {
    pub fn new(model: &Model) -> MassScratch {
        MassScratch {
            world_transform: vec![Transform::identity(); model.body_count() + 1],
            composite: vec![RigidInertia::zeros(); model.body_count() + 1],
            world_columns: vec![Motion::zeros(); model.nv],
        }
    }
}

/// The joint-space mass matrix M(q) (composite rigid bodies).
pub fn crba(model: &Model, data: &mut Data, q: &[f64]) -> Result<DMatrix<f64>, EvalError> {
    let mut mass = DMatrix::zeros(model.nv, model.nv);
    crba_into(model, data, q, &mut mass)?;
    Ok(mass)
}

/// The mass matrix written into `mass` (nv × nv). Only the entries between joints on one
/// branch (a joint and its ancestors) are written: the others are zero in every mass matrix,
/// so `mass` must be zero there (a zero matrix, or one this function filled before). Leaves the
/// joint transforms at q in `data` (not the velocities, nor the world poses).
pub fn crba_into(
    model: &Model,
    data: &mut Data,
    q: &[f64],
    mass: &mut DMatrix<f64>,
) -> Result<(), EvalError> {
    joint_transforms(model, data, q)?;
    crba_after_kinematics(model, data, mass);
    Ok(())
}

/// The joints' transforms (and motion subspaces) at q in `data`, without their velocities: what
/// the mass matrix and the bodies' motions under given rates (`body_motions`) read.
pub fn joint_transforms(model: &Model, data: &mut Data, q: &[f64]) -> Result<(), EvalError> {
    // Independent of one another, they overlap in the processor.
    for &k in &model.dynamic_joints {
        let joint = &model.joints[k];
        joint.update_transform(slice(q, joint.q_offset, joint.nq()), &mut data.states[k])?;
    }
    Ok(())
}

/// `crba_into` when `data` already holds the joints' transforms at q (`forward_kinematics`).
pub fn crba_after_kinematics(model: &Model, data: &mut Data, mass: &mut DMatrix<f64>) {
    let MassScratch {
        world_transform,
        composite,
        world_columns,
    } = &mut data.mass_scratch;
    for &k in &model.dynamic_joints {
        let joint = &model.joints[k];
        let state = &data.states[k];
        let (i, parent) = (joint.child, joint.dynamic_parent);
        // The fixed frame's own pose is the identity: no product at the root.
        let world = if parent == 0 {
            state.transform
        } else {
            world_transform[parent] * state.transform
        };
        world_transform[i] = world;
        let own = &model.dynamic_bodies[i - 1];
        composite[i] = if own.massless {
            RigidInertia::zeros()
        } else {
            own.rigid.to_parent_by_split(&world)
        };
        match joint.axis_rotation() {
            Some((k, scale)) => {
                world_columns[joint.v_offset] = world.axis_motion_to_parent(k, scale)
            }
            None => {
                for (r, column) in state.subspace.columns().iter().enumerate() {
                    world_columns[joint.v_offset + r] = world.motion_to_parent(column);
                }
            }
        }
    }
    // From the leaves: a joint's composite is whole when the pass reaches it (its children come
    // after it), so its columns are written and it is handed to its parent in one visit.
    let nv = model.nv;
    let entries = mass.as_mut_slice();
    for &k in model.dynamic_joints.iter().rev() {
        let joint = &model.joints[k];
        let (i, parent) = (joint.child, joint.dynamic_parent);
        let own = &composite[i];
        // The joint's branch lists its own and its ancestors' velocities.
        let branch = model.branch_velocities(k);
        for column in joint.v_offset..joint.v_offset + joint.nv() {
            let force = own.times(&world_columns[column]);
            // Column-major storage.
            for &row in branch {
                let value = world_columns[row].dot(&force);
                entries[row + column * nv] = value;
                entries[column + row * nv] = value;
            }
        }
        if parent != 0 {
            let (before, after) = composite.split_at_mut(i);
            before[parent] += after[0];
        }
    }
    add_rotors_to_mass(model, data, mass);
}

/// The rows of each column of `model`'s mass matrix that the composite-rigid-body algorithm
/// writes (`crba_after_kinematics`): the others are zero whatever the state.
pub fn mass_rows(model: &Model) -> Vec<Vec<usize>> {
    let mut rows = vec![Vec::new(); model.nv];
    for &k in &model.dynamic_joints {
        let joint = &model.joints[k];
        for column in joint.v_offset..joint.v_offset + joint.nv() {
            for &row in model.branch_velocities(k) {
                rows[column].push(row);
                if row != column {
                    rows[row].push(column);
                }
            }
        }
    }
    rows.iter_mut().for_each(|r| {
        r.sort_unstable();
        r.dedup();
    });
    rows
}

/// y = M x over the entries `rows` lists, column after column: the sums of a dense product
/// in the same order, without its products by zero.
pub fn mass_times(mass: &DMatrix<f64>, rows: &[Vec<usize>], x: &[f64], y: &mut [f64]) {
    y.fill(0.0);
    let nv = mass.nrows();
    let entries = mass.as_slice();
    for (column, (rows, &xj)) in rows.iter().zip(x).enumerate() {
        let entries = &entries[column * nv..(column + 1) * nv];
        for &row in rows {
            y[row] += entries[row] * xj;
        }
    }
}
