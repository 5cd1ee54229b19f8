//! `lsdc linearize`: the linear model ẋ = A x + B u, y = C x + D u of a mechanism about an
//! operating point (the initial state, the state where a run ends, or an equilibrium held by
//! the inputs, as `statics` finds it), with x the independent coordinates and their rates (every
//! coordinate of a tree; as many as the mobility with loops, see `chart`), u generalised forces
//! along named coordinates, y the program's outputs.
//!
//! What is exact and what is differenced:
//! - the coordinates' rows of A are [0 I] (ż is part of the state);
//! - B: the accelerations are affine in the generalised forces (ABA, or the constrained solve
//!   with loops, is linear in τ), so a unit input's change of the accelerations is B's column
//!   to rounding;
//! - D = 0: outputs read the state and the time, never the efforts;
//! - with loops, where nothing but gravity and the inputs acts, the accelerations' rows of A
//!   and B are exact: the constrained dynamics' derivatives in the chart's coordinates
//!   (`exact`); where those derivatives refuse (motions without mass, rows closing at second
//!   order, efforts that depend on the state), the linearisation says why and differences;
//! - elsewhere the accelerations' rows of A, and the outputs' C always, are central
//!   differences refined by Richardson extrapolation (`differences`), each entry with its
//!   error estimate.
//!
//! Compare Drake's `Linearize`, PyDy's `Linearizer` (which also reduces constrained systems to
//! independent coordinates) and MuJoCo's `mjd_transitionFD`.

pub mod chart;
pub mod differences;
mod error;
mod evaluator;
mod exact;
pub mod inputs;
pub mod modes;

use nalgebra::DMatrix;
use serde::{Serialize, Serializer};

use self::chart::Chart;
pub use self::error::{ImposedContext, LinearizeError, Unsupported};
use self::evaluator::Evaluator;
use self::inputs::{coordinate_index, refuse_repeated, Input, Inputs};
use self::modes::{Eigenvalue, Mode};
use super::statics::holding_efforts;
use crate::dynamics::compiled::EffortScratch;
use crate::dynamics::joint::JointType;
use crate::dynamics::loops::Stabilisation;
use crate::prepare::Prepared;
use crate::simulate::inputs::Inputs as SystemInputs;
use crate::simulate::system::{MechanicalSystem, SystemError};

/// The largest acceleration (rad/s² or m/s²) left at an equilibrium by the efforts that hold
/// it: their least-squares solve leaves round-off.
pub const EQUILIBRIUM: f64 = 1e-8;

/// Where the mechanism is linearised.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OperatingPoint {
    /// The initial state (closed on the loops), at t = 0, with the inputs at their start
    /// values (zero for those only named).
    Initial,
    /// The state where the prepared run ends (its duration), at that time, with the inputs as
    /// the run held them (their start values, zero for those only named).
    EndOfRun,
    /// The initial configuration at rest, with the inputs at the efforts that hold it there
    /// (`statics`); refused when they cannot.
    Equilibrium,
}

/// What to linearise.
#[derive(Clone, Debug)]
pub struct Request {
    pub point: OperatingPoint,
    /// Inputs besides the program's declared ones (which come first): coordinates
    /// `join.coordinate` along which a generalised force is an input, constant states.
    pub inputs: Vec<String>,
    /// With loops, the independent coordinates (as many as the mobility); empty for the run's
    /// free coordinates.
    pub coordinates: Vec<String>,
}

