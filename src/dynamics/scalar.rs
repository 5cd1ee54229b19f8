//! The scalars the recursive algorithms (RNEA, ABA and the joints' states they start from)
//! compute in: `f64`, and the dual numbers of forward-mode automatic differentiation
//! (`num_dual::Dual64`), whose derivative parts carry ∂/∂x of every quantity through the same
//! code, an oracle for the analytical derivatives that shares none of their algebra (Pinocchio
//! templates its algorithms on the scalar the same way, for CppAD and CasADi).
//!
//! One thing sets the scalars apart: a dof chain evaluated in general (`Kernel::General`, or a
//! loop's complementary link that is not one rotation or translation) has its pose, subspace
//! and bias from the expressions of the program, which are evaluated in `f64` only. A dual number refuses it rather than drop its derivatives; the joints the
//! analytical derivatives cover (welds, one rotation or one translation linear in the
//! coordinate, spherical and free joints) need no expression.

use num_dual::Dual64;

use crate::kinematics::eval::EvalError;
use crate::kinematics::model::ChainMotion;
use crate::spatial::Real;

/// A scalar of the recursive algorithms.
pub trait DynamicsScalar: Real {
    /// The values as `f64`, in which the program's expressions are evaluated: themselves for
    /// `f64`, `None` for a scalar that carries derivatives.
    fn plain(values: &[Self]) -> Option<&[f64]>;

    /// A dof chain's motion as the `f64` one its expressions are evaluated into: itself for
    /// `f64`, `None` for a scalar that carries derivatives.
    fn plain_motion(motion: &mut ChainMotion<Self>) -> Option<&mut ChainMotion<f64>>;
}

impl DynamicsScalar for f64 {
    fn plain(values: &[f64]) -> Option<&[f64]> {
        Some(values)
    }

    fn plain_motion(motion: &mut ChainMotion) -> Option<&mut ChainMotion> {
        Some(motion)
    }
}

impl DynamicsScalar for Dual64 {
    fn plain(_: &[Self]) -> Option<&[f64]> {
        None
    }

    fn plain_motion(_: &mut ChainMotion<Self>) -> Option<&mut ChainMotion> {
        None
    }
}

/// What the evaluation of a general dof chain says of coordinates that carry derivatives.
pub const NOT_DIFFERENTIABLE: EvalError = EvalError::NotGeometric(
    "dual numbers, in which the expressions of a general dof chain are not evaluated",
);
