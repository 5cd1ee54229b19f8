//! From the elaborated program's scalars (`SExpr`) to pool expressions: coordinates, rates,
//! time, unknowns and unknown functions become named symbols, the variables of the equations.

use std::collections::HashMap;
use std::sync::Arc;

use super::expr::{ExprId, Pool};
use super::program::{Lower, MalformedCall};
use super::quaternion_joints::{BallKind, QuaternionJoins};
use crate::elab::mechanism::{Mechanism, Origin, UnknownKind};

use crate::elab::value::{Frame, FrameQuantity, JoinId, SExpr, UnknownId};
use crate::topology::Topology;

/// A symbol of the equations and what it stands for.
#[derive(Clone, Debug)]
pub struct Variable {
    /// A name for people and for SymPy: `hinge.x`, `hinge.x'`, `mu_1`, `z34`.
    pub name: String,
    pub symbol: ExprId,
    /// What the program says it is: `coordinate x of join hinge`, `mass(satellite)`, …
    pub meaning: String,
    /// Its `given` value, if the program gives one (parameters only).
    pub given: Option<f64>,
    /// The unknown of the program it stands for (parameters only).
    pub unknown: Option<UnknownId>,
}

/// An unknown function applied to arguments (`?fs(x, x')`): its value is an input of the
/// equations, standing for the law the program left open.
#[derive(Clone, Debug)]
pub struct FunctionUse {
    /// The function's name (`cL2_x`).
    pub name: String,
    pub symbol: ExprId,
    pub arguments: Vec<ExprId>,
}

/// The variables of a mechanism's equations.
#[derive(Clone, Debug)]
pub struct Variables {
    /// Declared coordinates: the principal links' by number, then the complementary links'
    /// (a join written in the simulator's state, `quaternion_joints`, has its quaternion and
    /// translation there instead).
    pub positions: Vec<Variable>,
    /// Their first derivatives, in the same order (a join in the simulator's state: its body
    /// twist, fewer rates than positions).
    pub rates: Vec<Variable>,
    /// Unknown scalars of the program, in order of first use.
    pub parameters: Vec<Variable>,
    pub functions: Vec<FunctionUse>,
    pub time: ExprId,
}

/// Where one join's variables are: its first position and first rate, and how many of each.
#[derive(Clone, Copy, Debug)]
pub struct JoinVariables {
    pub position: usize,
    pub rate: usize,
    pub positions: usize,
    pub rates: usize,
}

/// Lowers scalars of one mechanism, creating the variables as they are met.
pub struct Lowering<'a> {
    mechanism: &'a Mechanism,
    generated: HashMap<UnknownId, String>,
    /// Body numbers, for the generic names (`mu_1`).
    body_numbers: HashMap<crate::elab::value::BodyId, usize>,
    /// Index of each join's first position among `positions` and of its first rate among
    /// `rates`, and how many of each it has.
    join_offsets: HashMap<JoinId, JoinVariables>,
    /// The joins written in the simulator's state.
    quaternion_joins: QuaternionJoins,
    parameters: HashMap<UnknownId, usize>,
    functions: HashMap<(UnknownId, Vec<ExprId>), usize>,
    pub variables: Variables,
    /// The frames whose state efforts use, with that state as expressions (set by the
    /// generator before it lowers the efforts).
    pub frames: Vec<(Arc<Frame>, FrameState)>,
}

/// A frame's state in the fixed axes, as expressions.
#[derive(Clone, Copy, Debug)]
pub struct FrameState {
    pub position: [ExprId; 3],
    pub velocity: [ExprId; 3],
    pub angular_velocity: [ExprId; 3],
    pub orientation: [[ExprId; 3]; 3],
}

#[derive(Debug)]
pub struct LowerError(pub String);

