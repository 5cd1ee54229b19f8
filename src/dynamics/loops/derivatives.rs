//! Derivatives of the constrained forward dynamics of a mechanism with closed loops:
//! ∂q̈/∂q, ∂q̈/∂v and ∂q̈/∂τ of the accelerations that solve
//!
//!   M(q) q̈ + b(q, v) = τ + Gᵀλ,   G(q) q̈ + γ(q, v) = 0
//!
//! on the rows the loops' `Structure` keeps, and the same derivatives in the independent
//! coordinates z of the motion on the loops (`IndependentDerivatives`).
//!
//! Differentiating the saddle-point (KKT) system at the solution (q̈, λ), as Pinocchio's
//! `computeConstraintDynamicsDerivatives` does (Carpentier & Mansard, "Analytical Derivatives of
//! Rigid Body Dynamics Algorithms", RSS 2018, §IV, extended to constraints in Sathya &
//! Carpentier, "Constrained Articulated Body Dynamics Algorithms", 2023), gives for a
//! direction x of q or v:
//!
//!   [ M  −Gᵀ ] [ ∂q̈ ]   [ −∂τ_ID/∂x + ∂(Gᵀλ)/∂x ]
//!   [ G   0  ] [ ∂λ ] = [ −∂(G q̈ + γ)/∂x         ]
//!
//! with τ_ID = RNEA(q, v, q̈) and λ, q̈ held fixed in the right-hand side; ∂τ gives the
//! right-hand side [I; 0]. The parts:
//!
//! - ∂τ_ID/∂q, ∂τ_ID/∂v: the analytical derivatives of inverse dynamics at (q, v, q̈)
//!   (`RneaDerivatives`), the external forces held in the bodies' frames;
//! - ∂(Gᵀλ)/∂q, ∂(G q̈ + γ)/∂q and ∂γ/∂v: the loops' rows evaluated in dual numbers
//!   (`rows::constraints_into` is generic over its scalar), one direction per state velocity
//!   (several directions per pass in vector dual numbers, `DualSVec64<4>`, measured slower:
//!   BENCHMARKS.md); forward mode carries the exact derivative, not a difference. Each direction's products
//!   with λ, q̈ and v are read off the rows' sparse blocks, without a dense copy of ∂G;
//! - one LU factorisation of the saddle-point matrix serves the accelerations, the multipliers
//!   and every right-hand side.
//!
//! The directions of q are those of the analytical derivatives of the tree: each state velocity
//! moves the positions along its joint's tangent space (`Model::position_rates` of a unit
//! velocity).
//!
//! On the loops, q = q(z) and v = T(q) ż with T the allowed motions whose independent
//! coordinates' rows are the identity ([Eᵀ; Gₛ] T = [I; 0]). Then
//! ∂z̈/∂ż = Eᵀ (∂q̈/∂v) T, ∂z̈/∂τ = Eᵀ ∂q̈/∂τ and ∂z̈/∂z = Eᵀ (∂q̈/∂q T + ∂q̈/∂v W), where
//! W = ∂v/∂z solves [Eᵀ; Gₛ] W = [0; −(∂G/∂q T) v] (the dependent rates follow the rows as
//! they turn).
//!
//! The motions without mass (a rod spinning between two ball joints) and the ball joints' idle
//! angles make the saddle-point matrix singular, rows that close only at second order nearly
//! so: such mechanisms are refused (`WithoutMass`, `WeakRows`), with an error.

use nalgebra::{DMatrix, DVector};
use num_dual::Dual64;

use super::rows::{constraints_into, Constraints, Extent};
use super::structure::Structure;
use crate::dynamics::algorithms::rnea_derivatives::{
    check_supported, DerivativeError, RneaDerivatives,
};
use crate::dynamics::algorithms::{crba_into, forward_kinematics, rnea_into, Data};
use crate::dynamics::model::Model;
use crate::kinematics::eval::EvalError;
use crate::spatial::Force;

