//! The efforts compiled once, when the model is built: every applied effort's value and
//! potential, every link effort's value and every link potential lowered into one hash-consed
//! expression DAG (the `Pool` of the symbolic back end) and evaluated as one tape per state.
//!
//! Written as trees, efforts repeat themselves: a spring's `distance(a, b)` appears in each
//! component of its `direction(a, b)`, `between` repeats the whole force negated, a damper
//! repeats the spring's geometry. In the pool each distinct subexpression is one node, and the
//! tape evaluates it once. Everything an effort refers to is resolved to a slot when the tape is
//! built: unknowns become constants (their values are known by then), join coordinates and
//! rates become positions in the declared state, frames become the state of one of the model's
//! `effort_frames` (computed once per evaluation from the forward kinematics).

use std::collections::HashMap;

use nalgebra::{Matrix3, Vector3};
use num_dual::Dual64;

use super::elements::EffortFrame;
use crate::elab::value::{FrameQuantity, SExpr, Scalar, Vector};
use crate::kinematics::eval::{EvalError, UnknownValues};
use crate::spatial::{Motion, Pose};
use crate::symbolic::expr::tangents::Tangents;
use crate::symbolic::expr::{ExprId, Pool, Tape};
use crate::symbolic::program::{lower_structure, Lower};

/// What a symbol of the tape stands for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Source {
    Time,
    /// A declared coordinate of the whole mechanism.
    Coordinate(usize),
    /// A declared rate.
    Rate(usize),
    /// A component of the state of `effort_frames[k]`.
    Frame(usize, FrameQuantity),
    /// The value of the program's state `k` (`state(x0)`).
    State(usize),
    /// One of the model's values in the actuated coordinates (`reduced_model`): Mₐ by rows,
    /// then Nₐ, then Gₐ.
    Model(usize),
}

/// Which of the model's quantities the laws read (the others are not computed).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ModelReads {
    pub mass: bool,
    pub bias: bool,
    pub gravity: bool,
}

impl ModelReads {
    pub fn any(&self) -> bool {
        self.mass || self.bias || self.gravity
    }

    /// Adds the quantities that the calls in `s` read (`inverse_dynamics` was written with
    /// `mass_matrix` and `bias`).
    pub fn add_calls(&mut self, s: &Scalar) {
        let calls = |name: &'static str| {
            s.any(&|e| matches!(e, SExpr::Call(call) if call.function == name))
        };
        self.mass |= calls("mass_matrix");
        self.bias |= calls("bias");
        self.gravity |= calls("gravity_effort");
    }

    /// The quantity at `slot` of the model's values (Mₐ by rows, Nₐ, Gₐ) for m coordinates.
    pub fn add_slot(&mut self, slot: usize, m: usize) {
        match slot {
            s if s < m * m => self.mass = true,
            s if s < m * m + m => self.bias = true,
            _ => self.gravity = true,
        }
    }
}

/// The compiled efforts: one tape whose roots are every effort's components.
#[derive(Clone, Debug)]
pub struct EffortTape {
    tape: Tape,
    /// Where each root's value lies among the tape's values.
    slots: Vec<usize>,
    /// The tape's first nodes that the efforts' values need (the potentials come after).
    values_end: usize,
    /// The source of each symbol, in the order of the symbols' indices.
    sources: Vec<Source>,
    /// Per effort frame, which parts of its state the tape reads.
    needs: Vec<Needs>,
}

/// The parts of a frame's state an effort reads: its position is cheap, the rest is computed
/// only when used (a spring reads positions only; a damper also velocities).
#[derive(Clone, Copy, Debug, Default)]
struct Needs {
    velocity: bool,
    angular_velocity: bool,
    orientation: bool,
}

impl Needs {
    fn add(&mut self, quantity: FrameQuantity) {
        match quantity {
            FrameQuantity::Position(_) => {}
            FrameQuantity::Velocity(_) => self.velocity = true,
            FrameQuantity::AngularVelocity(_) => self.angular_velocity = true,
            FrameQuantity::Orientation(..) => self.orientation = true,
        }
    }
}