/// A linear model of the mechanism about an operating point.
#[derive(Clone, Debug, Serialize)]
pub struct Linearization {
    /// `initial`, `end of run` or `equilibrium`.
    pub point: &'static str,
    pub time: f64,
    /// The independent coordinates, those that follow from them through the loops, and how
    /// the independent ones were chosen.
    pub coordinates: Vec<String>,
    pub dependent: Vec<String>,
    /// Motions held at the operating point: allowed by the loops, without mass, no
    /// coordinate's rate (rods spinning between ball joints).
    pub held: Vec<String>,
    /// Coordinates imposed by laws of time (drives, `time` in a dof chain): not states, but
    /// on their laws at the operating point's time, which makes A, B and C those of that time.
    pub driven: Vec<String>,
    pub choice: &'static str,
    /// The program's states that are states of the linear model (those not named as inputs).
    pub program_states: Vec<String>,
    /// `crank.q` for a coordinate, `crank.q'` for its rate: the coordinates, then their rates,
    /// then the program's states.
    pub states: Vec<String>,
    pub inputs: Vec<String>,
    /// The program's outputs, or the states when it declares none.
    pub outputs: Vec<String>,
    /// The operating point: the state, the inputs (the holding efforts at an equilibrium), and
    /// the coordinates' accelerations and the program's states' rates there (zero at an
    /// equilibrium).
    pub state: Vec<f64>,
    pub input: Vec<f64>,
    pub accelerations: Vec<f64>,
    pub state_rates: Vec<f64>,
    #[serde(rename = "A", serialize_with = "rows")]
    pub a: DMatrix<f64>,
    #[serde(rename = "B", serialize_with = "rows")]
    pub b: DMatrix<f64>,
    #[serde(rename = "C", serialize_with = "rows")]
    pub c: DMatrix<f64>,
    #[serde(rename = "D", serialize_with = "rows")]
    pub d: DMatrix<f64>,
    /// The estimated error of each entry of A, B and C (zero where exact).
    #[serde(rename = "A_error", serialize_with = "rows")]
    pub a_error: DMatrix<f64>,
    #[serde(rename = "B_error", serialize_with = "rows")]
    pub b_error: DMatrix<f64>,
    #[serde(rename = "C_error", serialize_with = "rows")]
    pub c_error: DMatrix<f64>,
    /// How the derivatives were obtained, for people.
    pub method: &'static str,
    /// With loops, why the accelerations' rows are differenced rather than exact (the
    /// constrained dynamics' derivatives refused them); `None` where they are exact, in a
    /// tree, or where differences were asked for.
    pub differenced_because: Option<String>,
    pub eigenvalues: Vec<Eigenvalue>,
    pub modes: Vec<Mode>,
}

/// A matrix as an array of rows.
fn rows<S: Serializer>(matrix: &DMatrix<f64>, serializer: S) -> Result<S::Ok, S::Error> {
    let rows: Vec<Vec<f64>> = matrix
        .row_iter()
        .map(|row| row.iter().copied().collect())
        .collect();
    rows.serialize(serializer)
}

/// How the entries that are not exact are computed.
pub const METHOD: &str = "rows of the coordinates, B's columns of generalised forces and D's \
exact; accelerations' and states' rows of A, B's and D's columns of states held as inputs, and \
C by central differences with Richardson extrapolation (steps h, h/2, h/4, h/8 with h = 1e-2 \
max(1, |x|)), each entry with Ridders' estimate of its truncation error plus a bound on rounding";

/// How the entries are computed where the constrained dynamics' derivatives give A's
/// accelerations' rows and B exactly.
pub const LOOP_METHOD: &str = "rows of the coordinates, D's, and A's and B's accelerations' rows \
exact (the constrained dynamics' derivatives in the independent coordinates: the saddle point \
differentiated, the loops' rows in dual numbers); C by central differences with Richardson \
extrapolation (steps h, h/2, h/4, h/8 with h = 1e-2 max(1, |x|)), each entry with Ridders' \
estimate of its truncation error plus a bound on rounding";

/// How A's accelerations' rows are found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Derivatives {
    /// Exact where the constrained dynamics' derivatives cover the mechanism (loops, nothing
    /// but gravity and the inputs acting), differenced elsewhere.
    ExactWhereCovered,
    /// Central differences everywhere (to compare with the exact ones).
    Differenced,
}

/// Linearises the prepared mechanism as `request` asks, exact where it can be.
pub fn linearize(prepared: &Prepared, request: &Request) -> Result<Linearization, LinearizeError> {
    linearize_by(prepared, request, Derivatives::ExactWhereCovered)
}

