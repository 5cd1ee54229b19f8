//! Identification of a mechanism's parameters from measured motion and efforts (`lsdc
//! identify`): the parameters that enter inverse dynamics linearly (bodies' inertial
//! parameters, joints' friction, `parameters`) by linear least squares on the regressor
//! (`dynamics::algorithms::regressor`), on their base parameters (`base`), from the measurements
//! of a CSV file (`measured`).
//!
//! Along the samples, each measured effort gives one equation: the effort is RNEA's at the
//! sample's (q, q̇, q̈) with the program's efforts and gravity, less the program's efforts, plus
//! the friction c q̇ + F_c sign q̇ that the actuator overcomes. That is linear in the parameters
//! asked for, the others held at the program's values: τ − (prediction at the program's values
//! − Y_asked π_program) = Y_asked π. The solve is on the base parameters, columns scaled to
//! unit norm, by the SVD, which gives the condition number; standard deviations come from the
//! residual's variance σ² = |r|² / (equations − base parameters) times (WᵀW)⁻¹ (the errors
//! taken independent, of equal variance, and the regressor exact).
//!
//! Parameters that enter nonlinearly (a length, a stiffness, an initial value) are fitted to
//! measured quantities of whole runs by Levenberg–Marquardt on the runs' sensitivities
//! (`nonlinear`): `parameters` refuses their names, and the command takes them there.

pub mod base;
pub mod loops;
pub mod measured;
pub mod nonlinear;
pub mod parameters;

use nalgebra::{DMatrix, DVector};
use serde::ser::SerializeMap;
use serde::{Serialize, Serializer};

use self::base::{base_parameters, BaseParameters};
use self::loops::LoopState;
use self::measured::Measured;
use self::parameters::{model_value, parameter_name, Asked, Parameter};
use crate::dynamics::algorithms::regressor::{regressor, PARAMETERS_PER_BODY};
use crate::dynamics::algorithms::{rnea, Data};
use crate::dynamics::joint::{Joint, JointType};
use crate::dynamics::loops::Stabilisation;
use crate::dynamics::model::Model;
use crate::elab::mechanism::Mechanism;
use crate::linalg::svd;
use crate::prepare::Prepared;
use crate::simulate::system::{MechanicalSystem, SystemError};
use crate::source::Span;
use crate::studies::motion_file::Derivation;

/// Random states at which the structural base parameters are found: at least this many, and
/// at least three equations per parameter.
const RANDOM_STATES: usize = 20;

/// Condition numbers above this leave the estimates to round-off: the data do not excite the
/// base parameters apart.
const CONDITION_LIMIT: f64 = 1e10;

/// One base parameter's estimate.
#[derive(Clone, Debug, Serialize)]
pub struct Estimate {
    /// The name of its leading parameter (`fore.Izz`), under which it is reported.
    #[serde(skip)]
    pub name: String,
    /// `fore.Izz + 0.16 fore.mass` when parameters are folded into it; `None` alone.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub combination: Option<String>,
    pub value: f64,
    pub std: f64,
    /// The program's value of the same parameter or combination.
    pub model: f64,
}

/// A parameter identifiable only within a base parameter's combination.
#[derive(Clone, Debug, Serialize)]
pub struct Folded {
    #[serde(skip)]
    pub name: String,
    /// The base parameters whose combinations it is folded into (their names).
    pub folded_into: Vec<String>,
}

/// The residual of the fit.
#[derive(Clone, Debug, Serialize)]
pub struct Residual {
    /// √(Σ r² / equations), in the efforts' units.
    pub rms: f64,
    /// |r| / |τ − prediction of the parameters not asked for|: the part of the efforts the
    /// fit leaves unexplained.
    pub relative: f64,
    /// σ = √(Σ r² / (equations − base parameters)), the estimated noise of an effort.
    pub sigma: f64,
    /// Per measured effort, in the order of the model's coordinates, its own σ, by which its
    /// equations are weighted (empty when the fit is exact to round-off, and not weighted).
    pub sigmas: Vec<f64>,
}

/// What `lsdc identify` finds.
#[derive(Clone, Debug, Serialize)]
pub struct Identification {
    #[serde(serialize_with = "by_name")]
    pub parameters: (Vec<Estimate>, Vec<Folded>),
    /// The parameters asked for through a body's or joint's name that have no effect on the
    /// measured efforts (an upper arm turning about the vertical has only its inertia about
    /// it): not estimated.
    pub without_effect: Vec<String>,
    /// The condition number of the base parameters' regressor, its columns scaled to unit norm.
    pub condition: f64,
    pub residual: Residual,
    pub samples: usize,
    pub equations: usize,
    /// Per coordinate (`elbow.q`), where its rates and accelerations come from.
    pub derivatives: Vec<(String, Derivation, Derivation)>,
}