/// The state an effort tape reads: the declared coordinates and rates of every join, the
/// values of the program's states, the time, and the forward kinematics of the state (each
/// body's pose and velocity, for the frames).
pub struct EffortState<'a> {
    pub world: &'a [Pose],
    pub velocity: &'a [Motion],
    pub coordinates: &'a [f64],
    pub rates: &'a [f64],
    pub states: &'a [f64],
    pub time: f64,
    /// The model's values in the actuated coordinates, for the laws that read them (empty
    /// for the others).
    pub model: &'a [f64],
}

/// Where an effort tape is evaluated: kept from one evaluation to the next, so that evaluating
/// allocates nothing once the buffers have their sizes.
#[derive(Clone, Debug, Default)]
pub struct EffortScratch {
    frames: Vec<FrameValues>,
    symbols: Vec<f64>,
    values: Vec<f64>,
}

impl EffortTape {
    /// Evaluates the efforts' values at `state`, and with `energy` the potentials too, into
    /// `scratch`; read the roots with [`EffortTape::root`].
    pub fn eval(
        &self,
        frames: &[EffortFrame],
        state: &EffortState<'_>,
        energy: bool,
        scratch: &mut EffortScratch,
    ) {
        self.symbols_into(frames, state, scratch);
        let count = if energy {
            self.tape.size()
        } else {
            self.values_end
        };
        self.tape
            .eval_prefix_into(&scratch.symbols, &mut scratch.values, count);
    }

    /// The symbols' values at `state` into `scratch.symbols`.
    fn symbols_into(
        &self,
        frames: &[EffortFrame],
        state: &EffortState<'_>,
        scratch: &mut EffortScratch,
    ) {
        scratch.frames.clear();
        scratch.frames.extend(
            frames
                .iter()
                .zip(&self.needs)
                .map(|(f, needs)| FrameValues::new(state, f.body, &f.offset, *needs)),
        );
        scratch.symbols.clear();
        scratch
            .symbols
            .extend(self.sources.iter().map(|source| match *source {
                Source::Time => state.time,
                Source::Coordinate(i) => state.coordinates[i],
                Source::Rate(i) => state.rates[i],
                Source::State(k) => state.states[k],
                Source::Frame(k, quantity) => scratch.frames[k].component(quantity),
                // Outputs read by a study that computes no model see NaN.
                Source::Model(k) => state.model.get(k).copied().unwrap_or(f64::NAN),
            }));
    }

    /// The efforts' values (not the potentials) and their derivatives along `out.directions`
    /// directions, symbol i's derivatives being `symbol_tangents[i * d..(i + 1) * d]`
    /// (forward mode through the tape, `Tape::tangents_prefix_into`); read them with
    /// [`EffortTape::root_tangent`] and [`EffortTape::root_value`].
    pub fn eval_tangents(
        &self,
        frames: &[EffortFrame],
        state: &EffortState<'_>,
        symbol_tangents: &[f64],
        scratch: &mut EffortScratch,
        out: &mut Tangents,
    ) {
        self.symbols_into(frames, state, scratch);
        (self.tape).tangents_prefix_into(&scratch.symbols, symbol_tangents, self.values_end, out);
    }

    /// The efforts' values and derivatives along direction `direction` of `symbol_tangents`
    /// (`directions` per symbol, as [`EffortTape::eval_tangents`] reads them), from the symbols
    /// of the last evaluation into `scratch`, by the tape in dual numbers
    /// (`Tape::eval_dual_prefix`): the oracle of the tangent mode, a root per effort component
    /// as [`EffortTape::root`] numbers them (the potentials' zero).
    pub fn eval_dual(
        &self,
        scratch: &EffortScratch,
        symbol_tangents: &[f64],
        (directions, direction): (usize, usize),
    ) -> Vec<Dual64> {
        let symbols: Vec<Dual64> = (scratch.symbols.iter().enumerate())
            .map(|(i, &x)| Dual64::new(x, symbol_tangents[i * directions + direction]))
            .collect();
        let values = self.tape.eval_dual_prefix(&symbols, self.values_end);
        self.slots.iter().map(|&slot| values[slot]).collect()
    }

    /// The value of root `k` after [`EffortTape::eval`].
    pub fn root(&self, scratch: &EffortScratch, k: usize) -> f64 {
        scratch.values[self.slots[k]]
    }

    /// The value of root `k` after [`EffortTape::eval_tangents`].
    pub fn root_value(&self, out: &Tangents, k: usize) -> f64 {
        out.values[self.slots[k]]
    }

