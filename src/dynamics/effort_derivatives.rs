//! The derivatives of the program's efforts with respect to the state, through the compiled
//! tape in forward mode (`Tape::tangents_prefix_into`): springs, dampers, forces and torques
//! whatever their laws, on trees.
//!
//! The efforts enter the dynamics as generalised forces G(q, v) = τ_links + Σ_b J_bᵀ f_b, with
//! f_b the wrench on body b in its own frame (as RNEA takes it). RNEA's analytical derivatives
//! (`rnea_derivatives`) hold f_b fixed in the bodies' frames, and so account for J_b's own
//! change; what is left, computed here, is
//!
//!   D = ∂τ_links/∂x + Σ_b J_bᵀ ∂f_b/∂x,   x = (q, v),
//!
//! so that the residual r = G − RNEA(q, v, a; 0) of the equations of motion changes by
//! D − ∂RNEA/∂x|_f (the tree Jacobian, `simulate::system::jacobian`), and forward dynamics by
//! M⁻¹ D more than ABA's derivatives at fixed efforts.
//!
//! Everything is written in the fixed frame, where the derivative along q_c (a velocity of the
//! joint whose motion in the fixed frame is S_c = (ω_c, v_c)) moves every body of the joint's
//! subtree rigidly by S_c: a point p by ω_c × p + v_c, a rotation R by [ω_c]× R, a body's
//! velocity V_b by S_c × (V_b − V_λ) with λ the joint's parent (Carpentier & Mansard, RSS
//! 2018, the convention `rnea_derivatives` takes); the derivative along q̇_c adds S_c to V_b.
//! These give the derivatives of the frames' states the tape reads (positions, velocities,
//! angular velocities, orientations), of the declared coordinates and rates (a tree's joints
//! declare their own), and through the tape those of every effort's value. A wrench F in the
//! fixed frame is then split into its rigid change S_c ×* F (RNEA's part) and the rest, whose
//! generalised forces S_kᵀ(·) over the body's branch are D's column.
//!
//! Covered: trees whose joints are dof chains with constant subspaces (those RNEA's
//! derivatives cover), forces and torques applied on frames, link efforts in a joint's own
//! frame; not the actuators' laws, the programs' states, friction, nor link efforts in a
//! step's frame (`covers` names the first that is not).

use nalgebra::{DMatrix, Matrix3, Vector3};

use super::algorithms::rnea_derivatives::check_supported;
use super::algorithms::Data;
use super::compiled::{EffortState, Source};
use super::efforts::Declared;
use super::joint::JointType;
use super::model::{AppliedGroup, Model};
use crate::elab::mechanism::EffortKind;
use crate::elab::value::FrameQuantity;
use crate::kinematics::eval::EvalError;
use crate::kinematics::model::ChainMotion;
use crate::spatial::{
    angular, cross_force, cross_motion, linear, motion_to_parent, skew, twist, Force, Motion,
};
use crate::symbolic::expr::tangents::Tangents;

/// Why the efforts' derivatives are not computed for a model: the first effort or structure
/// they do not cover.
pub fn covers(model: &Model) -> Result<(), &'static str> {
    if model.has_loops() || model.nc > 0 {
        return Err("a mechanism with loops");
    }
    if model.joints.iter().any(|j| j.kind != JointType::Chain) {
        return Err("a spherical or free joint");
    }
    if check_supported(model).is_err() {
        return Err("a dof chain whose subspace moves with its coordinates");
    }
    if model.actuation.is_some() {
        return Err("an actuator's law");
    }
    if !model.states.is_empty() {
        return Err("a state of the program");
    }
    if !model.frictions.is_empty() {
        return Err("friction");
    }
    let simple_link = |k: usize| {
        let joint = model.joints.get(k);
        joint.is_some_and(|j| j.nv() > 0 && j.nv() == j.chain.coordinate_count())
    };
    if (model.link_efforts.iter()).any(|e| e.step != 0 || !simple_link(e.joint)) {
        return Err("a link effort in a step's frame or on a joint without velocity");
    }
    if model.has_efforts() && model.effort_tape.is_err() {
        return Err("an effort the tape cannot evaluate");
    }
    Ok(())
}

