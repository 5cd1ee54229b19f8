//! The forward sensitivity equations integrated with the run: the augmented system
//! (x, S₁, …, S_m) with x' = f(t, x; p) and S_j' = ∂f/∂x S_j + ∂f/∂p_j, S_j(0) = ∂x₀/∂p_j, one
//! ODE whose every component the step control watches, so that the sensitivities' error is
//! controlled with the state's (Hairer, Nørsett & Wanner I, §I.14; Maly & Petzold, "Numerical
//! methods and software for sensitivity analysis of differential-algebraic systems", Appl.
//! Numer. Math. 20 (1996) 57–79, the *simultaneous corrector* scheme for explicit methods).
//!
//! How each term is computed, and why it is the cheapest exact route at hand:
//! - ∂f/∂x S_j is exact where the analytical derivatives of the articulated-body algorithm
//!   are f's whole derivative (Carpentier & Mansard, RSS 2018, `aba_derivatives`): a tree whose
//!   right-hand side is the rigid-body dynamics under a uniform gravity field (the weights the
//!   model recognises as one, `Model::gravity`), with no other effort and no state. Elsewhere
//!   it is a directional derivative of f along S_j, by one central difference (two
//!   evaluations of f per parameter, CVODES's internal difference quotient): those
//!   derivatives hold the applied efforts fixed in the bodies' frames and the efforts' tape has
//!   no forward mode yet, so the efforts would be differenced anyway, and m directions cost
//!   less than the n columns of a Jacobian of differences.
//! - ∂f/∂p_j, for a value of the program, is a central difference between the mechanism
//!   prepared at p_j ± h (two evaluations): the model (lengths, masses, inertias, efforts) is
//!   compiled with the values in it, and nothing differentiates the compilation. An initial
//!   value does not enter f: its term is zero.
//! - The outputs' derivatives d(y)/d(p_j) = ∂y/∂x S_j + ∂y/∂p_j likewise.
//!
//! The steps are h = ε^(1/3) max(1, |·|), the optimum of a central difference: truncation
//! h²/6 |f'''| and rounding ε|f|/h balance near 1e-11 relative, far below the tolerances.

use nalgebra::{DMatrix, DVector};

use super::parameters::Parameter;
use crate::dynamics::algorithms::aba_derivatives::AbaDerivatives;
use crate::dynamics::algorithms::forward_kinematics;
use crate::dynamics::algorithms::rnea_derivatives::check_supported;
use crate::dynamics::compiled::{EffortScratch, EffortState};
use crate::integrate::{CallbackError, OdeSystem};
use crate::prepare::Prepared;
use crate::simulate::system::{MechanicalSystem, SystemError};
use crate::spatial::Force;
use crate::studies::sweep::runs::Target;

/// The relative step of a central difference: the cube root of the machine epsilon.
pub fn central_step(scale: f64) -> f64 {
    f64::EPSILON.cbrt() * scale.abs().max(1.0)
}

/// One prepared mechanism evaluated at any state x = (positions, velocities, the program's
/// states): its state derivative and the quantities a sample writes.
pub struct Variant<'p> {
    pub prepared: &'p Prepared,
    system: MechanicalSystem<'p>,
    scratch: EffortScratch,
    /// The analytical derivatives' scratch, where they give ∂f/∂x (`has_exact_jacobian`).
    derivatives: Option<Box<AbaDerivatives>>,
}

