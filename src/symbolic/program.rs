//! Program scalars lowered into the expression pool, the one expression system of lsdc: the
//! structure (numbers, arithmetic, calls) is lowered alike everywhere, the leaves as each use
//! needs (the geometry's constants and dof chains in `kinematics::eval`, the efforts in
//! `dynamics::compiled`, the equations in `symbolic::lower`).

use std::collections::HashMap;

use super::expr::{ExponentialProfile, ExprId, Function, Pool};
use crate::elab::value::SExpr;

/// A call the pool cannot express: another number of arguments than the function takes, or a
/// function no one knows (the checker rejects both; lowering does not trust it blindly).
#[derive(Clone, Debug, PartialEq)]
pub struct MalformedCall(pub &'static str);

/// Lowering a program scalar into the pool: numbers, arithmetic and calls lower alike
/// everywhere; what the leaves (unknowns, coordinates, rates, the time, frames) become depends
/// on the use (constants and symbols of a dof chain, slots of the effort tape).
pub trait Lower {
    /// What a leaf can fail with; the structure's own failures come as a `MalformedCall`.
    type Error: From<MalformedCall>;

    fn pool(&mut self) -> &mut Pool;

    /// A scalar that is neither a number, arithmetic nor a call.
    fn leaf(&mut self, s: &SExpr) -> Result<ExprId, Self::Error>;

    /// A call that reads the model at the state (`mass_matrix(a.q, b.q)`, `bias(a.q)`,
    /// `gravity_effort(a.q)`): only the laws of actuators and outputs may.
    fn model_quantity(
        &mut self,
        _name: &str,
        _args: &[crate::elab::value::Scalar],
    ) -> Result<ExprId, Self::Error> {
        Err(MalformedCall("the model, which only actuators' laws and outputs read").into())
    }

    /// Lowers `s` (override to remember subexpressions already lowered).
    fn lower(&mut self, s: &SExpr) -> Result<ExprId, Self::Error> {
        lower_structure(self, s)
    }
}

/// The node of `s`, its operands lowered through `lowering`.
pub fn lower_structure<L: Lower + ?Sized>(lowering: &mut L, s: &SExpr) -> Result<ExprId, L::Error> {
    let binary = |lowering: &mut L, a: &SExpr, b: &SExpr| -> Result<_, L::Error> {
        Ok((lowering.lower(a)?, lowering.lower(b)?))
    };
    Ok(match s {
        SExpr::Num(v) => lowering.pool().constant(*v),
        SExpr::Neg(a) => {
            let a = lowering.lower(a)?;
            lowering.pool().neg(a)
        }
        SExpr::Add(a, b) => {
            let (a, b) = binary(lowering, a, b)?;
            lowering.pool().add(a, b)
        }
        SExpr::Sub(a, b) => {
            let (a, b) = binary(lowering, a, b)?;
            lowering.pool().sub(a, b)
        }
        SExpr::Mul(a, b) => {
            let (a, b) = binary(lowering, a, b)?;
            lowering.pool().mul(a, b)
        }
        SExpr::Div(a, b) => {
            let (a, b) = binary(lowering, a, b)?;
            lowering.pool().div(a, b)
        }
        SExpr::Pow(a, b) => {
            let (a, b) = binary(lowering, a, b)?;
            // A square is a product: cheaper than `powf`, and as exact.
            match lowering.pool().as_constant(b) {
                Some(2.0) => lowering.pool().mul(a, a),
                _ => lowering.pool().pow(a, b),
            }
        }
        SExpr::Call(call) if crate::elab::model_laws::is_model_function(call.function) => {
            lowering.model_quantity(call.function, &call.args)?
        }
        SExpr::Call(call) => lower_call(lowering, call.function, &call.args)?,
        leaf => lowering.leaf(leaf)?,
    })
}

/// A call of a built-in function: `atan2(y, x)`, a function of one argument, the piecewise
/// `select(test, a, b)` (a where test ≥ 0, else b) that saturations and the reference laws are
/// written with, and `derivative(e)`, the time derivative of a law of time, taken on the pool
/// (`Pool::derivative` with respect to the time's symbol, exact).
fn lower_call<L: Lower + ?Sized>(
    lowering: &mut L,
    name: &str,
    args: &[crate::elab::value::Scalar],
) -> Result<ExprId, L::Error> {
    let arity = match name {
        "atan2" => 2,
        "select" | "exponential_profile" => 3,
        _ => 1,
    };
    if args.len() != arity {
        return Err(MalformedCall("a call with another number of arguments").into());
    }
    let x = lowering.lower(&args[0])?;
    Ok(match name {
        "atan2" => {
            let second = lowering.lower(&args[1])?;
            lowering.pool().atan2(x, second)
        }
        "select" => {
            let (high, low) = (lowering.lower(&args[1])?, lowering.lower(&args[2])?);
            lowering.pool().select(x, high, low)
        }
        // The exponential law's profile of τ, its σ and λ numbers (checked where it is written).
        "exponential_profile" => {
            let (sigma, lambda) = (lowering.lower(&args[1])?, lowering.lower(&args[2])?);
            let pool = lowering.pool();
            let (Some(sigma), Some(lambda)) = (pool.as_constant(sigma), pool.as_constant(lambda))
            else {
                return Err(
                    MalformedCall("an exponential law whose σ or λ is not a number").into(),
                );
            };
            pool.apply(
                Function::ExponentialProfile(ExponentialProfile::new(sigma, lambda)),
                x,
            )
        }
        "derivative" => {
            let time = lowering.leaf(&SExpr::Time)?;
            lowering.pool().derivative(x, time, &mut HashMap::new())
        }
        _ => {
            let function = Function::from_name(name).ok_or(MalformedCall("an unknown function"))?;
            lowering.pool().apply(function, x)
        }
    })
}