/// The efforts' derivatives and their scratch; `new(&model)` once per model.
pub struct EffortDerivatives {
    /// D = ∂G/∂(q, v) with the bodies' Jacobians held (module documentation): nv × 2nv, the
    /// columns along q then along v.
    pub efforts: DMatrix<f64>,
    /// The gradient along (q, v) of the power of the efforts that derive from no potential.
    pub power: Vec<f64>,
    /// Per velocity, its joint's motion in the fixed frame S_c, and its joint's parent body.
    columns: Vec<Motion>,
    column_parent: Vec<usize>,
    /// Per body (0 earth), its velocity in the fixed frame.
    velocity: Vec<Motion>,
    /// Whether velocity c moves body b, at c (bodies + 1) + b: the branches as a table, read
    /// for every direction of every effort.
    moving: Vec<bool>,
    /// Per declared coordinate, the velocity it is (a tree's joints declare their own).
    declared_velocity: Vec<Option<usize>>,
    symbol_tangents: Vec<f64>,
    tangents: Tangents,
    /// Per direction, a wrench's change in the fixed frame and the rigid part removed.
    wrench_change: Vec<Force>,
    chain: ChainMotion,
}

impl EffortDerivatives {
    pub fn new(model: &Model) -> EffortDerivatives {
        let nv = model.nv;
        let mut declared_velocity = vec![None; model.declared_count];
        for (joint, &offset) in model.joints.iter().zip(&model.declared_offsets) {
            if joint.kind == JointType::Chain {
                let n = joint.chain.coordinate_count().min(joint.nv());
                for c in 0..n {
                    declared_velocity[offset + c] = Some(joint.v_offset + c);
                }
            }
        }
        let bodies = model.body_count() + 1;
        let mut moving = vec![false; nv * bodies];
        for body in 1..bodies {
            for &c in model.branch_velocities(body - 1) {
                moving[c * bodies + body] = true;
            }
        }
        EffortDerivatives {
            efforts: DMatrix::zeros(nv, 2 * nv),
            moving,
            power: vec![0.0; 2 * nv],
            columns: vec![Motion::zeros(); nv],
            column_parent: vec![0; nv],
            velocity: vec![Motion::zeros(); model.body_count() + 1],
            declared_velocity,
            symbol_tangents: Vec::new(),
            tangents: Tangents {
                directions: 2 * nv,
                ..Tangents::default()
            },
            wrench_change: vec![Force::zeros(); 2 * nv],
            chain: ChainMotion::default(),
        }
    }

    /// D and the power's gradient at the state `declared` gives, at `time`; `data` holds the
    /// forward kinematics of (q, v) and the model is covered ([`covers`]).
    pub fn compute(
        &mut self,
        model: &Model,
        data: &mut Data,
        declared: &Declared<'_>,
        time: f64,
    ) -> Result<(), EvalError> {
        self.efforts.fill(0.0);
        self.power.fill(0.0);
        if !model.has_efforts() {
            return Ok(());
        }
        self.motions(model, data);
        let tape = model.effort_tape.as_ref().map_err(Clone::clone)?;
        self.symbol_tangents_of(model, data, tape.sources());
        let state = EffortState {
            world: &data.world,
            velocity: &data.velocity,
            coordinates: declared.coordinates,
            rates: declared.rates,
            states: declared.states,
            time,
            model: &[],
        };
        let (symbols, out) = (&self.symbol_tangents, &mut self.tangents);
        tape.eval_tangents(
            &model.effort_frames,
            &state,
            symbols,
            &mut data.efforts,
            out,
        );
        for group in &model.applied_groups {
            let body_velocity = self.velocity[group.body];
            self.applied(model, data, group, group.value_roots);
            self.add_generalised(model, group.body);
            if let Some(roots) = group.nonconservative_roots {
                let wrench = self.applied(model, data, group, roots);
                // P = F·V_b: its change F'·V_b (`wrench_change` holds F' with the rigid
                // part taken off, which adds S_c ×* F; (S_c ×* F)·V = −F·(S_c × V)) and F·V_b'.
                for x in 0..2 * model.nv {
                    let change = self.wrench_change[x] + self.rigid(model, group.body, x, &wrench);
                    let moved = self.velocity_change(model, group.body, x);
                    self.power[x] += change.dot(&body_velocity) + wrench.dot(&moved);
                }
            }
        }
        self.add_links(model, declared)?;
        Ok(())
    }

    /// The tape's tangents at the last [`EffortDerivatives::compute`] (read a root's with
    /// `EffortTape::root_tangent`), and the symbols' derivatives they started from (symbol
    /// i's along the 2 nv directions at `[2 nv i..2 nv (i + 1)]`). Read only by the tests'
    /// dual-number oracle, so built only where the library's internals are public.
    #[cfg(lsdc_internals)]
    pub fn tape_tangents(&self) -> (&Tangents, &[f64]) {
        (&self.tangents, &self.symbol_tangents)
    }