/// Linearises the prepared mechanism as `request` asks, its derivatives found as `derivatives`
/// says.
pub fn linearize_by(
    prepared: &Prepared,
    request: &Request,
    derivatives: Derivatives,
) -> Result<Linearization, LinearizeError> {
    let model = &prepared.model;
    refuse_unsupported(prepared)?;
    refuse_imposed_motion(prepared, request.point)?;
    let input_names = with_declared(model, &request.inputs);
    let named = Inputs::named(prepared, &input_names)?;
    let Operating {
        time,
        q,
        v,
        efforts,
        states,
    } = operating_state(prepared, request.point, &named.effort_names)?;
    let mut y: Vec<f64> = q.iter().chain(&v).copied().collect();
    let mut system = MechanicalSystem::new(
        model,
        prepared.coordinates.clone(),
        Stabilisation::Projection,
    );
    // The inputs act as a stepped run's do: efforts held along their velocities.
    system.state.inputs = SystemInputs::along(named.efforts.clone());
    system.set_states(&states);
    let (chart, choice) = if model.has_loops() {
        system.start_loops(&mut y)?;
        let free = system.scratch.loops.structure.free.clone();
        let (q, _) = model.split_state(&y);
        choose_coordinates(prepared, &mut system, free, &request.coordinates, &q)?
    } else {
        if !request.coordinates.is_empty() {
            return Err(LinearizeError::TreeCoordinates);
        }
        let choice = match model.drives.is_empty() {
            true => "every coordinate of the tree",
            false => "every coordinate of the tree but those imposed in time",
        };
        (Chart::tree(model, &q, &v), choice)
    };
    let (q, v) = model.split_state(&y);
    let n = chart.independent.len();
    // x = (z, ż, s): the independent coordinates, their rates, the program's kept states;
    // z_all = x followed by the held states' values, the inputs differenced with x.
    let x: Vec<f64> = (chart.coordinates(&q).into_iter())
        .chain(chart.independent.iter().map(|&i| v[i]))
        .chain(named.kept_states.iter().map(|&k| states[k]))
        .collect();
    let held: Vec<f64> = named.held_states.iter().map(|&k| states[k]).collect();
    let size = x.len();
    let with_held: Vec<f64> = x.iter().chain(&held).copied().collect();
    let mut evaluator = Evaluator {
        prepared,
        system,
        chart,
        time,
        inputs: named,
        scratch: EffortScratch::default(),
    };
    let rates = evaluator.rates(&x, &efforts, &held)?;
    if request.point == OperatingPoint::Equilibrium {
        if let Some((k, &left)) = (rates.iter().enumerate())
            .max_by(|a, b| a.1.abs().total_cmp(&b.1.abs()))
            .filter(|(_, a)| a.abs() > EQUILIBRIUM)
        {
            let coordinate = match k < n {
                true => model.velocity_name(evaluator.chart.independent[k]),
                false => model.states[evaluator.inputs.kept_states[k - n]]
                    .name
                    .clone(),
            };
            return Err(LinearizeError::NotAnEquilibrium {
                coordinate,
                acceleration: left,
            });
        }
    }
    let every: Vec<usize> = (0..with_held.len()).collect();
    let split = |z: &[f64]| (z[..size].to_vec(), z[size..].to_vec());
    let exact = match (model.has_loops(), derivatives) {
        (true, Derivatives::ExactWhereCovered) => {
            Some(exact::loop_rows(&mut evaluator, &x, &efforts, &rates))
        }
        _ => None,
    };
    let (exact, differenced_because) = match exact {
        Some(Ok(rows)) => (Some(rows), None),
        Some(Err(refusal)) => (None, Some(refusal)),
        None => (None, None),
    };
    let mut a = DMatrix::zeros(size, size);
    let mut a_error = DMatrix::zeros(size, size);
    a.view_mut((0, n), (n, n)).fill_with_identity();
    let below = size - n;
    // The differenced rows (none where exact: no program state, so none held, when exact).
    let lower = match &exact {
        Some(rows) => {
            a.view_mut((n, 0), (n, size)).copy_from(&rows.by_state);
            differences::Estimated {
                value: DMatrix::zeros(below, with_held.len()),
                error: DMatrix::zeros(below, with_held.len()),
            }
        }
        None => {
            let lower = differences::jacobian(&with_held, &every, rates.len(), |z| {
                let (x, held) = split(z);
                evaluator.rates(&x, &efforts, &held)
            })?;
            a.view_mut((n, 0), (below, size))
                .copy_from(&lower.value.columns(0, size));
            a_error
                .view_mut((n, 0), (below, size))
                .copy_from(&lower.error.columns(0, size));
            lower
        }
    };
    let inputs = &evaluator.inputs.inputs.clone();
    let mut b = DMatrix::zeros(size, inputs.len());
    let mut b_error = DMatrix::zeros(size, inputs.len());
    let (mut effort_column, mut held_column) = (0, 0);
    for (k, input) in inputs.iter().enumerate() {
        match input {
            Input::Effort(_) if exact.is_some() => {
                let rows = &exact.as_ref().expect("matched").by_effort;
                b.view_mut((n, k), (n, 1))
                    .copy_from(&rows.column(effort_column));
                effort_column += 1;
            }
            Input::Effort(_) => {
                // The accelerations are affine in a generalised force, the states' rates
                // independent of it: a unit's worth of change (scaled to the operating input,
                // so that adding it loses nothing to rounding) gives the column.
                let j = effort_column;
                effort_column += 1;
                let step = efforts[j].abs().max(1.0);
                let mut moved = efforts.clone();
                moved[j] += step;
                let changed = evaluator.rates(&x, &moved, &held)?;
                for r in 0..below {
                    b[(n + r, k)] = (changed[r] - rates[r]) / step;
                }
            }
            Input::State(_) => {
                let column = size + held_column;
                held_column += 1;
                for r in 0..below {
                    b[(n + r, k)] = lower.value[(r, column)];
                    b_error[(n + r, k)] = lower.error[(r, column)];
                }
            }
        }
    }
    let states_named = state_names(model, &evaluator.chart.independent, &evaluator.inputs);
    let (outputs, c, c_error, d) = if prepared.outputs.is_empty() {
        let identity = DMatrix::identity(size, size);
        let d = DMatrix::zeros(size, inputs.len());
        (
            states_named.clone(),
            identity,
            DMatrix::zeros(size, size),
            d,
        )
    } else {
        let count = prepared.outputs.names.len();
        let derivative = differences::jacobian(&with_held, &every, count, |z| {
            let (x, held) = split(z);
            evaluator.outputs(&x, &efforts, &held)
        })?;
        // D: the outputs read no generalised force (the model they read counts none of the
        // inputs); the held states' columns are differenced with C's.
        let mut d = DMatrix::zeros(count, inputs.len());
        let held_columns =
            (inputs.iter().enumerate()).filter(|(_, i)| matches!(i, Input::State(_)));
        for ((k, _), column) in held_columns.zip(size..) {
            d.set_column(k, &derivative.value.column(column));
        }
        (
            prepared.outputs.names.clone(),
            derivative.value.columns(0, size).into_owned(),
            derivative.error.columns(0, size).into_owned(),
            d,
        )
    };
    let eigenvalues = modes::eigenvalues(&a).ok_or(LinearizeError::NoEigenvalues)?;
    let chart = &evaluator.chart;
    let input: Vec<f64> = {
        let (mut effort, mut state) = (efforts.iter(), held.iter());
        (inputs.iter())
            .map(|i| match i {
                Input::Effort(_) => *effort.next().expect("one per effort input"),
                Input::State(_) => *state.next().expect("one per state input"),
            })
            .collect()
    };
    Ok(Linearization {
        point: match request.point {
            OperatingPoint::Initial => "initial",
            OperatingPoint::EndOfRun => "end of run",
            OperatingPoint::Equilibrium => "equilibrium",
        },
        time,
        coordinates: chart
            .independent
            .iter()
            .map(|&i| model.velocity_name(i))
            .collect(),
        dependent: chart
            .dependent
            .iter()
            .map(|&i| model.velocity_name(i))
            .collect(),
        held: chart.held.iter().map(|&i| model.velocity_name(i)).collect(),
        driven: (chart.driven.iter())
            .map(|&(i, _)| model.velocity_name(i))
            .collect(),
        choice,
        program_states: (evaluator.inputs.kept_states.iter())
            .map(|&k| model.states[k].name.clone())
            .collect(),
        states: states_named,
        inputs: input_names,
        outputs,
        state: x,
        input,
        accelerations: rates[..n].to_vec(),
        state_rates: rates[n..].to_vec(),
        a,
        b,
        c,
        d,
        a_error,
        b_error,
        c_error,
        method: match exact {
            Some(_) => LOOP_METHOD,
            None => METHOD,
        },
        differenced_because,
        modes: modes::modes(&eigenvalues),
        eigenvalues,
    })
}