/// The estimates then the folded parameters, one entry per name.
fn by_name<S: Serializer>(
    (estimates, folded): &(Vec<Estimate>, Vec<Folded>),
    serializer: S,
) -> Result<S::Ok, S::Error> {
    let mut map = serializer.serialize_map(Some(estimates.len() + folded.len()))?;
    for e in estimates {
        map.serialize_entry(&e.name, e)?;
    }
    for f in folded {
        map.serialize_entry(&f.name, f)?;
    }
    map.end()
}

/// Why the parameters cannot be identified.
#[derive(Clone, Debug, PartialEq)]
pub enum IdentifyError {
    /// A part of the mechanism the regressor does not cover (loops, a spherical or free joint,
    /// contacts), at `span`.
    Unsupported { what: String, span: Span },
    /// Parameters asked for that have no effect on the measured efforts.
    WithoutEffect(Vec<String>),
    /// Fewer equations than base parameters plus one (for the residual's variance).
    TooFewSamples {
        samples: usize,
        equations: usize,
        base: usize,
    },
    /// The data's regressor is too ill-conditioned to separate the base parameters.
    NotExcited { condition: f64 },
    /// The dynamics cannot be evaluated at a sample (its time, the reason).
    Evaluation { time: f64, why: String },
}

impl std::fmt::Display for IdentifyError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            IdentifyError::Unsupported { what, .. } => write!(f, "{what}"),
            IdentifyError::WithoutEffect(names) => write!(
                f,
                "cannot identify {}: {} no effect on the measured efforts (at any state); leave {} out of `--parameters`, or measure the efforts {} on",
                quoted(names),
                if names.len() == 1 { "it has" } else { "they have" },
                if names.len() == 1 { "it" } else { "them" },
                if names.len() == 1 { "it acts" } else { "they act" },
            ),
            IdentifyError::TooFewSamples { samples, equations, base } => write!(
                f,
                "{samples} samples give {equations} equations for {base} base parameters: at least {} are needed (one more than the parameters, for the residual's variance)",
                base + 1
            ),
            IdentifyError::NotExcited { condition } => write!(
                f,
                "the measured motion does not excite the parameters apart: the regressor's condition number is {condition:.3e} (above {CONDITION_LIMIT:e}); measure a richer motion (more frequencies, larger amplitudes, every joint moving)"
            ),
            IdentifyError::Evaluation { time, why } => {
                write!(f, "cannot evaluate the dynamics at t = {time}: {why}")
            }
        }
    }
}

impl std::error::Error for IdentifyError {}

fn quoted(names: &[String]) -> String {
    let quoted: Vec<String> = names.iter().map(|n| format!("`{n}`")).collect();
    quoted.join(", ")
}

/// Refuses what the regressor does not cover: contacts, free joints, and spherical joints of
/// a tree, whose orientations would be measured. On a mechanism with closed loops the measured
/// coordinates are the actuated ones and the others follow from the loops' closure (`loops`),
/// so its ball joints are solved, not read.
pub fn check_supported(model: &Model, mechanism: &Mechanism) -> Result<(), IdentifyError> {
    if let Some(contact) = mechanism.contacts.first() {
        return Err(IdentifyError::Unsupported {
            what: "the mechanism has contacts: `identify` builds the regressor of a tree's inverse dynamics without contacts".to_string(),
            span: contact.span,
        });
    }
    let read = |j: &&Joint| match j.kind {
        JointType::Chain => false,
        JointType::Spherical { .. } => !model.has_loops(),
        JointType::Free { .. } => true,
    };
    if let Some(joint) = model.joints.iter().find(read) {
        return Err(IdentifyError::Unsupported {
            what: format!("`{}` is a spherical or free joint, whose measured orientation would be a quaternion: `identify` reads joints' own coordinates", joint.chain.name),
            span: mechanism.join(joint.chain.join).span,
        });
    }
    Ok(())
}