    /// The joints' motions S_c and the bodies' velocities, in the fixed frame.
    fn motions(&mut self, model: &Model, data: &Data) {
        self.velocity[0] = Motion::zeros();
        for (k, joint) in model.joints.iter().enumerate() {
            let body = joint.child;
            let world = &data.world[body];
            self.velocity[body] = motion_to_parent(world, &data.velocity[body]);
            let columns = data.states[k].subspace.columns();
            for (c, column) in columns.iter().enumerate() {
                self.columns[joint.v_offset + c] = motion_to_parent(world, column);
                self.column_parent[joint.v_offset + c] = joint.dynamic_parent;
            }
        }
    }

    /// Whether velocity `c` moves body `body`.
    fn moves(&self, c: usize, body: usize) -> bool {
        self.moving[c * self.velocity.len() + body]
    }

    /// The rigid displacement of `body` along direction x (a q's; none along the v's).
    fn displacement(&self, model: &Model, body: usize, x: usize) -> Motion {
        match x < model.nv && self.moves(x, body) {
            true => self.columns[x],
            false => Motion::zeros(),
        }
    }

    /// The change of `body`'s velocity along direction x: S_c × (V_b − V_λ) along q_c, S_c
    /// along q̇_c.
    fn velocity_change(&self, model: &Model, body: usize, x: usize) -> Motion {
        let nv = model.nv;
        let c = x % nv;
        if !self.moves(c, body) {
            return Motion::zeros();
        }
        if x >= nv {
            return self.columns[c];
        }
        let relative = self.velocity[body] - self.velocity[self.column_parent[c]];
        cross_motion(&self.columns[c], &relative)
    }

    /// The change of F moving rigidly with `body` along direction x: S_c ×* F.
    fn rigid(&self, model: &Model, body: usize, x: usize, wrench: &Force) -> Force {
        cross_force(&self.displacement(model, body, x), wrench)
    }

    /// Each symbol's derivatives along (q, v), by rows of 2 nv.
    fn symbol_tangents_of(&mut self, model: &Model, data: &Data, sources: &[Source]) {
        let d = 2 * model.nv;
        self.symbol_tangents.clear();
        self.symbol_tangents.resize(sources.len() * d, 0.0);
        for (i, source) in sources.iter().enumerate() {
            let mut row = std::mem::take(&mut self.symbol_tangents);
            let row_of = &mut row[i * d..(i + 1) * d];
            match *source {
                // Neither the time nor the model's values in actuated coordinates (the
                // actuators are not covered) move with the state.
                Source::Time | Source::State(_) | Source::Model(_) => {}
                Source::Coordinate(k) => {
                    if let Some(c) = self.declared_velocity[k] {
                        row_of[c] = 1.0;
                    }
                }
                Source::Rate(k) => {
                    if let Some(c) = self.declared_velocity[k] {
                        row_of[model.nv + c] = 1.0;
                    }
                }
                Source::Frame(k, quantity) => self.frame_tangent(model, data, k, quantity, row_of),
            }
            self.symbol_tangents = row;
        }
    }

    /// The derivatives of one component of effort frame k's state along (q, v).
    fn frame_tangent(
        &self,
        model: &Model,
        data: &Data,
        k: usize,
        quantity: FrameQuantity,
        row: &mut [f64],
    ) {
        let nv = model.nv;
        let frame = &model.effort_frames[k];
        let body = frame.body;
        if body == 0 {
            return;
        }
        let world = &data.world[body];
        let point = world.translation.vector + world.rotation * frame.offset.translation.vector;
        let velocity = self.velocity[body];
        for &c in model.branch_velocities(body - 1) {
            let s = self.columns[c];
            let moved = angular(&s).cross(&point) + linear(&s);
            match quantity {
                FrameQuantity::Position(i) => row[c] = moved[i as usize],
                FrameQuantity::Velocity(i) => {
                    // ṗ = V_lin + V_ang × p.
                    let change = self.velocity_change(model, body, c);
                    let along_q = linear(&change)
                        + angular(&change).cross(&point)
                        + angular(&velocity).cross(&moved);
                    row[c] = along_q[i as usize];
                    row[nv + c] = moved[i as usize];
                }
                FrameQuantity::AngularVelocity(i) => {
                    let change = self.velocity_change(model, body, c);
                    row[c] = angular(&change)[i as usize];
                    row[nv + c] = angular(&s)[i as usize];
                }
                FrameQuantity::Orientation(i, j) => {
                    let rotation: Matrix3<f64> = *(world.rotation * frame.offset.rotation)
                        .to_rotation_matrix()
                        .matrix();
                    row[c] = (skew(&angular(&s)) * rotation)[(i as usize, j as usize)];
                }
            }
        }
    }