/// Why the constrained dynamics' derivatives cannot be computed.
#[derive(Clone, Debug, PartialEq)]
pub enum ConstrainedDerivativeError {
    /// A joint the analytical derivatives of the tree do not cover, or a geometry that cannot
    /// be evaluated.
    Derivatives(DerivativeError),
    /// The loops' rows cannot be evaluated in dual numbers (a complementary link whose dof
    /// chain is evaluated in general), or at all.
    Evaluation(EvalError),
    /// The constrained equations have no unique solution here: the kept rows are dependent
    /// (a singular configuration).
    Singular,
    /// The loops allow motions that move no mass (a rod spinning between two ball joints) or
    /// leave coordinates idle (a ball joint's angles): the solve leaves them at rest, which is
    /// not a function of the state these derivatives differentiate.
    WithoutMass { motions: usize },
    /// Some kept rows close their loop only at second order (`RowChoice::weak`): independent
    /// of the others by about the square root of the closure residual, the configuration is
    /// singular but for round-off, and the accelerations' derivatives are amplified by the
    /// inverse of that (measured on `maille1`: 1e-9 between two exact solves, 4e-3 between
    /// the derivatives and central differences); they are not computed.
    WeakRows { rows: usize },
    /// The independent coordinates asked for are not as many as the motions the kept rows
    /// allow, or do not parametrise them.
    NotIndependent { given: usize, allowed: usize },
}

impl From<DerivativeError> for ConstrainedDerivativeError {
    fn from(e: DerivativeError) -> Self {
        ConstrainedDerivativeError::Derivatives(e)
    }
}

impl From<EvalError> for ConstrainedDerivativeError {
    fn from(e: EvalError) -> Self {
        ConstrainedDerivativeError::Evaluation(e)
    }
}

impl std::fmt::Display for ConstrainedDerivativeError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ConstrainedDerivativeError::Derivatives(e) => write!(f, "{e}"),
            ConstrainedDerivativeError::Evaluation(e) => {
                write!(f, "the loops' rows cannot be differentiated: {e:?}")
            }
            ConstrainedDerivativeError::Singular => write!(
                f,
                "the constrained equations of motion are singular here (dependent loop rows): \
                 their derivatives are not defined"
            ),
            ConstrainedDerivativeError::WithoutMass { motions } => write!(
                f,
                "the loops allow {motions} motions that move no mass (or idle coordinates): \
                 the derivatives of the constrained dynamics are not computed for them"
            ),
            ConstrainedDerivativeError::WeakRows { rows } => write!(
                f,
                "{rows} loop rows close only at second order (a singular configuration but for \
                 round-off): the derivatives of the constrained dynamics are not computed there"
            ),
            ConstrainedDerivativeError::NotIndependent { given, allowed } => write!(
                f,
                "{given} coordinates were given as independent where the loops allow {allowed} \
                 motions, or they do not parametrise them"
            ),
        }
    }
}

/// The derivatives in independent coordinates z (as many as the motions the loops allow).
#[derive(Clone, Debug)]
pub struct IndependentDerivatives {
    /// ∂z̈/∂z and ∂z̈/∂ż, m × m.
    pub dacceleration_dz: DMatrix<f64>,
    pub dacceleration_drates: DMatrix<f64>,
    /// ∂z̈/∂τ, m × (state velocities): a generalised force along any state velocity.
    pub dacceleration_dtau: DMatrix<f64>,
    /// ∂q/∂z = T: the allowed motions whose independent coordinates' rows are the identity.
    /// Read by the tests (z's derivatives carried back to q's); built only where the
    /// library's internals are public.
    #[cfg(lsdc_internals)]
    pub tangent: DMatrix<f64>,
}

/// The constrained accelerations and their derivatives, with the scratch they are computed
/// in; `new(&model)` once.
pub struct ConstrainedDerivatives {
    /// q̈ over the state's velocities, and λ over the kept rows (Gₛ's sign: M q̈ + b = τ + Gₛᵀλ).
    pub acceleration: DVector<f64>,
    pub multipliers: DVector<f64>,
    /// ∂q̈/∂q (along each state velocity's tangent direction), ∂q̈/∂v, ∂q̈/∂τ; n × n each.
    pub dacceleration_dq: DMatrix<f64>,
    pub dacceleration_dv: DMatrix<f64>,
    pub dacceleration_dtau: DMatrix<f64>,
    /// The kept rows of G at the last state, and (∂G/∂q_j) v by columns j.
    jacobian: DMatrix<f64>,
    velocity_rows_dq: DMatrix<f64>,
    inverse: RneaDerivatives,
    mass: DMatrix<f64>,
    bias: DVector<f64>,
    rows: Constraints,
    dual_data: Data<Dual64>,
    dual_rows: Constraints<Dual64>,
}

