//! Analytical derivatives of forward dynamics, q̈ = ABA(q, v, τ): since RNEA(q, v, ABA(q, v, τ))
//! = τ, differentiating gives ∂q̈/∂q = −M⁻¹ ∂τ/∂q and ∂q̈/∂v = −M⁻¹ ∂τ/∂v, the derivatives of
//! inverse dynamics taken at the accelerations q̈, and ∂q̈/∂τ = M⁻¹ (Carpentier & Mansard,
//! "Analytical Derivatives of Rigid Body Dynamics Algorithms", RSS 2018, §IV).
//!
//! q̈ and the mass matrix come from the passes of those derivatives themselves
//! (`RneaDerivatives::forward_dynamics`: the bias efforts and the composite inertias at q̈ = 0,
//! then q̈ by the mass matrix's factor, ABA's values to round-off); with geared rotors, from
//! ABA and CRBA. q̈, M⁻¹ and the products −M⁻¹ ∂τ are solves with M's factor along the tree,
//! M = Lᵀ D L (`mass_factor`), by rows over the columns of each row's tree: 2 Σ dᵢ + n
//! products a column (dᵢ the depth of velocity i) where a dense product by M⁻¹ costs n²,
//! nothing crossing between the tree's separate branches.

use nalgebra::{DMatrix, DVector};

use super::mass_factor::MassFactor;
use super::rnea_derivatives::{check_supported, joint_frames, DerivativeError, RneaDerivatives};
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
    /// The inverse dynamics' derivatives at q̈, scratch: without geared rotors they are left
    /// by rows and solved in place (`RneaDerivatives::forward_dynamics`).
    inverse: RneaDerivatives,
    /// The mass matrix at q (zero where CRBA writes nothing, as it needs with geared rotors;
    /// without, the scratch M⁻¹ is solved in once it is factored) and its factor.
    mass: DMatrix<f64>,
    factor: MassFactor,
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
            factor: MassFactor::new(model),
        }
    }

    /// q̈, forward dynamics at (q, v, τ) under the external forces `external` (per body, in its
    /// frame), and its derivatives with respect to q, v and τ.
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
        let inverse = &mut self.inverse;
        if model.rotors.is_empty() {
            joint_frames(model, data, q, v)
                .map_err(|e| ForwardDerivativeError::Dynamics(DynamicsError::Evaluation(e)))?;
            let (factor, mass) = (&mut self.factor, &mut self.mass);
            let accelerations = &mut self.acceleration;
            let state = (v, tau);
            let mass_inverse = &mut self.mass_inverse;
            if !inverse.forward_dynamics(
                model,
                data,
                state,
                external,
                factor,
                mass,
                mass_inverse,
                accelerations,
            ) {
                return Err(ForwardDerivativeError::SingularMass);
            }
            // ∂τ/∂q and ∂τ/∂v by rows, solved side by side where they are.
            (self.factor).solve_rows_negated_into(
                [
                    inverse.dtau_dq.as_mut_slice(),
                    inverse.dtau_dv.as_mut_slice(),
                ],
                [&mut self.dacceleration_dq, &mut self.dacceleration_dv],
            );
        } else {
            // One evaluation of the joints' motions serves ABA, CRBA and the derivatives.
            aba_into(model, data, q, v, tau, external, &mut self.acceleration)
                .map_err(ForwardDerivativeError::Dynamics)?;
            crba_after_kinematics(model, data, &mut self.mass);
            if !self.factor.factor(&self.mass) {
                return Err(ForwardDerivativeError::SingularMass);
            }
            let state = (v, self.acceleration.as_slice());
            inverse.after_kinematics(model, data, state, external, base_acceleration(model));
            self.factor.inverse_into(&mut self.mass_inverse);
            (self.factor).solve_negated(&inverse.dtau_dq, &mut self.dacceleration_dq);
            (self.factor).solve_negated(&inverse.dtau_dv, &mut self.dacceleration_dv);
        }
        Ok(())
    }
}
