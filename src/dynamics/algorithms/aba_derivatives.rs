//! Analytical derivatives of forward dynamics, q̈ = ABA(q, v, τ): since RNEA(q, v, ABA(q, v, τ))
//! = τ, differentiating gives ∂q̈/∂q = −M⁻¹ ∂τ/∂q and ∂q̈/∂v = −M⁻¹ ∂τ/∂v, the derivatives of
//! inverse dynamics taken at the accelerations q̈, and ∂q̈/∂τ = M⁻¹ (Carpentier & Mansard,
//! "Analytical Derivatives of Rigid Body Dynamics Algorithms", RSS 2018, §IV). M⁻¹ comes from the
//! mass matrix (CRBA, geared rotors included) and its Cholesky factor.

use nalgebra::{DMatrix, DVector};

use super::rnea_derivatives::{check_supported, DerivativeError, RneaDerivatives};
use super::{aba_into, base_acceleration, crba_after_kinematics, Data, DynamicsError};
use crate::dynamics::model::Model;
use crate::spatial::Force;

/// Why forward dynamics or its derivatives cannot be computed.
#[derive(Clone, Debug, PartialEq)]
pub enum ForwardDerivativeError {
    Derivatives(DerivativeError),
    Dynamics(DynamicsError),
    /// The mass matrix is not positive definite (a body without inertia along some motion).
    SingularMass,
}

impl From<DerivativeError> for ForwardDerivativeError {
    fn from(e: DerivativeError) -> Self {
        ForwardDerivativeError::Derivatives(e)
    }
}

impl std::fmt::Display for ForwardDerivativeError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ForwardDerivativeError::Derivatives(e) => write!(f, "{e}"),
            ForwardDerivativeError::Dynamics(e) => write!(f, "{e:?}"),
            ForwardDerivativeError::SingularMass => {
                write!(f, "the mass matrix is not positive definite")
            }
        }
    }
}

/// q̈ and its derivatives, with the scratch they are computed in; `new(&model)` once.
pub struct AbaDerivatives {
    pub acceleration: DVector<f64>,
    /// ∂q̈/∂q (in the joints' tangent spaces), ∂q̈/∂v and ∂q̈/∂τ = M⁻¹, nv × nv each.
    pub dacceleration_dq: DMatrix<f64>,
    pub dacceleration_dv: DMatrix<f64>,
    pub mass_inverse: DMatrix<f64>,
    pub inverse: RneaDerivatives,
    /// The mass matrix at q (zero where CRBA writes nothing, as it needs).
    mass: DMatrix<f64>,
}

impl AbaDerivatives {
    pub fn new(model: &Model) -> AbaDerivatives {
        let nv = model.nv;
        AbaDerivatives {
            acceleration: DVector::zeros(nv),
            dacceleration_dq: DMatrix::zeros(nv, nv),
            dacceleration_dv: DMatrix::zeros(nv, nv),
            mass_inverse: DMatrix::zeros(nv, nv),
            inverse: RneaDerivatives::new(model),
            mass: DMatrix::zeros(nv, nv),
        }
    }

    /// q̈ = ABA(q, v, τ) under the external forces `external` (per body, in its frame) and its
    /// derivatives with respect to q, v and τ.
    pub fn compute(
        &mut self,
        model: &Model,
        data: &mut Data,
        q: &[f64],
        v: &[f64],
        tau: &[f64],
        external: &[Force],
    ) -> Result<(), ForwardDerivativeError> {
        check_supported(model)?;
        // One evaluation of the joints' motions serves ABA, CRBA and the derivatives.
        aba_into(model, data, q, v, tau, external, &mut self.acceleration)
            .map_err(ForwardDerivativeError::Dynamics)?;
        crba_after_kinematics(model, data, &mut self.mass);
        let cholesky =
            (self.mass.clone().cholesky()).ok_or(ForwardDerivativeError::SingularMass)?;
        self.mass_inverse = cholesky.inverse();
        let inverse = &mut self.inverse;
        let state = (v, self.acceleration.as_slice());
        inverse.after_kinematics(model, data, state, external, base_acceleration(model));
        self.mass_inverse
            .mul_to(&inverse.dtau_dq, &mut self.dacceleration_dq);
        self.mass_inverse
            .mul_to(&inverse.dtau_dv, &mut self.dacceleration_dv);
        self.dacceleration_dq.neg_mut();
        self.dacceleration_dv.neg_mut();
        Ok(())
    }
}