/// The columns of the parameters `asked` at one state: the regressor's inertial columns and
/// the friction's (q̇ for the viscous, sign q̇ for the dry), nv rows.
fn asked_columns(
    model: &Model,
    data: &mut Data,
    state: (&[f64], &[f64], &[f64]),
    asked: &[Parameter],
) -> Result<DMatrix<f64>, String> {
    let (q, v, a) = state;
    let inertial = asked
        .iter()
        .any(|p| matches!(p, Parameter::Inertial { .. }));
    let y = match inertial {
        true => regressor(model, data, q, v, a).map_err(|e| SystemError::from(e).to_string())?,
        false => DMatrix::zeros(model.nv, 0),
    };
    let mut columns = DMatrix::zeros(model.nv, asked.len());
    for (k, parameter) in asked.iter().enumerate() {
        match *parameter {
            Parameter::Inertial { body, index } => {
                columns.set_column(k, &y.column(PARAMETERS_PER_BODY * (body - 1) + index))
            }
            Parameter::Dry { velocity } => columns[(velocity, k)] = sign(v[velocity]),
            Parameter::Viscous { velocity } => columns[(velocity, k)] = v[velocity],
        }
    }
    Ok(columns)
}

/// The sign of a rate, 0 at rest (where dry friction holds any effort up to F_c).
fn sign(rate: f64) -> f64 {
    if rate == 0.0 {
        0.0
    } else {
        rate.signum()
    }
}

/// A generator of numbers in [−1, 1) for the random states (xorshift64*, Vigna 2016): fixed
/// seed, so that the base parameters found do not change from run to run.
struct Numbers(u64);

impl Numbers {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        let bits = self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11;
        2.0 * (bits as f64 / (1u64 << 53) as f64) - 1.0
    }
}

/// The structural base parameters of `asked` on the efforts `rows` (velocities): from the
/// regressor at random states (coordinates in [−π, π), rates and accelerations in [−2, 2)).
pub fn structural_base(
    model: &Model,
    asked: &[Parameter],
    rows: &[usize],
) -> Result<BaseParameters, String> {
    let states = RANDOM_STATES.max((3 * asked.len()).div_ceil(rows.len().max(1)));
    let mut numbers = Numbers(0x9e37_79b9_7f4a_7c15);
    let mut data = Data::new(model);
    let mut w = DMatrix::zeros(states * rows.len(), asked.len());
    for s in 0..states {
        let mut draw = |scale: f64| (0..model.nv).map(|_| scale * numbers.next()).collect();
        let (q, v, a): (Vec<f64>, Vec<f64>, Vec<f64>) =
            (draw(std::f64::consts::PI), draw(2.0), draw(2.0));
        let columns = asked_columns(model, &mut data, (&q, &v, &a), asked)?;
        for (r, &velocity) in rows.iter().enumerate() {
            w.set_row(s * rows.len() + r, &columns.row(velocity));
        }
    }
    Ok(base_parameters(&w))
}

/// The equations of every sample: per measured effort, the asked parameters' columns (`w`)
/// and the effort less the prediction of the parameters not asked (`y`); on a mechanism with
/// closed loops, projected on the measured coordinates (`loops`).
fn sample_equations(
    prepared: &Prepared,
    measured: &Measured,
    asked: &[Parameter],
) -> Result<(DMatrix<f64>, DVector<f64>), IdentifyError> {
    let model = &prepared.model;
    let rows = &measured.measured_efforts;
    let samples = measured.times.len();
    let equations = samples * rows.len();
    let program_values: Vec<f64> = asked.iter().map(|&p| model_value(model, p)).collect();
    let mut system =
        MechanicalSystem::new(model, prepared.coordinates.clone(), Stabilisation::None);
    let mut closure = match model.has_loops() {
        true => {
            let (q, _) = model
                .state_from_declared(&prepared.coordinates, &prepared.rates)
                .map_err(|e| IdentifyError::Evaluation {
                    time: 0.0,
                    why: SystemError::from(e).to_string(),
                })?;
            Some(LoopState::new(model, &q, rows))
        }
        false => None,
    };
    let mut loop_data = Data::new(model);
    let mut w = DMatrix::zeros(equations, asked.len());
    let mut y = DVector::zeros(equations);
    for s in 0..samples {
        let time = measured.times[s];
        let failed = |why: String| IdentifyError::Evaluation { time, why };
        let measured_state = (
            measured.positions[s].as_slice(),
            measured.rates[s].as_slice(),
            measured.accelerations[s].as_slice(),
        );
        let closed = match closure.as_mut() {
            Some(closure) => Some(
                closure
                    .close(model, &mut loop_data, measured_state)
                    .map_err(failed)?,
            ),
            None => None,
        };
        let (q, v, a) = match &closed {
            Some(c) => (c.q.as_slice(), c.v.as_slice(), c.a.as_slice()),
            None => measured_state,
        };
        let efforts = system
            .efforts(time, q, v)
            .map_err(|e| failed(e.to_string()))?;
        let data = &mut system.scratch.data;
        let (q, v, a) = (&q[..model.nq], &v[..model.nv], &a[..model.nv]);
        let mut predicted = rnea(model, data, q, v, a, &efforts.external)
            .map_err(|e| failed(SystemError::from(e).to_string()))?;
        predicted -= efforts.tau.rows(0, model.nv);
        for friction in &model.frictions {
            let rate = v[friction.velocity];
            predicted[friction.velocity] += friction.viscous * rate + friction.dry * sign(rate);
        }
        let mut columns = asked_columns(model, data, (q, v, a), asked).map_err(failed)?;
        predicted -= &columns * DVector::from_column_slice(&program_values);
        // On the measured coordinates: Xᵀ of the tree's efforts, or the measured rows.
        if let Some(c) = &closed {
            let tree = c.motions.rows(0, model.nv).transpose();
            columns = &tree * columns;
            predicted = &tree * predicted;
        }
        for (r, &velocity) in rows.iter().enumerate() {
            let row = s * rows.len() + r;
            let own = if closed.is_some() { r } else { velocity };
            w.set_row(row, &columns.row(own));
            y[row] = measured.efforts[s][r] - predicted[own];
        }
    }
    Ok((w, y))
}