    /// The derivatives of root `k` after [`EffortTape::eval_tangents`].
    pub fn root_tangent<'t>(&self, out: &'t Tangents, k: usize) -> &'t [f64] {
        out.of(self.slots[k])
    }

    /// What each symbol stands for, in the order of the symbols' indices.
    pub fn sources(&self) -> &[Source] {
        &self.sources
    }

    /// Whether the tape reads a declared coordinate or rate in `range`.
    pub fn reads_declared(&self, range: std::ops::Range<usize>) -> bool {
        self.sources.iter().any(|source| match *source {
            Source::Coordinate(i) | Source::Rate(i) => range.contains(&i),
            _ => false,
        })
    }

    /// Whether the tape reads the time.
    pub fn reads_time(&self) -> bool {
        self.sources.contains(&Source::Time)
    }

    /// What the tape reads of the model, for `m` actuated coordinates.
    pub fn model_reads(&self, m: usize) -> ModelReads {
        let mut reads = ModelReads::default();
        for source in &self.sources {
            if let Source::Model(slot) = *source {
                reads.add_slot(slot, m);
            }
        }
        reads
    }

    /// Number of distinct nodes evaluated per state.
    pub fn size(&self) -> usize {
        self.tape.size()
    }
}

/// Where an expression's link coordinates (`Coordinate { index, .. }`) lie among the declared
/// coordinates: at `offset` for a link effort or potential, nowhere for an applied effort.
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub struct Link(pub Option<usize>);

/// Lowers expressions into one pool, then builds the tape of all of them.
pub struct TapeBuilder<'a> {
    pool: Pool,
    sources: Vec<Source>,
    roots: Vec<ExprId>,
    /// The roots only the energy needs (potentials), by index among `roots`.
    energy_only: Vec<usize>,
    unknowns: &'a UnknownValues,
    frames: &'a [EffortFrame],
    declared_offset: &'a dyn Fn(crate::elab::value::JoinId) -> Option<usize>,
    /// Subexpressions already lowered, by address and link: programs share subtrees (`let`).
    lowered: HashMap<(*const SExpr, Link), ExprId>,
    /// The link of the expression being lowered.
    link: Link,
    /// The actuated coordinates (declared indices), along which the model is read.
    model_coordinates: Vec<usize>,
}

