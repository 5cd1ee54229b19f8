//! Program scalars lowered into the expression pool of the symbolic back end, the one expression
//! system of lsdc: the structure (numbers, arithmetic, calls) is lowered alike everywhere, the
//! leaves as each use needs (the geometry's constants and dof chains here, the efforts in
//! `dynamics::compiled`, the equations in `symbolic::lower`). Values are computed by folding
//! constants or by a tape; derivatives are taken in the pool.

use std::collections::HashMap;

use crate::elab::value::{SExpr, UnknownId};
use crate::symbolic::expr::{ExprId, Pool, Tape};
use crate::symbolic::program::{Lower, MalformedCall};

/// Values of the program's unknowns (written `?s` and generic quantities).
pub type UnknownValues = HashMap<UnknownId, f64>;

#[derive(Clone, Debug, PartialEq)]
pub enum EvalError {
    /// An unknown without a value.
    Missing(UnknownId),
    /// Something that is not a function of the link's coordinates alone (a derivative `x'`,
    /// another join's coordinate, the time): not allowed in geometry.
    NotGeometric(&'static str),
    /// The geometry at a configuration is not a finite number (a coordinate so large that the
    /// poses overflow, a degenerate joint).
    NotFinite,
}

impl From<MalformedCall> for EvalError {
    fn from(error: MalformedCall) -> EvalError {
        EvalError::NotGeometric(error.0)
    }
}

/// How messages name an unknown: `` `L` `` (its `let` name), `` `mass(arm)` `` (a generic
/// quantity) or "an unknown `?s`".
pub fn unknown_label(mechanism: &crate::elab::mechanism::Mechanism, id: UnknownId) -> String {
    let unknown = &mechanism.unknowns[id.0 as usize];
    match (&unknown.name, unknown.origin) {
        (Some(name), _) => format!("`{name}`"),
        (None, crate::elab::mechanism::Origin::Written) => "an unknown `?s`".to_string(),
        (None, origin) => format!("`{}`", mechanism.generic_name(origin)),
    }
}

/// What [`EvalError::NotFinite`] says.
pub const NOT_FINITE: &str =
    "its value is not a finite number there (a coordinate too large, or a degenerate joint)";

/// A sentence for people about an evaluation error.
pub fn describe(error: &EvalError, mechanism: &crate::elab::mechanism::Mechanism) -> String {
    match error {
        EvalError::Missing(id) => format!("no value for {}", unknown_label(mechanism, *id)),
        EvalError::NotGeometric(what) => format!("it depends on {what}"),
        EvalError::NotFinite => NOT_FINITE.to_string(),
    }
}

/// The leaves of geometry: unknowns are constants (their values are known), the enclosing
/// link's coordinates are `coordinates` (symbols of a dof chain, or none for constants);
/// nothing else may appear.
pub struct Geometric<'a> {
    pub pool: Pool,
    pub unknowns: &'a UnknownValues,
    pub coordinates: Vec<ExprId>,
}

impl Lower for Geometric<'_> {
    type Error = EvalError;

    fn pool(&mut self) -> &mut Pool {
        &mut self.pool
    }

    fn leaf(&mut self, s: &SExpr) -> Result<ExprId, EvalError> {
        match s {
            SExpr::Unknown(id) => {
                let value = *self.unknowns.get(id).ok_or(EvalError::Missing(*id))?;
                Ok(self.pool.constant(value))
            }
            SExpr::UnknownFunction(call) => Err(EvalError::Missing(call.function)),
            SExpr::Coordinate { index, order: 0 } => self
                .coordinates
                .get(*index as usize)
                .copied()
                .ok_or(EvalError::NotGeometric("a coordinate of another link")),
            SExpr::Coordinate { order: 1, .. } => Err(EvalError::NotGeometric("a time derivative")),
            SExpr::Coordinate { .. } => Err(EvalError::NotGeometric("a second time derivative")),
            SExpr::JoinCoordinate { .. } => Err(EvalError::NotGeometric("a coordinate of a join")),
            SExpr::Time => Err(EvalError::NotGeometric("the time")),
            SExpr::State(_) => Err(EvalError::NotGeometric(
                "a state or an input (`state(...)`, `input`), whose value changes during a run",
            )),
            _ => Err(EvalError::NotGeometric(
                "the state of a frame (position, velocity, …)",
            )),
        }
    }
}

/// The value of a constant scalar: lowered into a pool, where constants fold (a tape evaluates
/// what does not fold to a finite number, such as `log(0)`).
pub fn eval(s: &SExpr, unknowns: &UnknownValues) -> Result<f64, EvalError> {
    let mut lowering = Geometric {
        pool: Pool::new(),
        unknowns,
        coordinates: Vec::new(),
    };
    let root = lowering.lower(s)?;
    Ok(match lowering.pool.as_constant(root) {
        Some(value) => value,
        None => Tape::new(&lowering.pool, &[root]).eval(&[])[0],
    })
}