impl<'p> Variant<'p> {
    pub fn new(prepared: &'p Prepared) -> Variant<'p> {
        let model = &prepared.model;
        let stabilisation = prepared.settings.stabilisation;
        Variant {
            prepared,
            system: MechanicalSystem::new(model, prepared.coordinates.clone(), stabilisation),
            scratch: EffortScratch::default(),
            derivatives: has_exact_jacobian(prepared).then(|| Box::new(AbaDerivatives::new(model))),
        }
    }

    /// ∂f/∂x at x from the analytical derivatives of ABA, where they are exact
    /// ([`has_exact_jacobian`]): [[0, I], [∂q̈/∂q, ∂q̈/∂v]]. `None` elsewhere, or where the mass
    /// matrix is not positive definite (f's own evaluation says why).
    fn exact_jacobian(&mut self, x: &[f64]) -> Option<DMatrix<f64>> {
        let derivatives = self.derivatives.as_mut()?;
        let model = self.system.model;
        let nv = model.nv;
        let (q, v) = x.split_at(model.nq);
        let tau = vec![0.0; nv];
        let external = vec![Force::zeros(); model.body_count() + 1];
        let data = &mut self.system.scratch.data;
        derivatives
            .compute(model, data, q, v, &tau, &external)
            .ok()?;
        let mut jacobian = DMatrix::zeros(2 * nv, 2 * nv);
        jacobian.view_mut((0, nv), (nv, nv)).fill_with_identity();
        (jacobian.view_mut((nv, 0), (nv, nv))).copy_from(&derivatives.dacceleration_dq);
        (jacobian.view_mut((nv, nv), (nv, nv))).copy_from(&derivatives.dacceleration_dv);
        Some(jacobian)
    }

    /// The length of x: positions, velocities, states.
    pub fn dimension(&self) -> usize {
        self.system.dimension() + self.system.state_count()
    }

    /// The start of the run from declared coordinates and rates: positions, velocities, then
    /// the program's states' initial values.
    pub fn start(&self, coordinates: &[f64], rates: &[f64]) -> Result<Vec<f64>, SystemError> {
        let model = self.system.model;
        let (mut x, v) = model.state_from_declared(coordinates, rates)?;
        x.extend_from_slice(&v);
        x.extend(model.states.iter().map(|state| state.initial));
        Ok(x)
    }

    /// x' = f(t, x) into `rates`.
    pub fn rates(&mut self, t: f64, x: &[f64], rates: &mut [f64]) -> Result<(), SystemError> {
        let n = self.system.dimension();
        self.system.set_states(&x[n..]);
        self.system.derivative(t, &x[..n], &mut rates[..n])?;
        if x.len() > n {
            self.system.state_rates(&mut rates[n..])?;
        }
        Ok(())
    }

    /// The declared coordinates, their rates, the program's states and outputs at (t, x), in
    /// the order of `quantity_names`.
    pub fn quantities(&mut self, t: f64, x: &[f64]) -> Result<Vec<f64>, SystemError> {
        let model = self.system.model;
        let n = self.system.dimension();
        if self.prepared.outputs.reads_model {
            // The model in the actuated coordinates comes from an evaluation, as in a run.
            let mut rates = vec![0.0; x.len()];
            self.rates(t, x, &mut rates)?;
        }
        self.system.set_states(&x[n..]);
        let (q, v) = model.split_state(&x[..n]);
        let (coordinates, rates) = model.declared((t, &q, v), &self.system.state.reference)?;
        let scratch = &mut *self.system.scratch;
        let model_values = (scratch.model_laws.as_ref()).map_or(&[][..], |r| &r.values[..]);
        forward_kinematics(model, &mut scratch.data, &q, v)?;
        let state = EffortState {
            world: &scratch.data.world,
            velocity: &scratch.data.velocity,
            coordinates: &coordinates,
            rates: &rates,
            states: &x[n..],
            time: t,
            model: model_values,
        };
        let outputs = self.prepared.outputs.values(&state, &mut self.scratch);
        let mut values = coordinates;
        values.extend_from_slice(&rates);
        values.extend_from_slice(&x[n..]);
        values.extend(outputs);
        Ok(values)
    }
}

/// Whether the analytical derivatives of ABA are the whole ∂f/∂x of `prepared`: a tree of
/// joints whose motion subspaces they cover, whose coordinates are its positions (no
/// quaternion), under no effort but a uniform gravity field and with no state of the program.
pub fn has_exact_jacobian(prepared: &Prepared) -> bool {
    let model = &prepared.model;
    !model.has_efforts()
        && model.states.is_empty()
        && !model.has_loops()
        && model.mimics.is_empty()
        && model.positions() == model.velocities()
        && check_supported(model).is_ok()
}

/// A value of the program's mechanism prepared at p + h and at p − h, and 2h as represented.
pub struct Preparations {
    pub plus: Prepared,
    pub minus: Prepared,
    pub width: f64,
}

/// The variants of [`Preparations`], evaluated.
pub struct Shifted<'p> {
    pub plus: Variant<'p>,
    pub minus: Variant<'p>,
    pub width: f64,
}

/// What a variant evaluates at (t, x): its state derivative, or its quantities.
type Evaluate<'p> = fn(&mut Variant<'p>, f64, &[f64]) -> Result<Vec<f64>, SystemError>;

/// A sample of the augmented run: the quantities and, for each quantity then each parameter,
/// its derivative.
pub struct Row {
    pub time: f64,
    pub values: Vec<f64>,
    pub derivatives: Vec<f64>,
}

/// The augmented system (x, S₁, …, S_m), S_j stored after x in turn.
pub struct Augmented<'p> {
    pub nominal: Variant<'p>,
    /// Per parameter, the shifted models of a value of the program (`None` for an initial
    /// value, which f does not depend on).
    pub shifted: Vec<Option<Shifted<'p>>>,
    /// The samples observed so far.
    pub rows: Vec<Row>,
}