/// The coordinates `crank.q`, then their rates `crank.q'`, then the program's kept states.
fn state_names(
    model: &crate::dynamics::model::Model,
    independent: &[usize],
    inputs: &Inputs,
) -> Vec<String> {
    let names: Vec<String> = independent
        .iter()
        .map(|&i| model.velocity_name(i))
        .collect();
    names
        .iter()
        .cloned()
        .chain(names.iter().map(|n| format!("{n}'")))
        .chain(
            inputs
                .kept_states
                .iter()
                .map(|&k| model.states[k].name.clone()),
        )
        .collect()
}

/// The state velocities of coordinates named `join.coordinate`, each named once.
fn indices(prepared: &Prepared, names: &[String]) -> Result<Vec<usize>, LinearizeError> {
    refuse_repeated(names)?;
    (names.iter())
        .map(|name| coordinate_index(prepared, name))
        .collect()
}

/// The operating point's time, positions, velocities, generalised forces along the inputs'
/// coordinates and the program's states.
struct Operating {
    time: f64,
    q: Vec<f64>,
    v: Vec<f64>,
    efforts: Vec<f64>,
    states: Vec<f64>,
}

/// The operating point `point` asks for, its driven coordinates on their laws at its time.
/// The program's declared inputs (`input swing.q = 0;`, then `input voltage = 0;`) first,
/// then those `named` that are not declared (a name repeated there stays repeated, for
/// `Inputs::named`'s error).
fn with_declared(model: &crate::dynamics::model::Model, named: &[String]) -> Vec<String> {
    let efforts = model.effort_inputs.iter().map(|(name, _)| name);
    let values = (model.states.iter().filter(|state| state.input)).map(|state| &state.name);
    let declared: Vec<String> = efforts.chain(values).cloned().collect();
    let named = named
        .iter()
        .filter(|name| !declared.contains(name))
        .cloned();
    declared.iter().cloned().chain(named).collect()
}