impl<'a> TapeBuilder<'a> {
    pub fn new(
        unknowns: &'a UnknownValues,
        frames: &'a [EffortFrame],
        declared_offset: &'a dyn Fn(crate::elab::value::JoinId) -> Option<usize>,
    ) -> TapeBuilder<'a> {
        TapeBuilder {
            pool: Pool::new(),
            sources: Vec::new(),
            roots: Vec::new(),
            energy_only: Vec::new(),
            unknowns,
            frames,
            declared_offset,
            lowered: HashMap::new(),
            link: Link(None),
            model_coordinates: Vec::new(),
        }
    }

    /// The builder of laws that read the model along the actuated coordinates `coordinates`
    /// (declared indices, in order).
    pub fn reading_model(mut self, coordinates: Vec<usize>) -> TapeBuilder<'a> {
        self.model_coordinates = coordinates;
        self
    }

    /// Adds a potential's root, evaluated only when the energy is asked for; returns its index
    /// among the roots.
    pub fn potential(&mut self, s: &SExpr, link: Link) -> Result<usize, EvalError> {
        let id = self.lower_in(s, link)?;
        self.roots.push(id);
        self.energy_only.push(self.roots.len() - 1);
        Ok(self.roots.len() - 1)
    }

    /// Adds a scalar's root; returns its index among the roots.
    pub fn scalar(&mut self, s: &SExpr, link: Link) -> Result<usize, EvalError> {
        let id = self.lower_in(s, link)?;
        self.roots.push(id);
        Ok(self.roots.len() - 1)
    }

    /// Adds the three components of a vector; returns their indices among the tape's values.
    pub fn vector(&mut self, v: &Vector, link: Link) -> Result<[usize; 3], EvalError> {
        let lowered = self.lower_vector(v, link)?;
        Ok(self.vector_root(lowered))
    }

    /// A vector's components in the pool, not yet roots.
    pub fn lower_vector(&mut self, v: &Vector, link: Link) -> Result<[ExprId; 3], EvalError> {
        Ok([
            self.lower_in(&v[0], link)?,
            self.lower_in(&v[1], link)?,
            self.lower_in(&v[2], link)?,
        ])
    }

    /// The componentwise sum of two lowered vectors.
    pub fn add_vectors(&mut self, a: [ExprId; 3], b: [ExprId; 3]) -> [ExprId; 3] {
        [0, 1, 2].map(|i| self.pool.add(a[i], b[i]))
    }

    /// Makes a lowered vector's components roots; returns their indices among the values.
    pub fn vector_root(&mut self, v: [ExprId; 3]) -> [usize; 3] {
        v.map(|id| {
            self.roots.push(id);
            self.roots.len() - 1
        })
    }

    /// The tape of every root, the efforts' values first: evaluating without the energy stops
    /// after the nodes they reach.
    pub fn build(self) -> EffortTape {
        let mut needs = vec![Needs::default(); self.frames.len()];
        for source in &self.sources {
            if let Source::Frame(k, quantity) = *source {
                needs[k].add(quantity);
            }
        }
        let is_value = |k: &usize| !self.energy_only.contains(k);
        let values: Vec<usize> = (0..self.roots.len()).filter(is_value).collect();
        let order: Vec<usize> = values.iter().chain(&self.energy_only).copied().collect();
        let reordered: Vec<ExprId> = order.iter().map(|&k| self.roots[k]).collect();
        let tape = Tape::new(&self.pool, &reordered);
        let mut slots = vec![0; self.roots.len()];
        for (position, &k) in order.iter().enumerate() {
            slots[k] = tape.roots[position];
        }
        let values_end = values.iter().map(|&k| slots[k] + 1).max().unwrap_or(0);
        EffortTape {
            tape,
            slots,
            values_end,
            sources: self.sources,
            needs,
        }
    }

    fn symbol(&mut self, source: Source) -> ExprId {
        let name = format!("{source:?}");
        let id = self.pool.symbol(&name);
        if self.pool.symbol_index(id) == Some(self.sources.len()) {
            self.sources.push(source);
        }
        id
    }

    fn lower_in(&mut self, s: &SExpr, link: Link) -> Result<ExprId, EvalError> {
        self.link = link;
        self.lower(s)
    }

    fn coordinate(&mut self, index: usize, order: u32) -> Result<ExprId, EvalError> {
        match order {
            0 => Ok(self.symbol(Source::Coordinate(index))),
            1 => Ok(self.symbol(Source::Rate(index))),
            _ => Err(EvalError::NotGeometric("a second time derivative")),
        }
    }
}

