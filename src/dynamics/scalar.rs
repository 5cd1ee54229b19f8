//! The scalars the recursive algorithms (RNEA, ABA and the joints' states they start from)
//! compute in: `f64`, and the dual numbers of forward-mode automatic differentiation
//! (`num_dual`), whose derivative parts carry ∂/∂x of every quantity through the same code, an
//! oracle for the analytical derivatives that shares none of their algebra (Pinocchio templates
//! its algorithms on the scalar the same way, for CppAD and CasADi).
//!
//! One thing sets the scalars apart: a dof chain evaluated in general (`Kernel::General`) has
//! its pose, subspace and bias from the expressions of the program, which are evaluated in
//! `f64` only. A dual number refuses it rather than drop its derivatives; the joints the
//! analytical derivatives cover (welds, one rotation or one translation linear in the
//! coordinate, spherical and free joints) need no expression.

use num_dual::{Dual64, DualSVec64};

use super::joint::{Joint, JointState};
use crate::kinematics::eval::EvalError;
use crate::spatial::Real;

/// A scalar of the recursive algorithms.
pub trait DynamicsScalar: Real {
    /// The state of a joint whose dof chain is evaluated in general, at (q, v).
    fn general_chain_state(
        joint: &Joint,
        q: &[Self],
        v: &[Self],
        state: &mut JointState<Self>,
    ) -> Result<(), EvalError>;
}

impl DynamicsScalar for f64 {
    fn general_chain_state(
        joint: &Joint,
        q: &[f64],
        v: &[f64],
        state: &mut JointState,
    ) -> Result<(), EvalError> {
        joint.chain_state(q, v, state)
    }
}

/// What a dual number says of a general dof chain.
const NOT_DIFFERENTIABLE: EvalError = EvalError::NotGeometric(
    "dual numbers, in which the expressions of a general dof chain are not evaluated",
);

impl DynamicsScalar for Dual64 {
    fn general_chain_state(
        _: &Joint,
        _: &[Self],
        _: &[Self],
        _: &mut JointState<Self>,
    ) -> Result<(), EvalError> {
        Err(NOT_DIFFERENTIABLE)
    }
}

impl<const N: usize> DynamicsScalar for DualSVec64<N> {
    fn general_chain_state(
        _: &Joint,
        _: &[Self],
        _: &[Self],
        _: &mut JointState<Self>,
    ) -> Result<(), EvalError> {
        Err(NOT_DIFFERENTIABLE)
    }
}