fn operating_state(
    prepared: &Prepared,
    point: OperatingPoint,
    inputs: &[String],
) -> Result<Operating, LinearizeError> {
    let mut operating = free_operating_state(prepared, point, inputs)?;
    for driven in &prepared.model.drives {
        let law = driven.at(operating.time);
        operating.q[driven.position] = law.position;
        operating.v[driven.velocity] = law.rate;
    }
    Ok(operating)
}

/// The operating point's state as the initial values, a run or the statics give it; the
/// program's states at their starting values but where a run ends.
fn free_operating_state(
    prepared: &Prepared,
    point: OperatingPoint,
    inputs: &[String],
) -> Result<Operating, LinearizeError> {
    let model = &prepared.model;
    let declared = |coordinates: &[f64], rates: &[f64]| {
        model
            .state_from_declared(coordinates, rates)
            .map_err(|e| LinearizeError::System(SystemError::from(e)))
    };
    let starting: Vec<f64> = model.states.iter().map(|s| s.initial).collect();
    // The efforts a run holds: a declared input's start value, 0 for one only named.
    let held: Vec<f64> = (inputs.iter())
        .map(|name| {
            let declared = model.effort_inputs.iter().find(|(n, _)| n == name);
            declared.map_or(0.0, |(_, start)| *start)
        })
        .collect();
    match point {
        OperatingPoint::Initial => {
            let (q, v) = declared(&prepared.coordinates, &prepared.rates)?;
            Ok(Operating {
                time: 0.0,
                q,
                v,
                efforts: held.clone(),
                states: starting,
            })
        }
        OperatingPoint::EndOfRun => {
            let mut last = None;
            // A sample's outputs start with the drives' efforts, then the states' values.
            let states = model.drives.len()..model.drives.len() + model.states.len();
            let simulation = crate::simulate::run::run(prepared, &mut |sample| {
                last = Some((
                    sample.time,
                    sample.coordinates.clone(),
                    sample.rates.clone(),
                    sample.outputs[states.clone()].to_vec(),
                ))
            });
            if let Some(failure) = simulation.report.failure {
                return Err(LinearizeError::RunFailed {
                    time: failure.time,
                    message: failure.message,
                });
            }
            let (time, coordinates, rates, states) = last.ok_or(LinearizeError::RunFailed {
                time: 0.0,
                message: "the run wrote no sample".to_string(),
            })?;
            let (q, v) = declared(&coordinates, &rates)?;
            Ok(Operating {
                time,
                q,
                v,
                efforts: held.clone(),
                states,
            })
        }
        OperatingPoint::Equilibrium => {
            let rest = vec![0.0; prepared.rates.len()];
            let (q, v) = declared(&prepared.coordinates, &rest)?;
            let efforts = match inputs.is_empty() {
                true => Vec::new(),
                false => holding_efforts(prepared, inputs)
                    .map_err(LinearizeError::Name)?
                    .efforts
                    .iter()
                    .map(|e| e.effort)
                    .collect(),
            };
            Ok(Operating {
                time: 0.0,
                q,
                v,
                efforts,
                states: starting,
            })
        }
    }
}

