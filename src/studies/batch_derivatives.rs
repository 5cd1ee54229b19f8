//! The analytical derivatives `lsdc eval --derivatives` adds to a state (`batch`): of the inverse
//! dynamics (∂τ/∂q, ∂τ/∂v, when `a` is given), of the forward dynamics (∂q̈/∂q, ∂q̈/∂v, ∂q̈/∂τ,
//! when `tau` is given) and of the mass matrix (∂M/∂q_j, one matrix per velocity j), computed by
//! `dynamics::algorithms::{rnea_derivatives, aba_derivatives, crba_derivatives}`. Derivatives along
//! q are along the velocities (a spherical or free joint's tangent space, q · exp(ε e_j)).
//!
//! The program's efforts (its forces, torques and link efforts: springs, dampers, any law of the
//! frames' states and of the coordinates and rates) are differentiated too, through their
//! compiled tape in forward mode (`dynamics::effort_derivatives`), on trees whose joints are
//! one-coordinate dof chains: the inverse dynamics τ = RNEA(q, v, a; f) − τ_links changes by
//! ∂RNEA/∂x|_f − D and the forward dynamics by ∂ABA/∂x|_f + M⁻¹ D, D the efforts' derivatives.
//! Where those do not cover the program (actuators' laws, friction, the programs' states,
//! spherical and free joints, loops) its efforts are held at their values at the state, in the
//! bodies' frames (`efforts_held` says so).

use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};

use crate::dynamics::algorithms::aba_derivatives::AbaDerivatives;
use crate::dynamics::algorithms::crba_derivatives::mass_derivatives;
use crate::dynamics::algorithms::rnea_derivatives::RneaDerivatives;
use crate::dynamics::algorithms::Data;
use crate::dynamics::model::Model;
use crate::spatial::Force;

/// A matrix by rows, as the JSON gives it.
pub type Rows = Vec<Vec<f64>>;

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct InverseDerivatives {
    pub dq: Rows,
    pub dv: Rows,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct ForwardDerivatives {
    pub dq: Rows,
    pub dv: Rows,
    pub dtau: Rows,
}

/// The derivatives at one state; `rnea` and `aba` are present when `a` and `tau` were given.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct StateDerivatives {
    /// Whether the program has efforts besides gravity that are held fixed rather than
    /// differentiated.
    pub efforts_held: bool,
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub rnea: Option<InverseDerivatives>,
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub aba: Option<ForwardDerivatives>,
    /// ∂M/∂q_j for each velocity j, each by rows.
    pub crba: Vec<Rows>,
}

fn rows(m: &DMatrix<f64>) -> Rows {
    m.row_iter().map(|r| r.iter().copied().collect()).collect()
}

/// Whether the model has efforts beyond gravity.
fn has_efforts(model: &Model) -> bool {
    !model.applied.is_empty()
        || !model.link_efforts.is_empty()
        || !model.frictions.is_empty()
        || model.actuation.is_some()
}

/// The derivatives at (q, v), of RNEA at `a` and of ABA at `tau` when given, under the external
/// forces `external` (per body, in its frame), with the efforts' derivatives `efforts` (D, nv ×
/// 2nv along q then v: `MechanicalSystem::effort_derivatives`) where they are computed.
pub fn state_derivatives(
    model: &Model,
    data: &mut Data,
    (q, v): (&[f64], &[f64]),
    (a, tau): (Option<&[f64]>, Option<&[f64]>),
    external: &[Force],
    efforts: Option<&DMatrix<f64>>,
) -> Result<StateDerivatives, String> {
    let nv = model.nv;
    // D's halves, or zeros where the efforts are held.
    let zero = DMatrix::zeros(nv, nv);
    let (along_q, along_v) = match efforts {
        Some(d) => (
            d.columns(0, nv).into_owned(),
            d.columns(nv, nv).into_owned(),
        ),
        None => (zero.clone(), zero),
    };
    let rnea = match a {
        Some(a) => {
            let mut inverse = RneaDerivatives::new(model);
            (inverse.compute(model, data, q, v, a, external)).map_err(|e| e.to_string())?;
            Some(InverseDerivatives {
                dq: rows(&(&inverse.dtau_dq - &along_q)),
                dv: rows(&(&inverse.dtau_dv - &along_v)),
            })
        }
        None => None,
    };
    let aba = match tau {
        Some(tau) => {
            let mut forward = AbaDerivatives::new(model);
            (forward.compute(model, data, q, v, tau, external)).map_err(|e| e.to_string())?;
            let inverse_mass = &forward.mass_inverse;
            Some(ForwardDerivatives {
                dq: rows(&(&forward.dacceleration_dq + inverse_mass * &along_q)),
                dv: rows(&(&forward.dacceleration_dv + inverse_mass * &along_v)),
                dtau: rows(inverse_mass),
            })
        }
        None => None,
    };
    let mass = mass_derivatives(model, data, q).map_err(|e| e.to_string())?;
    Ok(StateDerivatives {
        efforts_held: has_efforts(model) && efforts.is_none(),
        rnea,
        aba,
        crba: mass.iter().map(rows).collect(),
    })
}