impl<'a> Lowering<'a> {
    /// The lowering of `mechanism`'s scalars: its joins in their declared coordinates, but
    /// those of `quaternion_joins`, in the simulator's state.
    pub fn in_state(
        pool: &mut Pool,
        mechanism: &'a Mechanism,
        topology: &Topology,
        quaternion_joins: QuaternionJoins,
    ) -> Lowering<'a> {
        let generated = crate::topology::notation::unknown_names(mechanism, topology);
        let mut positions = Vec::new();
        let mut rates = Vec::new();
        let mut join_offsets = HashMap::new();
        let joins = topology
            .principal
            .iter()
            .map(|l| l.join)
            .chain(topology.complementary.iter().map(|l| l.join));
        for join in joins {
            let name = mechanism.join_name(join);
            let (position, rate) = (positions.len(), rates.len());
            let mut variable = |list: &mut Vec<Variable>, name: String, meaning: String| {
                list.push(Variable {
                    symbol: pool.symbol(&name),
                    name,
                    meaning,
                    given: None,
                    unknown: None,
                });
            };
            if let Some(&kind) = quaternion_joins.get(&join) {
                for part in kind.position_names() {
                    let meaning = format!("position `{part}` of the ball of join `{name}`");
                    variable(&mut positions, format!("{name}.{part}"), meaning);
                }
                for part in kind.rate_names() {
                    let meaning = format!("body rate `{part}` of join `{name}`");
                    variable(&mut rates, format!("{name}.{part}"), meaning);
                }
            } else {
                for coordinate in &mechanism.link(mechanism.join(join).link).coordinates {
                    let position = format!("{name}.{coordinate}");
                    let rate = format!("{position}'");
                    let meaning = format!("coordinate `{coordinate}` of join `{name}`");
                    variable(&mut positions, position, meaning.clone());
                    variable(&mut rates, rate, format!("rate of the {meaning}"));
                }
            }
            let counts = (positions.len() - position, rates.len() - rate);
            join_offsets.insert(
                join,
                JoinVariables {
                    position,
                    rate,
                    positions: counts.0,
                    rates: counts.1,
                },
            );
        }
        let time = pool.symbol("t");
        let body_numbers = topology.number_of.clone();
        Lowering {
            mechanism,
            generated,
            body_numbers,
            join_offsets,
            quaternion_joins,
            parameters: HashMap::new(),
            functions: HashMap::new(),
            frames: Vec::new(),
            variables: Variables {
                positions,
                rates,
                parameters: Vec::new(),
                functions: Vec::new(),
                time,
            },
        }
    }

    /// Where a join's variables are among `positions` and `rates`, and how many it has.
    pub fn join_variables(&self, join: JoinId) -> JoinVariables {
        self.join_offsets[&join]
    }

    /// How the simulator integrates a join written in its state; `None` for a join in its
    /// declared coordinates.
    pub fn ball(&self, join: JoinId) -> Option<BallKind> {
        self.quaternion_joins.get(&join).copied()
    }

    /// The expression of `s`; `link` is the join whose link encloses it (for `x`, `x'`).
    pub fn scalar(
        &mut self,
        pool: &mut Pool,
        s: &SExpr,
        link: Option<JoinId>,
    ) -> Result<ExprId, LowerError> {
        Symbolic {
            lowering: self,
            pool,
            link,
        }
        .lower(s)
    }

    pub fn vector(
        &mut self,
        pool: &mut Pool,
        v: &crate::elab::value::Vector,
        link: Option<JoinId>,
    ) -> Result<[ExprId; 3], LowerError> {
        Ok([
            self.scalar(pool, &v[0], link)?,
            self.scalar(pool, &v[1], link)?,
            self.scalar(pool, &v[2], link)?,
        ])
    }

    fn frame_state(&self, frame: &Frame, quantity: FrameQuantity) -> Result<ExprId, LowerError> {
        let (_, state) = self
            .frames
            .iter()
            .find(|(f, _)| **f == *frame)
            .ok_or_else(|| LowerError("the state of a frame outside an effort".to_string()))?;
        Ok(match quantity {
            FrameQuantity::Position(i) => state.position[i as usize],
            FrameQuantity::Velocity(i) => state.velocity[i as usize],
            FrameQuantity::AngularVelocity(i) => state.angular_velocity[i as usize],
            FrameQuantity::Orientation(i, j) => state.orientation[i as usize][j as usize],
        })
    }

    fn coordinate(&self, join: JoinId, index: u32, order: u32) -> Result<ExprId, LowerError> {
        if self.quaternion_joins.contains_key(&join) {
            return Err(LowerError(format!(
                "it reads the declared angles of `{}`, which the simulator's state holds as a quaternion",
                self.mechanism.join_name(join)
            )));
        }
        let k = self
            .join_offsets
            .get(&join)
            .ok_or_else(|| LowerError("a coordinate of a join outside the mechanism".to_string()))?
            .position
            + index as usize;
        match order {
            0 => Ok(self.variables.positions[k].symbol),
            1 => Ok(self.variables.rates[k].symbol),
            _ => Err(LowerError(format!(
                "it uses the second derivative of `{}`; efforts may use coordinates, their first derivatives and time",
                self.variables.positions[k].name
            ))),
        }
    }

    fn parameter(&mut self, pool: &mut Pool, id: UnknownId) -> ExprId {
        if let Some(&k) = self.parameters.get(&id) {
            return self.variables.parameters[k].symbol;
        }
        let unknown = &self.mechanism.unknowns[id.0 as usize];
        let meaning = match unknown.origin {
            Origin::Written => "an unknown of the program".to_string(),
            origin => self.mechanism.generic_name(origin),
        };
        let mut name = self.parameter_name(id);
        while name == "t"
            || self.variables.parameters.iter().any(|p| p.name == name)
            || self.variables.positions.iter().any(|p| p.name == name)
        {
            name.push('_');
        }
        let given = self
            .mechanism
            .given
            .iter()
            .find(|(g, _, _)| *g == id)
            .and_then(|(_, v, _)| crate::elab::value::constant(v));
        let variable = Variable {
            symbol: pool.symbol(&name),
            name,
            meaning,
            given,
            unknown: Some(id),
        };
        self.parameters.insert(id, self.variables.parameters.len());
        self.variables.parameters.push(variable);
        self.variables
            .parameters
            .last()
            .map(|v| v.symbol)
            .unwrap_or(self.variables.time)
    }

    /// The `let` name, else the notation table's, else a thesis-style name built from the body
    /// number (`mu_1`, `mIg_1_x`).
    fn parameter_name(&self, id: UnknownId) -> String {
        let unknown = &self.mechanism.unknowns[id.0 as usize];
        if let Some(name) = &unknown.name {
            // The components of a `?v` share its name.
            return match unknown.kind {
                UnknownKind::Vector => {
                    format!("{name}_{}", ["x", "y", "z"][unknown.component as usize % 3])
                }
                _ => name.to_string(),
            };
        }
        if let Some(name) = self.generated.get(&id) {
            return name.clone();
        }
        const AXES: [&str; 6] = ["x", "y", "z", "rx", "ry", "rz"];
        let number = |body| self.body_numbers.get(&body).copied().unwrap_or(0);
        match unknown.origin {
            Origin::Mass(body) => format!("mu_{}", number(body)),
            Origin::Inertia(body, axis) => {
                format!("mIg_{}_{}", number(body), AXES[axis as usize % 3])
            }
            Origin::InertiaFrame(body, k) => {
                format!("vGT_{}_{}", number(body), AXES[k as usize % 6])
            }
            Origin::EffortValue(effort, axis) => {
                format!("effort{}_{}", effort.0 + 1, AXES[axis as usize % 3])
            }
            Origin::Written if unknown.kind == UnknownKind::Function => format!("f{}", id.0 + 1),
            Origin::Written => format!("unknown{}", id.0 + 1),
        }
    }

    fn function(&mut self, pool: &mut Pool, id: UnknownId, arguments: Vec<ExprId>) -> ExprId {
        let key = (id, arguments);
        if let Some(&k) = self.functions.get(&key) {
            return self.variables.functions[k].symbol;
        }
        let name = self.parameter_name(id);
        // The symbol stands for the value of the application; its name shows the arguments.
        let shown: Vec<String> = key.1.iter().map(|&a| self.argument_name(pool, a)).collect();
        let symbol = pool.symbol(&format!("{name}({})", shown.join(", ")));
        self.functions
            .insert(key.clone(), self.variables.functions.len());
        self.variables.functions.push(FunctionUse {
            name,
            symbol,
            arguments: key.1,
        });
        symbol
    }

    fn argument_name(&self, pool: &Pool, a: ExprId) -> String {
        match pool.node(a) {
            super::expr::Node::Symbol(i) => pool.symbol_name(i).to_string(),
            _ => format!("e{}", a.index()),
        }
    }
}