    /// An applied group's wrench F in the fixed frame (about its origin) from the roots
    /// `roots` of its value, and its changes along every direction into `wrench_change`, the
    /// rigid part S_c ×* F taken off.
    fn applied(
        &mut self,
        model: &Model,
        data: &Data,
        group: &AppliedGroup,
        roots: [usize; 3],
    ) -> Force {
        let tape = model.effort_tape.as_ref().expect("checked by `compute`");
        let out = &self.tangents;
        let value = Vector3::from_fn(|i, _| tape.root_value(out, roots[i]));
        let basis = match group.basis {
            0 => Matrix3::identity(),
            b => *data.world[b].rotation.to_rotation_matrix().matrix(),
        };
        let world = &data.world[group.body];
        let point = world.translation.vector + world.rotation * group.point;
        let direction = basis * value;
        let wrench_of = |direction: Vector3<f64>, point: Vector3<f64>| match group.kind {
            EffortKind::Force => twist(point.cross(&direction), direction),
            EffortKind::Torque => twist(direction, Vector3::zeros()),
        };
        let wrench = wrench_of(direction, point);
        for x in 0..2 * model.nv {
            let value_change = Vector3::from_fn(|i, _| tape.root_tangent(out, roots[i])[x]);
            let turned = angular(&self.displacement(model, group.basis, x));
            let direction_change = basis * value_change + turned.cross(&direction);
            let moved = self.displacement(model, group.body, x);
            let change = match group.kind {
                EffortKind::Force => {
                    let point_change = angular(&moved).cross(&point) + linear(&moved);
                    twist(
                        point_change.cross(&direction) + point.cross(&direction_change),
                        direction_change,
                    )
                }
                EffortKind::Torque => twist(direction_change, Vector3::zeros()),
            };
            self.wrench_change[x] = change - cross_force(&moved, &wrench);
        }
        wrench
    }

    /// Adds J_bᵀ of `wrench_change` (a wrench's change on `body`, in the fixed frame) to D.
    fn add_generalised(&mut self, model: &Model, body: usize) {
        if body == 0 {
            return;
        }
        for &c in model.branch_velocities(body - 1) {
            let s = self.columns[c];
            for (x, change) in self.wrench_change.iter().enumerate() {
                self.efforts[(c, x)] += s.dot(change);
            }
        }
    }

    /// The link efforts' generalised forces twistᵀ w on their joints' velocities (the twists
    /// constant: one-velocity chains in their own frame), and their powers.
    fn add_links(&mut self, model: &Model, declared: &Declared<'_>) -> Result<(), EvalError> {
        let tape = model.effort_tape.as_ref().map_err(Clone::clone)?;
        let nv = model.nv;
        for effort in &model.link_efforts {
            let joint = &model.joints[effort.joint];
            let offset = model.declared_offsets[effort.joint];
            let n = joint.chain.coordinate_count();
            let coordinates = &declared.coordinates[offset..offset + n];
            joint
                .chain
                .chain_motion_into(coordinates, None, &mut self.chain)?;
            let out = &self.tangents;
            let value = Vector3::from_fn(|i, _| tape.root_value(out, effort.value_roots[i]));
            let as_wrench = |v: Vector3<f64>| match effort.kind {
                EffortKind::Force => twist(Vector3::zeros(), v),
                EffortKind::Torque => twist(v, Vector3::zeros()),
            };
            let wrench = as_wrench(value);
            for (k, twist_k) in self.chain.subspace.column_iter().enumerate() {
                let row = joint.v_offset + k;
                let on_declared = twist_k.dot(&wrench);
                for x in 0..2 * nv {
                    let change =
                        Vector3::from_fn(|i, _| tape.root_tangent(out, effort.value_roots[i])[x]);
                    let along = twist_k.dot(&as_wrench(change));
                    self.efforts[(row, x)] += along;
                    if !effort.conservative {
                        self.power[x] += along * declared.rates[offset + k];
                    }
                }
                if !effort.conservative {
                    self.power[nv + row] += on_declared;
                }
            }
        }
        Ok(())
    }
}
