//! ∂M/∂q, the derivatives of the mass matrix (CRBA) along each velocity's tangent direction.
//! M(q) a is inverse dynamics without velocity, gravity or external force, so column l of ∂M/∂q_j
//! is ∂τ/∂q_j of RNEA(q, 0, e_l) (`rnea_derivatives`, Carpentier & Mansard, RSS 2018): one pass
//! of the inverse dynamics' derivatives per column, geared rotors included.

use nalgebra::DMatrix;

use super::rnea_derivatives::{DerivativeError, RneaDerivatives};
use super::Data;
use crate::dynamics::model::Model;
use crate::spatial::{Force, Motion};

/// ∂M/∂q_j for every velocity j (nv matrices of nv × nv) at positions q.
pub fn mass_derivatives(
    model: &Model,
    data: &mut Data,
    q: &[f64],
) -> Result<Vec<DMatrix<f64>>, DerivativeError> {
    let nv = model.nv;
    let mut derivatives = vec![DMatrix::zeros(nv, nv); nv];
    let mut inverse = RneaDerivatives::new(model);
    let (zero, mut unit) = (vec![0.0; nv], vec![0.0; nv]);
    let external = vec![Force::zeros(); model.body_count() + 1];
    for l in 0..nv {
        unit[l] = 1.0;
        let state = (q, zero.as_slice(), unit.as_slice());
        inverse.compute_with_base(model, data, state, &external, Motion::zeros())?;
        unit[l] = 0.0;
        for (j, derivative) in derivatives.iter_mut().enumerate() {
            derivative.set_column(l, &inverse.dtau_dq.column(j));
        }
    }
    Ok(derivatives)
}