/// Identifies the parameters `asked` of `prepared` from `measured` (see the module's
/// documentation).
pub fn identify(
    prepared: &Prepared,
    measured: &Measured,
    asked: &Asked,
) -> Result<Identification, IdentifyError> {
    let model = &prepared.model;
    let rows = &measured.measured_efforts;
    let all = &asked.parameters;
    let samples = measured.times.len();
    let equations = samples * rows.len();
    let (w_all, y) = sample_equations(prepared, measured, all)?;
    // A tree's base parameters are structural, found at random states; the states of a
    // mechanism with closed loops must close them: its base parameters are the data's.
    let base_of = |columns: &[Parameter], w: DMatrix<f64>| match model.has_loops() {
        true => Ok(base_parameters(&w)),
        false => structural_base(model, columns, rows),
    };
    let mut refused = Vec::new();
    for (k, (&p, &explicit)) in all.iter().zip(&asked.explicit).enumerate() {
        let alone = base_of(&[p], w_all.columns(k, 1).into_owned());
        if explicit && alone.is_ok_and(|b| !b.without_effect.is_empty()) {
            refused.push(parameter_name(model, p));
        }
    }
    if !refused.is_empty() {
        return Err(IdentifyError::WithoutEffect(refused));
    }
    let base =
        base_of(all, w_all.clone()).map_err(|why| IdentifyError::Evaluation { time: 0.0, why })?;
    let without_effect: Vec<String> = (base.without_effect.iter())
        .map(|&k| parameter_name(model, all[k]))
        .collect();
    let asked = all.as_slice();
    let count = base.independent.len();
    if equations <= count {
        return Err(IdentifyError::TooFewSamples {
            samples,
            equations,
            base: count,
        });
    }
    let program_values: Vec<f64> = asked.iter().map(|&p| model_value(model, p)).collect();
    let w = w_all.select_columns(&base.independent);
    let (estimates, condition, residual) = weighted_least_squares(&w, &y, rows.len())?;
    let name = |k: usize| parameter_name(model, asked[k]);
    let mut reported = Vec::with_capacity(count);
    for (i, &leading) in base.independent.iter().enumerate() {
        let terms = &base.combinations[i];
        let combination = (!terms.is_empty()).then(|| {
            let folded = terms.iter().map(|&(j, beta)| {
                let sign = if beta < 0.0 { "-" } else { "+" };
                match six_digits(beta.abs()).as_str() {
                    "1" => format!(" {sign} {}", name(j)),
                    coefficient => format!(" {sign} {coefficient} {}", name(j)),
                }
            });
            name(leading) + &folded.collect::<String>()
        });
        let model_value = program_values[leading]
            + terms
                .iter()
                .map(|&(j, b)| b * program_values[j])
                .sum::<f64>();
        reported.push(Estimate {
            name: name(leading),
            combination,
            value: estimates.0[i],
            std: estimates.1[i],
            model: model_value,
        });
    }
    let folded = (base.dependent.iter())
        .map(|&j| {
            let into = (base.independent.iter().zip(&base.combinations))
                .filter(|(_, terms)| terms.iter().any(|&(k, _)| k == j))
                .map(|(&i, _)| name(i))
                .collect();
            Folded {
                name: name(j),
                folded_into: into,
            }
        })
        .collect();
    let derivatives = (0..model.nv)
        .map(|i| {
            (
                model.velocity_name(i),
                measured.rates_from[i],
                measured.accelerations_from[i],
            )
        })
        .collect();
    Ok(Identification {
        parameters: (reported, folded),
        without_effect,
        condition,
        residual,
        samples,
        equations,
        derivatives,
    })
}