impl<'p> Augmented<'p> {
    /// The augmented system of `parameters` with the models `shifted` (see the field).
    pub fn new(
        nominal: &'p Prepared,
        parameters: &[Parameter],
        shifted: &'p [Preparations],
    ) -> Augmented<'p> {
        let mut models = shifted.iter();
        let shifted = (parameters.iter())
            .map(|p| match p.target {
                Target::Value => models.next().map(|models| Shifted {
                    plus: Variant::new(&models.plus),
                    minus: Variant::new(&models.minus),
                    width: models.width,
                }),
                Target::Initial { .. } => None,
            })
            .collect();
        Augmented {
            nominal: Variant::new(nominal),
            shifted,
            rows: Vec::new(),
        }
    }

    fn state_dimension(&self) -> usize {
        self.nominal.dimension()
    }

    /// The derivative along S_j of `evaluate` at (t, x), central: (g(x + δS) − g(x − δS)) / 2δ,
    /// with δ moving x by a relative ε^(1/3); zero along S_j = 0.
    fn along(
        variant: &mut Variant<'p>,
        (t, x, direction): (f64, &[f64], &[f64]),
        evaluate: Evaluate<'p>,
        into: &mut [f64],
    ) -> Result<(), SystemError> {
        let size = direction.iter().fold(0.0f64, |m, d| m.max(d.abs()));
        if size == 0.0 {
            return Ok(());
        }
        let scale = x.iter().fold(0.0f64, |m, d| m.max(d.abs()));
        let delta = central_step(scale) / size;
        let moved = |sign: f64| -> Vec<f64> {
            (x.iter().zip(direction))
                .map(|(x, d)| x + sign * delta * d)
                .collect()
        };
        let plus = evaluate(variant, t, &moved(1.0))?;
        let minus = evaluate(variant, t, &moved(-1.0))?;
        for (k, value) in into.iter_mut().enumerate() {
            *value += (plus[k] - minus[k]) / (2.0 * delta);
        }
        Ok(())
    }

    /// The central difference between the shifted models of `evaluate` at (t, x), added to
    /// `into`.
    fn across(
        shifted: &mut Shifted<'p>,
        (t, x): (f64, &[f64]),
        evaluate: Evaluate<'p>,
        into: &mut [f64],
    ) -> Result<(), SystemError> {
        let plus = evaluate(&mut shifted.plus, t, x)?;
        let minus = evaluate(&mut shifted.minus, t, x)?;
        for (k, value) in into.iter_mut().enumerate() {
            *value += (plus[k] - minus[k]) / shifted.width;
        }
        Ok(())
    }

    /// d(g)/d(p_j) = ∂g/∂x S_j + ∂g/∂p_j for each parameter, parameter after parameter, where
    /// `evaluate` gives g at (t, x) of a variant, and ∂g/∂x is `jacobian` when given.
    fn total_derivatives(
        &mut self,
        (t, augmented): (f64, &[f64]),
        length: usize,
        evaluate: Evaluate<'p>,
        jacobian: Option<&DMatrix<f64>>,
    ) -> Result<Vec<Vec<f64>>, SystemError> {
        let n = self.state_dimension();
        let x = &augmented[..n];
        let mut columns = Vec::with_capacity(self.shifted.len());
        for (j, shifted) in self.shifted.iter_mut().enumerate() {
            let direction = &augmented[n * (j + 1)..n * (j + 2)];
            let mut column = match jacobian {
                Some(jacobian) => (jacobian * DVector::from_column_slice(direction))
                    .data
                    .into(),
                None => vec![0.0; length],
            };
            if jacobian.is_none() {
                Self::along(&mut self.nominal, (t, x, direction), evaluate, &mut column)?;
            }
            if let Some(shifted) = shifted {
                Self::across(shifted, (t, x), evaluate, &mut column)?;
            }
            columns.push(column);
        }
        Ok(columns)
    }
}

/// f at (t, x) of a variant, as a vector.
fn state_rates(variant: &mut Variant<'_>, t: f64, x: &[f64]) -> Result<Vec<f64>, SystemError> {
    let mut rates = vec![0.0; x.len()];
    variant.rates(t, x, &mut rates)?;
    Ok(rates)
}

fn quantities(variant: &mut Variant<'_>, t: f64, x: &[f64]) -> Result<Vec<f64>, SystemError> {
    variant.quantities(t, x)
}

impl OdeSystem for Augmented<'_> {
    fn dimension(&self) -> usize {
        self.state_dimension() * (1 + self.shifted.len())
    }

    fn rhs(&mut self, t: f64, y: &[f64], dydt: &mut [f64]) -> Result<(), CallbackError> {
        let n = self.state_dimension();
        self.nominal.rates(t, &y[..n], &mut dydt[..n])?;
        let jacobian = self.nominal.exact_jacobian(&y[..n]);
        let columns = self.total_derivatives((t, y), n, state_rates, jacobian.as_ref())?;
        for (j, column) in columns.iter().enumerate() {
            dydt[n * (j + 1)..n * (j + 2)].copy_from_slice(column);
        }
        Ok(())
    }

    fn autonomous(&self) -> bool {
        self.nominal.system.autonomous()
    }

    fn observe(&mut self, t: f64, y: &[f64]) -> Result<(), CallbackError> {
        let n = self.state_dimension();
        let values = self.nominal.quantities(t, &y[..n])?;
        let columns = self.total_derivatives((t, y), values.len(), quantities, None)?;
        // For each quantity, its derivative with respect to each parameter in turn.
        let derivatives = (0..values.len())
            .flat_map(|k| columns.iter().map(move |column| column[k]))
            .collect();
        self.rows.push(Row {
            time: t,
            values,
            derivatives,
        });
        Ok(())
    }
}