impl ConstrainedDerivatives {
    pub fn new(model: &Model) -> ConstrainedDerivatives {
        let n = model.velocities();
        ConstrainedDerivatives {
            acceleration: DVector::zeros(n),
            multipliers: DVector::zeros(0),
            dacceleration_dq: DMatrix::zeros(n, n),
            dacceleration_dv: DMatrix::zeros(n, n),
            dacceleration_dtau: DMatrix::zeros(n, n),
            jacobian: DMatrix::zeros(0, n),
            velocity_rows_dq: DMatrix::zeros(0, n),
            inverse: RneaDerivatives::new(model),
            mass: DMatrix::zeros(model.nv, model.nv),
            bias: DVector::zeros(model.nv),
            rows: Constraints::new(model),
            dual_data: Data::with_scalar(model),
            dual_rows: Constraints::with_scalar(model),
        }
    }

    /// q̈, λ and their derivatives at (q, v) (state lengths) under the generalised forces `tau`
    /// (one per state velocity) and the external forces `external` (per body, in its frame),
    /// on the loops' rows `structure` keeps.
    #[allow(clippy::too_many_arguments)]
    pub fn compute(
        &mut self,
        model: &Model,
        data: &mut Data,
        structure: &Structure,
        q: &[f64],
        v: &[f64],
        tau: &[f64],
        external: &[Force],
    ) -> Result<(), ConstrainedDerivativeError> {
        check_supported(model)?;
        let without_mass = structure.massless + structure.idle.len();
        if without_mass > 0 {
            return Err(ConstrainedDerivativeError::WithoutMass {
                motions: without_mass,
            });
        }
        if structure.choice.weak > 0 {
            return Err(ConstrainedDerivativeError::WeakRows {
                rows: structure.choice.weak,
            });
        }
        let kept = &structure.choice.rows;
        let (n, nv, r) = (model.velocities(), model.nv, kept.len());
        forward_kinematics(model, data, q, v)?;
        constraints_into(model, data, q, v, Extent::Motion, &mut self.rows)?;
        self.jacobian = self.rows.jacobian.dense().select_rows(kept);
        let gamma = self.rows.bias.select_rows(kept);
        crba_into(model, data, q, &mut self.mass)?;
        let rest = vec![0.0; nv];
        rnea_into(model, data, q, v, &rest, external, &mut self.bias)?;

        // The saddle-point matrix [M −Gₛᵀ; Gₛ 0] and its factor.
        let mut saddle = DMatrix::zeros(n + r, n + r);
        saddle.view_mut((0, 0), (nv, nv)).copy_from(&self.mass);
        saddle
            .view_mut((0, n), (n, r))
            .copy_from(&(-self.jacobian.transpose()));
        saddle.view_mut((n, 0), (r, n)).copy_from(&self.jacobian);
        let factor = saddle.lu();
        let mut right = DVector::zeros(n + r);
        right.rows_mut(0, n).copy_from_slice(tau);
        let mut top = right.rows_mut(0, nv);
        top -= &self.bias;
        right.rows_mut(n, r).copy_from(&(-&gamma));
        let solution = factor
            .solve(&right)
            .filter(|x| x.iter().all(|x| x.is_finite()))
            .ok_or(ConstrainedDerivativeError::Singular)?;
        self.acceleration = solution.rows(0, n).into_owned();
        self.multipliers = solution.rows(n, r).into_owned();

        // Inverse dynamics' derivatives at the accelerations found.
        let accelerations = &self.acceleration.as_slice()[..nv];
        (self.inverse).compute(model, data, q, v, accelerations, external)?;

        // The rows' derivatives in dual numbers, one direction of q, then of v, per velocity.
        let mut rows_dq = DMatrix::zeros(n + r, n);
        let mut rows_dv = DMatrix::zeros(n + r, n);
        self.velocity_rows_dq = DMatrix::zeros(r, n);
        let (mut unit, mut direction) = (vec![0.0; n], vec![0.0; q.len()]);
        let plain = |x: &[f64]| x.iter().map(|&x| Dual64::from_re(x)).collect::<Vec<_>>();
        let seeded = |x: &[f64], d: &[f64]| {
            (x.iter().zip(d))
                .map(|(&x, &d)| Dual64::new(x, d))
                .collect::<Vec<_>>()
        };
        let (q_plain, v_plain) = (plain(q), plain(v));
        for j in 0..n {
            unit[j] = 1.0;
            model.position_rates(q, &unit, &mut direction);
            self.dual_pass(model, &seeded(q, &direction), &v_plain)?;
            // (∂Gₛ/∂q_j)ᵀλ − ∂τ_ID/∂q_j over the velocities (the complementary links'
            // coordinates carry no inertia: τ_ID depends on the tree's), and
            // −(∂Gₛ/∂q_j q̈ + ∂γ/∂q_j) below; (∂Gₛ/∂q_j) v for the chart.
            let mut column = rows_dq.column_mut(j);
            for (i, &row) in kept.iter().enumerate() {
                let (mut times_acceleration, mut times_velocity) = (0.0, 0.0);
                for (c, value) in self.dual_rows.jacobian.row(row) {
                    column[c] += value.eps * self.multipliers[i];
                    times_acceleration += value.eps * self.acceleration[c];
                    times_velocity += value.eps * v[c];
                }
                column[n + i] = -(times_acceleration + self.dual_rows.bias[row].eps);
                self.velocity_rows_dq[(i, j)] = times_velocity;
            }
            if j < nv {
                let mut tree = column.rows_mut(0, nv);
                tree -= self.inverse.dtau_dq.column(j);
            }
            self.dual_pass(model, &q_plain, &seeded(v, &unit))?;
            let mut column = rows_dv.column_mut(j);
            if j < nv {
                column
                    .rows_mut(0, nv)
                    .copy_from(&(-self.inverse.dtau_dv.column(j)));
            }
            for (i, &row) in kept.iter().enumerate() {
                column[n + i] = -self.dual_rows.bias[row].eps;
            }
            unit[j] = 0.0;
        }
        let mut rows_dtau = DMatrix::zeros(n + r, n);
        rows_dtau.view_mut((0, 0), (n, n)).fill_with_identity();
        for (right, out) in [
            (rows_dq, &mut self.dacceleration_dq),
            (rows_dv, &mut self.dacceleration_dv),
            (rows_dtau, &mut self.dacceleration_dtau),
        ] {
            let solved = factor
                .solve(&right)
                .ok_or(ConstrainedDerivativeError::Singular)?;
            out.copy_from(&solved.rows(0, n));
        }
        Ok(())
    }