/// The chart of a mechanism with loops: the run's free coordinates, or those named, as many as
/// the motions with mass. The massless motions (a rod spinning between two ball joints) are
/// held where they are by as many of the free spherical joints' velocities, the first set
/// (in the run's order) that the named coordinates complete into a chart: holding them only
/// fixes how far the massless parts have spun, which no force depends on.
fn choose_coordinates(
    prepared: &Prepared,
    system: &mut MechanicalSystem<'_>,
    free: Vec<usize>,
    named: &[String],
    q: &[f64],
) -> Result<(Chart, &'static str), LinearizeError> {
    let model = &prepared.model;
    let massless = system.scratch.loops.structure.massless;
    let (spins, coordinates): (Vec<usize>, Vec<usize>) =
        (free.iter()).partition(|&&i| model.position_of(i).is_none());
    let run_choice = || free.iter().map(|&i| model.velocity_name(i)).collect();
    let with_mass = free.len().saturating_sub(massless);
    let (independent, choice) = if named.is_empty() {
        if coordinates.len() != with_mass || spins.len() > massless {
            return Err(LinearizeError::FreeQuaternion {
                with_mass,
                run_choice: run_choice(),
            });
        }
        (coordinates, "the free coordinates the run chooses")
    } else {
        (
            indices(prepared, named)?,
            "the coordinates named with --coordinate",
        )
    };
    if independent.len() != with_mass {
        return Err(LinearizeError::CoordinateCount {
            given: independent.len(),
            with_mass,
            run_choice: run_choice(),
        });
    }
    let data = &mut system.scratch.data;
    for held in subsets(&spins, massless) {
        let chart = Chart::with_loops(model, independent.clone(), held, q);
        let parametrises = (chart.parametrises(model, data))
            .map_err(|e| LinearizeError::System(SystemError::from(e)))?;
        if parametrises {
            return Ok((chart, choice));
        }
    }
    Err(LinearizeError::NotIndependent {
        given: named.to_vec(),
        run_choice: run_choice(),
    })
}

/// The subsets of `count` of `items`, in order (those that leave out the last items first).
fn subsets(items: &[usize], count: usize) -> Vec<Vec<usize>> {
    if count == 0 {
        return vec![Vec::new()];
    }
    if items.len() < count {
        return Vec::new();
    }
    let mut found: Vec<Vec<usize>> = subsets(&items[1..], count - 1)
        .into_iter()
        .map(|rest| std::iter::once(items[0]).chain(rest).collect())
        .collect();
    found.extend(subsets(&items[1..], count));
    found
}

/// Refuses, before anything is computed, a mechanism with a part a linearisation does not
/// handle (`Unsupported`), naming the first such join or contact.
fn refuse_unsupported(prepared: &Prepared) -> Result<(), LinearizeError> {
    let model = &prepared.model;
    let refuse = |name: &str, kind| LinearizeError::Unsupported {
        name: name.to_string(),
        kind,
    };
    // With loops, such a joint may follow from the independent coordinates
    // (`choose_coordinates` refuses it among them).
    let quaternion = model.joints.iter().find(|j| j.kind != JointType::Chain);
    if let (false, Some(joint)) = (model.has_loops(), quaternion) {
        return Err(refuse(&joint.chain.name, Unsupported::Quaternion));
    }
    if let Some(contact) = model.contacts.first() {
        return Err(refuse(&contact.name, Unsupported::Contact));
    }
    if let Some(mimic) = model.mimics.first() {
        let join = &model.joints[mimic.joint].chain.name;
        return Err(refuse(join, Unsupported::Mimic));
    }
    if let Some(friction) = model.frictions.first() {
        let join = &model.joints[friction.joint].chain.name;
        return Err(refuse(join, Unsupported::Friction));
    }
    Ok(())
}

/// Refuses motions imposed in time where the linear model would not be the driven
/// mechanism's: with loops (the chart's closure would move the driven coordinates off their
/// laws) and at an equilibrium (a driven coordinate is not at rest, nor held by the inputs).
fn refuse_imposed_motion(prepared: &Prepared, point: OperatingPoint) -> Result<(), LinearizeError> {
    let model = &prepared.model;
    if let Some(path) = model.position_drives.first() {
        return Err(LinearizeError::ImposedMotion {
            name: path.frame.name.clone(),
            context: ImposedContext::Path,
        });
    }
    let Some(driven) = model.drives.first() else {
        return Ok(());
    };
    let context = match (model.has_loops(), point) {
        (true, _) => ImposedContext::Loops,
        (false, OperatingPoint::Equilibrium) => ImposedContext::Equilibrium,
        (false, _) => return Ok(()),
    };
    Err(LinearizeError::ImposedMotion {
        name: driven.coordinate.clone(),
        context,
    })
}