/// Least squares weighted by each measured effort's noise (Gautier & Poignet, "Extended Kalman
/// filtering and weighted least squares dynamic identification of robot", Control Engineering
/// Practice 9, 2001): the efforts of different joints differ by orders of magnitude, and so
/// does their noise. A first, unweighted fit gives each effort's σ_j² = |r_j|² / (samples − base
/// parameters) from its rows (row k belongs to effort k mod `efforts`); the rows divided by
/// σ_j are fitted again, whose standard deviations are then those of errors of unequal
/// variances. The residual reported is the unweighted fit's, in the efforts' units.
#[allow(clippy::type_complexity)]
fn weighted_least_squares(
    w: &DMatrix<f64>,
    y: &DVector<f64>,
    efforts: usize,
) -> Result<((Vec<f64>, Vec<f64>), f64, Residual), IdentifyError> {
    let (first, _, residual) = least_squares(w, y)?;
    let (equations, count) = w.shape();
    let samples = equations / efforts;
    let r = y - w * DVector::from_column_slice(&first.0);
    let sigmas: Vec<f64> = (0..efforts)
        .map(|j| {
            let squares: f64 = (j..equations).step_by(efforts).map(|k| r[k] * r[k]).sum();
            (squares / samples.saturating_sub(count).max(1) as f64).sqrt()
        })
        .collect();
    // Noise-free data leave residuals of round-off: weights of their ratios mean nothing.
    if sigmas.iter().any(|&s| s <= 1e-12 * y.amax()) {
        return Ok((first, least_squares(w, y)?.1, residual));
    }
    let weight = |k: usize| 1.0 / sigmas[k % efforts];
    let weighted_w = DMatrix::from_fn(equations, count, |k, j| w[(k, j)] * weight(k));
    let weighted_y = DVector::from_fn(equations, |k, _| y[k] * weight(k));
    let (estimates, condition, _) = least_squares(&weighted_w, &weighted_y)?;
    Ok((estimates, condition, Residual { sigmas, ..residual }))
}

/// A coefficient of a combination for people: six significant digits, written shortest.
fn six_digits(x: f64) -> String {
    let rounded: f64 = format!("{x:.5e}").parse().unwrap_or(x);
    crate::diag::number::shortest(rounded)
}

/// Estimates and standard deviations of x in w x ≈ y, the condition number of w with its
/// columns scaled to unit norm, and the residual.
#[allow(clippy::type_complexity)]
fn least_squares(
    w: &DMatrix<f64>,
    y: &DVector<f64>,
) -> Result<((Vec<f64>, Vec<f64>), f64, Residual), IdentifyError> {
    let (equations, count) = w.shape();
    let norms: Vec<f64> = w.column_iter().map(|c| c.norm()).collect();
    let scaled = DMatrix::from_fn(equations, count, |i, j| w[(i, j)] / norms[j]);
    let not_excited = IdentifyError::NotExcited {
        condition: f64::INFINITY,
    };
    let decomposition = svd(scaled, true, true).ok_or(not_excited.clone())?;
    let singular = &decomposition.singular_values;
    let condition = singular.max() / singular.min();
    // A NaN condition (a zero singular value over zero) is refused too.
    if condition.is_nan() || condition > CONDITION_LIMIT {
        return Err(IdentifyError::NotExcited { condition });
    }
    let (u, v_t) = match (&decomposition.u, &decomposition.v_t) {
        (Some(u), Some(v_t)) => (u, v_t),
        _ => return Err(not_excited),
    };
    // x_scaled = V Σ⁻¹ Uᵀ y; covariance of x_scaled = σ² V Σ⁻² Vᵀ.
    let projected = u.transpose() * y;
    let scaled_x = v_t.transpose() * projected.component_div(singular);
    let x: Vec<f64> = (0..count).map(|j| scaled_x[j] / norms[j]).collect();
    let r = y - w * DVector::from_column_slice(&x);
    let sum_squares = r.norm_squared();
    let variance = sum_squares / (equations - count) as f64;
    let std = (0..count)
        .map(|j| {
            let spread: f64 = (0..count)
                .map(|k| (v_t[(k, j)] / singular[k]).powi(2))
                .sum();
            (variance * spread).sqrt() / norms[j]
        })
        .collect();
    let residual = Residual {
        rms: (sum_squares / equations as f64).sqrt(),
        relative: sum_squares.sqrt() / y.norm().max(f64::MIN_POSITIVE),
        sigma: variance.sqrt(),
        sigmas: Vec::new(),
    };
    Ok(((x, std), condition, residual))
}