    /// The loops' rows and their bias at the dual state (q, v), into `dual_rows`.
    fn dual_pass(&mut self, model: &Model, q: &[Dual64], v: &[Dual64]) -> Result<(), EvalError> {
        forward_kinematics(model, &mut self.dual_data, q, v)?;
        let (data, rows) = (&mut self.dual_data, &mut self.dual_rows);
        constraints_into(model, data, q, v, Extent::Motion, rows)
    }

    /// The derivatives of the last `compute` in the independent coordinates `independent`
    /// (state velocities, each a coordinate's rate), at its state, which must be on the loops
    /// (G v = 0).
    pub fn in_independent_coordinates(
        &self,
        independent: &[usize],
    ) -> Result<IndependentDerivatives, ConstrainedDerivativeError> {
        let (r, n) = self.jacobian.shape();
        let m = independent.len();
        let not_independent = ConstrainedDerivativeError::NotIndependent {
            given: m,
            allowed: n.saturating_sub(r),
        };
        if m + r != n {
            return Err(not_independent);
        }
        // [Eᵀ; Gₛ], square.
        let mut chart = DMatrix::zeros(n, n);
        for (k, &i) in independent.iter().enumerate() {
            chart[(k, i)] = 1.0;
        }
        chart.view_mut((m, 0), (r, n)).copy_from(&self.jacobian);
        let factor = chart.lu();
        let mut right = DMatrix::zeros(n, m);
        right.view_mut((0, 0), (m, m)).fill_with_identity();
        let tangent = factor
            .solve(&right)
            .filter(|t| t.iter().all(|x| x.is_finite()))
            .ok_or(not_independent.clone())?;
        right.fill(0.0);
        right
            .view_mut((m, 0), (r, m))
            .copy_from(&(-(&self.velocity_rows_dq * &tangent)));
        let rates_dz = factor.solve(&right).expect("factored above");
        let select = |matrix: &DMatrix<f64>| matrix.select_rows(independent);
        let dq = &self.dacceleration_dq * &tangent + &self.dacceleration_dv * &rates_dz;
        Ok(IndependentDerivatives {
            dacceleration_dz: select(&dq),
            dacceleration_drates: select(&(&self.dacceleration_dv * &tangent)),
            dacceleration_dtau: select(&self.dacceleration_dtau),
            #[cfg(lsdc_internals)]
            tangent,
        })
    }
}