impl Lower for TapeBuilder<'_> {
    type Error = EvalError;

    fn pool(&mut self) -> &mut Pool {
        &mut self.pool
    }

    /// Subexpressions already lowered (by address and link) are reused: programs share
    /// subtrees (`let`).
    fn lower(&mut self, s: &SExpr) -> Result<ExprId, EvalError> {
        let key = (s as *const SExpr, self.link);
        if let Some(&id) = self.lowered.get(&key) {
            return Ok(id);
        }
        let id = lower_structure(self, s)?;
        self.lowered.insert(key, id);
        Ok(id)
    }

    fn leaf(&mut self, s: &SExpr) -> Result<ExprId, EvalError> {
        Ok(match s {
            SExpr::Time => self.symbol(Source::Time),
            SExpr::State(id) => self.symbol(Source::State(id.0 as usize)),
            SExpr::Unknown(id) => {
                let value = *self.unknowns.get(id).ok_or(EvalError::Missing(*id))?;
                self.pool.constant(value)
            }
            SExpr::UnknownFunction(call) => return Err(EvalError::Missing(call.function)),
            SExpr::Coordinate { index, order } => {
                let offset = self
                    .link
                    .0
                    .ok_or(EvalError::NotGeometric("a coordinate of another link"))?;
                self.coordinate(offset + *index as usize, *order)?
            }
            SExpr::JoinCoordinate { join, index, order } => {
                let offset = (self.declared_offset)(*join)
                    .ok_or(EvalError::NotGeometric("a coordinate of a join"))?;
                self.coordinate(offset + *index as usize, *order)?
            }
            SExpr::FrameState(frame, quantity) => {
                let k = self
                    .frames
                    .iter()
                    .position(|f| *f.frame == **frame)
                    .ok_or(EvalError::NotGeometric("a frame outside the mechanism"))?;
                match self.frames[k].body {
                    // A frame of earth does not move: its state is a constant.
                    0 => self
                        .pool
                        .constant(earth_frame(&self.frames[k].offset, *quantity)),
                    _ => self.symbol(Source::Frame(k, *quantity)),
                }
            }
            _ => unreachable!("numbers, arithmetic and calls are lowered by their structure"),
        })
    }

    /// `mass_matrix(a, b)`, `bias(a)`, `gravity_effort(a)`: the model's value at its slot.
    fn model_quantity(&mut self, name: &str, args: &[Scalar]) -> Result<ExprId, EvalError> {
        let not_actuated =
            EvalError::NotGeometric("the model along a coordinate that is not actuated");
        let index = |s: &Scalar| -> Result<usize, EvalError> {
            let SExpr::JoinCoordinate {
                join,
                index,
                order: 0,
            } = **s
            else {
                return Err(not_actuated.clone());
            };
            let declared =
                (self.declared_offset)(join).ok_or(not_actuated.clone())? + index as usize;
            let found = self.model_coordinates.iter().position(|&c| c == declared);
            found.ok_or(not_actuated.clone())
        };
        let m = self.model_coordinates.len();
        let slot = match (name, args) {
            ("mass_matrix", [a, b]) => index(a)? * m + index(b)?,
            ("bias", [a]) => m * m + index(a)?,
            ("gravity_effort", [a]) => m * m + m + index(a)?,
            _ => return Err(not_actuated),
        };
        Ok(self.symbol(Source::Model(slot)))
    }
}

/// A component of the state of the frame at `offset` on earth.
fn earth_frame(offset: &Pose, quantity: FrameQuantity) -> f64 {
    match quantity {
        FrameQuantity::Position(i) => offset.translation.vector[i as usize],
        FrameQuantity::Velocity(_) | FrameQuantity::AngularVelocity(_) => 0.0,
        FrameQuantity::Orientation(i, j) => {
            offset.rotation.to_rotation_matrix().matrix()[(i as usize, j as usize)]
        }
    }
}

/// A frame's state at one instant, in the fixed axes.
#[derive(Clone, Debug)]
struct FrameValues {
    position: Vector3<f64>,
    velocity: Vector3<f64>,
    angular_velocity: Vector3<f64>,
    orientation: Matrix3<f64>,
}

impl FrameValues {
    /// The frame at `offset` on `body`: its position, and what `needs` asks for of the rest
    /// (zeros otherwise).
    fn new(state: &EffortState<'_>, body: usize, offset: &Pose, needs: Needs) -> FrameValues {
        let world = &state.world[body];
        let velocity = &state.velocity[body];
        let spin = Vector3::new(velocity[0], velocity[1], velocity[2]);
        // Most elements act between bodies' own frames: no offset to turn.
        let at_origin = offset.translation.vector == Vector3::zeros();
        let mut values = FrameValues {
            position: match at_origin {
                true => world.translation.vector,
                false => world.translation.vector + world.rotation * offset.translation.vector,
            },
            velocity: Vector3::zeros(),
            angular_velocity: Vector3::zeros(),
            orientation: Matrix3::zeros(),
        };
        if needs.velocity {
            let linear = Vector3::new(velocity[3], velocity[4], velocity[5]);
            values.velocity = match at_origin {
                true => world.rotation * linear,
                false => world.rotation * (linear + spin.cross(&offset.translation.vector)),
            };
        }
        if needs.angular_velocity {
            values.angular_velocity = world.rotation * spin;
        }
        if needs.orientation {
            values.orientation = *(world.rotation * offset.rotation)
                .to_rotation_matrix()
                .matrix();
        }
        values
    }

    fn component(&self, quantity: FrameQuantity) -> f64 {
        match quantity {
            FrameQuantity::Position(i) => self.position[i as usize],
            FrameQuantity::Velocity(i) => self.velocity[i as usize],
            FrameQuantity::AngularVelocity(i) => self.angular_velocity[i as usize],
            FrameQuantity::Orientation(i, j) => self.orientation[(i as usize, j as usize)],
        }
    }
}