/// The program's scalars within one link (`link`: the join whose coordinates `x`, `x'` stand
/// in it) as expressions of the equations' variables: numbers, arithmetic and calls lower as
/// everywhere (`symbolic::program::Lower`); the leaves become the variables.
struct Symbolic<'l, 'a, 'p> {
    lowering: &'l mut Lowering<'a>,
    pool: &'p mut Pool,
    link: Option<JoinId>,
}

impl Lower for Symbolic<'_, '_, '_> {
    type Error = LowerError;

    fn pool(&mut self) -> &mut Pool {
        self.pool
    }

    fn leaf(&mut self, s: &SExpr) -> Result<ExprId, LowerError> {
        let lowering = &mut *self.lowering;
        Ok(match s {
            SExpr::Time => lowering.variables.time,
            SExpr::Unknown(id) => lowering.parameter(self.pool, *id),
            SExpr::UnknownFunction(call) => {
                let arguments = call
                    .args
                    .iter()
                    .map(|a| self.lower(a))
                    .collect::<Result<Vec<_>, _>>()?;
                self.lowering.function(self.pool, call.function, arguments)
            }
            SExpr::Coordinate { index, order } => {
                let join = self
                    .link
                    .ok_or_else(|| LowerError("a link coordinate outside its link".to_string()))?;
                lowering.coordinate(join, *index, *order)?
            }
            SExpr::JoinCoordinate { join, index, order } => {
                lowering.coordinate(*join, *index, *order)?
            }
            SExpr::FrameState(frame, quantity) => lowering.frame_state(frame, *quantity)?,
            SExpr::State(_) => {
                return Err(LowerError(
                    "it reads a state (`state(...)`), whose own equation is not among them"
                        .to_string(),
                ))
            }
            other => return Err(LowerError(format!("{other:?} is not a leaf"))),
        })
    }
}

impl From<MalformedCall> for LowerError {
    fn from(error: MalformedCall) -> LowerError {
        LowerError(format!("it has {}", error.0))
    }
}
