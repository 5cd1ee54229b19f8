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
//! - the accelerations' rows of A and the outputs' C are central differences refined by
//!   Richardson extrapolation (`differences`), each entry with its error estimate: the model
//!   has no analytic derivatives of its efforts and dynamics yet.
//!
//! Compare Drake's `Linearize`, PyDy's `Linearizer` (which also reduces constrained systems to
//! independent coordinates) and MuJoCo's `mjd_transitionFD`.

pub mod chart;
pub mod differences;
pub mod modes;

use std::fmt;

use nalgebra::DMatrix;
use serde::{Serialize, Serializer};

use self::chart::{Chart, ChartError};
use self::modes::{Eigenvalue, Mode};
use super::statics::{holding_efforts, velocity_index, StaticsError};
use crate::diag::Diagnostic;
use crate::dynamics::angles::AngleReference;
use crate::dynamics::compiled::{EffortScratch, EffortState};
use crate::dynamics::joint::JointType;
use crate::dynamics::loops::Stabilisation;
use crate::elab::imposed_motion::refused_by;
use crate::elab::mechanism::Mechanism;
use crate::elab::value::JoinId;
use crate::prepare::Prepared;
use crate::simulate::inputs::Inputs;
use crate::simulate::system::{MechanicalSystem, SystemError};

/// The largest acceleration (rad/s² or m/s²) left at an equilibrium by the efforts that hold
/// it: their least-squares solve leaves round-off.
pub const EQUILIBRIUM: f64 = 1e-8;

/// Where the mechanism is linearised.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OperatingPoint {
    /// The initial state (closed on the loops), at t = 0, with zero inputs.
    Initial,
    /// The state where the prepared run ends (its duration), at that time, with zero inputs.
    EndOfRun,
    /// The initial configuration at rest, with the inputs at the efforts that hold it there
    /// (`statics`); refused when they cannot.
    Equilibrium,
}

/// What to linearise.
#[derive(Clone, Debug)]
pub struct Request {
    pub point: OperatingPoint,
    /// Coordinates `join.coordinate` along which a generalised force is an input.
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
    /// `crank.q` for a coordinate, `crank.q'` for its rate: the coordinates, then their rates.
    pub states: Vec<String>,
    pub inputs: Vec<String>,
    /// The program's outputs, or the states when it declares none.
    pub outputs: Vec<String>,
    /// The operating point: the state, the inputs (the holding efforts at an equilibrium), and
    /// the coordinates' accelerations there (zero at an equilibrium).
    pub state: Vec<f64>,
    pub input: Vec<f64>,
    pub accelerations: Vec<f64>,
    #[serde(rename = "A", serialize_with = "rows")]
    pub a: DMatrix<f64>,
    #[serde(rename = "B", serialize_with = "rows")]
    pub b: DMatrix<f64>,
    #[serde(rename = "C", serialize_with = "rows")]
    pub c: DMatrix<f64>,
    #[serde(rename = "D", serialize_with = "rows")]
    pub d: DMatrix<f64>,
    /// The estimated error of each entry of A and C (zero where exact).
    #[serde(rename = "A_error", serialize_with = "rows")]
    pub a_error: DMatrix<f64>,
    #[serde(rename = "C_error", serialize_with = "rows")]
    pub c_error: DMatrix<f64>,
    /// How the derivatives were obtained, for people.
    pub method: &'static str,
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
pub const METHOD: &str = "rows of the coordinates, B and D exact; accelerations' rows of A and \
C by central differences with Richardson extrapolation (steps h, h/2, h/4, h/8 with h = 1e-2 \
max(1, |x|)), each entry with Ridders' estimate of its truncation error plus a bound on rounding";

/// Linearises the prepared mechanism as `request` asks.
pub fn linearize(prepared: &Prepared, request: &Request) -> Result<Linearization, LinearizeError> {
    let model = &prepared.model;
    refuse_unsupported(prepared)?;
    refuse_imposed_motion(prepared, request.point)?;
    let inputs = indices(prepared, &request.inputs)?;
    let Operating { time, q, v, input } =
        operating_state(prepared, request.point, &request.inputs)?;
    let mut y: Vec<f64> = q.iter().chain(&v).copied().collect();
    let mut system = MechanicalSystem::new(
        model,
        prepared.coordinates.clone(),
        Stabilisation::Projection,
    );
    // The inputs act as a stepped run's do: efforts held along their velocities.
    system.state.inputs = Inputs::along(inputs.clone());
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
    let x: Vec<f64> = (chart.coordinates(&q).into_iter())
        .chain(chart.independent.iter().map(|&i| v[i]))
        .collect();
    let mut evaluator = Evaluator {
        prepared,
        system,
        chart,
        time,
        inputs,
        scratch: EffortScratch::default(),
    };
    let accelerations = evaluator.accelerations(&x, &input)?;
    if request.point == OperatingPoint::Equilibrium {
        if let Some((k, &left)) = (accelerations.iter().enumerate())
            .max_by(|a, b| a.1.abs().total_cmp(&b.1.abs()))
            .filter(|(_, a)| a.abs() > EQUILIBRIUM)
        {
            let coordinate = model.velocity_name(evaluator.chart.independent[k]);
            return Err(LinearizeError::NotAnEquilibrium {
                coordinate,
                acceleration: left,
            });
        }
    }
    let all: Vec<usize> = (0..2 * n).collect();
    let lower = differences::jacobian(&x, &all, n, |x| evaluator.accelerations(x, &input))?;
    let mut a = DMatrix::zeros(2 * n, 2 * n);
    let mut a_error = DMatrix::zeros(2 * n, 2 * n);
    a.view_mut((0, n), (n, n)).fill_with_identity();
    a.view_mut((n, 0), (n, 2 * n)).copy_from(&lower.value);
    a_error.view_mut((n, 0), (n, 2 * n)).copy_from(&lower.error);
    let mut b = DMatrix::zeros(2 * n, evaluator.inputs.len());
    for k in 0..evaluator.inputs.len() {
        // The accelerations are affine in the input: a unit's worth of change (scaled to the
        // operating input, so that adding it loses nothing to rounding) gives the column.
        let size = input[k].abs().max(1.0);
        let mut moved = input.clone();
        moved[k] += size;
        let changed = evaluator.accelerations(&x, &moved)?;
        for r in 0..n {
            b[(n + r, k)] = (changed[r] - accelerations[r]) / size;
        }
    }
    let states = state_names(model, &evaluator.chart.independent);
    let (outputs, c, c_error) = if prepared.outputs.is_empty() {
        let identity = DMatrix::identity(2 * n, 2 * n);
        (states.clone(), identity, DMatrix::zeros(2 * n, 2 * n))
    } else {
        let count = prepared.outputs.names.len();
        let derivative = differences::jacobian(&x, &all, count, |x| evaluator.outputs(x))?;
        (
            prepared.outputs.names.clone(),
            derivative.value,
            derivative.error,
        )
    };
    let d = DMatrix::zeros(outputs.len(), evaluator.inputs.len());
    let eigenvalues = modes::eigenvalues(&a).ok_or(LinearizeError::NoEigenvalues)?;
    let chart = &evaluator.chart;
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
        states,
        inputs: request.inputs.clone(),
        outputs,
        state: x,
        input,
        accelerations,
        a,
        b,
        c,
        d,
        a_error,
        c_error,
        method: METHOD,
        modes: modes::modes(&eigenvalues),
        eigenvalues,
    })
}

/// The coordinates `crank.q`, then their rates `crank.q'`.
fn state_names(model: &crate::dynamics::model::Model, independent: &[usize]) -> Vec<String> {
    let names: Vec<String> = independent
        .iter()
        .map(|&i| model.velocity_name(i))
        .collect();
    names
        .iter()
        .cloned()
        .chain(names.iter().map(|n| format!("{n}'")))
        .collect()
}

/// The state velocities of coordinates named `join.coordinate`, each named once.
fn indices(prepared: &Prepared, names: &[String]) -> Result<Vec<usize>, LinearizeError> {
    for (k, name) in names.iter().enumerate() {
        if names[..k].contains(name) {
            return Err(LinearizeError::Repeated { name: name.clone() });
        }
    }
    let model = &prepared.model;
    names
        .iter()
        .map(|name| {
            let index = velocity_index(prepared, name).map_err(LinearizeError::Name)?;
            match model.drives.iter().any(|d| d.velocity == index) {
                true => Err(LinearizeError::DrivenInput { name: name.clone() }),
                false => Ok(index),
            }
        })
        .collect()
}

/// The operating point's time, positions, velocities and inputs.
struct Operating {
    time: f64,
    q: Vec<f64>,
    v: Vec<f64>,
    input: Vec<f64>,
}

/// The operating point `point` asks for, its driven coordinates on their laws at its time.
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

/// The operating point's state as the initial values, a run or the statics give it.
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
    match point {
        OperatingPoint::Initial => {
            let (q, v) = declared(&prepared.coordinates, &prepared.rates)?;
            let input = vec![0.0; inputs.len()];
            Ok(Operating {
                time: 0.0,
                q,
                v,
                input,
            })
        }
        OperatingPoint::EndOfRun => {
            let mut last = None;
            let simulation = crate::simulate::run::run(prepared, &mut |sample| {
                last = Some((
                    sample.time,
                    sample.coordinates.clone(),
                    sample.rates.clone(),
                ))
            });
            if let Some(failure) = simulation.report.failure {
                return Err(LinearizeError::RunFailed {
                    time: failure.time,
                    message: failure.message,
                });
            }
            let (time, coordinates, rates) = last.ok_or(LinearizeError::RunFailed {
                time: 0.0,
                message: "the run wrote no sample".to_string(),
            })?;
            let (q, v) = declared(&coordinates, &rates)?;
            let input = vec![0.0; inputs.len()];
            Ok(Operating { time, q, v, input })
        }
        OperatingPoint::Equilibrium => {
            let rest = vec![0.0; prepared.rates.len()];
            let (q, v) = declared(&prepared.coordinates, &rest)?;
            let input = match inputs.is_empty() {
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
                input,
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
        (free.iter()).partition(|&&i| chart::position_of(model, i).is_none());
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

/// What a linearisation does not handle.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Unsupported {
    /// A spherical or free joint: its orientation is a quaternion, not coordinates to
    /// differentiate along.
    Quaternion,
    /// A contact: its rolling rows constrain velocities, not positions.
    Contact,
    /// A coupled (mimic) joint: its coordinate is not independent, nor closed by a loop.
    Mimic,
    /// Joint friction: not smooth at rest.
    Friction,
    /// A state of the program (`state(x0)`): its equation is not among the mechanism's yet.
    State,
}

impl Unsupported {
    pub fn what(self) -> &'static str {
        match self {
            Unsupported::Quaternion => "a spherical or free joint",
            Unsupported::Contact => "a contact",
            Unsupported::Mimic => "a coupled (mimic) joint",
            Unsupported::Friction => "a joint with friction",
            Unsupported::State => "a state",
        }
    }

    fn help(self) -> &'static str {
        match self {
            Unsupported::Quaternion => "its orientation is a quaternion, not coordinates to linearise along: write the joint as a chain of revolutes (`link(a, b, c) dof = ...`)",
            Unsupported::Contact => "a contact constrains velocities, not positions: independent coordinates do not describe it",
            Unsupported::Mimic => "write the coupling as a loop of the mechanism, or linearise without it",
            Unsupported::Friction => "friction is not smooth at rest: linearise without it, or with a viscous damper written as an effort",
            Unsupported::State => "the linear model is the mechanism's alone: linearise without the states (a controller's integral, a motor's current)",
        }
    }
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
    if let Some(state) = model.states.first() {
        return Err(refuse(&state.name, Unsupported::State));
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

/// The equations of motion in the chart's coordinates, and the outputs.
struct Evaluator<'p> {
    prepared: &'p Prepared,
    system: MechanicalSystem<'p>,
    chart: Chart,
    time: f64,
    /// The inputs' state velocities.
    inputs: Vec<usize>,
    scratch: EffortScratch,
}

impl Evaluator<'_> {
    fn state(&mut self, x: &[f64]) -> Result<(Vec<f64>, Vec<f64>), LinearizeError> {
        let n = self.chart.independent.len();
        let model = self.system.model;
        let data = &mut self.system.scratch.data;
        Ok(self.chart.state(model, data, &x[..n], &x[n..])?)
    }

    /// The independent coordinates' accelerations at state x under inputs u.
    fn accelerations(&mut self, x: &[f64], u: &[f64]) -> Result<Vec<f64>, LinearizeError> {
        let model = self.system.model;
        let (q, v) = self.state(x)?;
        self.system.state.inputs.held.copy_from_slice(u);
        let y: Vec<f64> = q.iter().chain(&v).copied().collect();
        let mut dydt = vec![0.0; y.len()];
        self.system.derivative(self.time, &y, &mut dydt)?;
        let positions = model.positions();
        Ok(self
            .chart
            .independent
            .iter()
            .map(|&i| dydt[positions + i])
            .collect())
    }

    /// The program's outputs at state x.
    fn outputs(&mut self, x: &[f64]) -> Result<Vec<f64>, LinearizeError> {
        let model = self.system.model;
        let (q, v) = self.state(x)?;
        // Angles against the program's initial values, as every output of the study.
        let reference = AngleReference::at_rest(self.prepared.coordinates.clone());
        let (coordinates, rates) = model
            .declared((self.time, &q, &v), &reference)
            .map_err(|e| LinearizeError::System(SystemError::from(e)))?;
        let data = &mut self.system.scratch.data;
        crate::dynamics::algorithms::forward_kinematics(model, data, &q, &v)
            .map_err(|e| LinearizeError::System(SystemError::from(e)))?;
        let state = EffortState {
            world: &data.world,
            velocity: &data.velocity,
            coordinates: &coordinates,
            rates: &rates,
            states: &[],
            time: self.time,
            model: &[],
        };
        Ok(self.prepared.outputs.values(&state, &mut self.scratch))
    }
}

/// Where a linearisation refuses motions imposed in time.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImposedContext {
    Loops,
    Equilibrium,
    /// A frame's position imposed (`drive position(F) = law`), whose rows the chart does not
    /// keep.
    Path,
}

impl ImposedContext {
    /// The command as the user ran it, for the refusal.
    fn command(self) -> &'static str {
        match self {
            ImposedContext::Loops => "`lsdc linearize` of a mechanism with closed loops",
            ImposedContext::Equilibrium => "`lsdc linearize --equilibrium`",
            ImposedContext::Path => {
                "`lsdc linearize` of a mechanism whose frame's position is imposed"
            }
        }
    }

    fn help(self) -> &'static str {
        match self {
            ImposedContext::Loops => "linearise the mechanism without the motion imposed in time (remove the drive, or the time from the dof chain); a tree is linearised with its drives on their laws",
            ImposedContext::Equilibrium => "a coordinate imposed in time is not at rest: linearise about the initial state, or a run's state with --at-time T, where the drives are on their laws",
            ImposedContext::Path => "linearise the mechanism without its position drive, or drive its coordinates instead (`drive crank.q = law`)",
        }
    }
}

/// Why a mechanism cannot be linearised as asked.
#[derive(Debug)]
pub enum LinearizeError {
    /// An input or coordinate names no coordinate that can carry one (see `StaticsError`).
    Name(StaticsError),
    /// A coordinate named twice among the inputs or the coordinates.
    Repeated {
        name: String,
    },
    /// `--coordinate` for a tree, whose coordinates are all independent.
    TreeCoordinates,
    /// As many independent coordinates as the motions with mass are needed; the run's choice.
    CoordinateCount {
        given: usize,
        with_mass: usize,
        run_choice: Vec<String>,
    },
    /// The run's free coordinates include spherical or free joints' velocities, which are no
    /// coordinate's rates, beyond the massless motions: coordinates must be named.
    FreeQuaternion {
        with_mass: usize,
        run_choice: Vec<String>,
    },
    /// The coordinates named leave some of the others undetermined by the loops.
    NotIndependent {
        given: Vec<String>,
        run_choice: Vec<String>,
    },
    /// An input along a coordinate a drive imposes: no force moves it.
    DrivenInput {
        name: String,
    },
    /// A coordinate imposed in time (`name`) where it is not handled.
    ImposedMotion {
        name: String,
        context: ImposedContext,
    },
    /// A join or contact (`name`) of a kind a linearisation does not handle.
    Unsupported {
        name: String,
        kind: Unsupported,
    },
    /// At an equilibrium the inputs do not hold the mechanism: the largest acceleration left.
    NotAnEquilibrium {
        coordinate: String,
        acceleration: f64,
    },
    /// The run to the operating point failed.
    RunFailed {
        time: f64,
        message: String,
    },
    /// The loops cannot be closed at a state near the operating point.
    Chart(ChartError),
    System(SystemError),
    /// The eigenvalues of A could not be computed (a value not finite).
    NoEigenvalues,
}

impl From<SystemError> for LinearizeError {
    fn from(error: SystemError) -> Self {
        LinearizeError::System(error)
    }
}

impl From<ChartError> for LinearizeError {
    fn from(error: ChartError) -> Self {
        LinearizeError::Chart(error)
    }
}

impl LinearizeError {
    /// The error as a diagnostic located in the program, where it is about a part of it (E0850).
    pub fn diagnostic(&self, mechanism: &Mechanism) -> Option<Diagnostic> {
        if let LinearizeError::ImposedMotion { context, .. } = self {
            return refused_by(mechanism, context.command(), context.help());
        }
        let LinearizeError::Unsupported { name, kind } = self else {
            return None;
        };
        let mut joins = (0..mechanism.joins.len() as u32).map(JoinId);
        let span = match joins.find(|&id| mechanism.join_name(id) == *name) {
            Some(id) => mechanism.join(id).span,
            None => {
                let index =
                    (0..mechanism.contacts.len()).find(|&k| mechanism.contact_name(k) == *name)?;
                mechanism.contacts[index].span
            }
        };
        Some(
            Diagnostic::error(
                "E0850",
                format!("`{name}` cannot be linearised: {}", kind.what()),
            )
            .primary(span, kind.what())
            .help(kind.help()),
        )
    }
}

impl fmt::Display for LinearizeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            LinearizeError::Name(error) => write!(f, "{error}"),
            LinearizeError::Repeated { name } => write!(f, "`{name}` is named twice"),
            LinearizeError::TreeCoordinates => write!(
                f,
                "--coordinate chooses the independent coordinates of closed loops; every coordinate of a tree is independent"
            ),
            LinearizeError::CoordinateCount {
                given,
                with_mass,
                run_choice,
            } => write!(
                f,
                "{given} coordinate(s) given with --coordinate, but the loops leave {with_mass} independent motion(s) with mass (the run's free coordinates: {})",
                quoted(run_choice)
            ),
            LinearizeError::FreeQuaternion { with_mass, run_choice } => write!(
                f,
                "the run's free coordinates ({}) include velocities of spherical joints, which are no coordinates' rates: name {with_mass} independent coordinates of revolute or prismatic joints with --coordinate (the actuated ones of a parallel robot)",
                quoted(run_choice)
            ),
            LinearizeError::NotIndependent { given, run_choice } => write!(
                f,
                "the loops do not determine the other coordinates from {}: choose coordinates that move independently, as the run's {}",
                quoted(given),
                quoted(run_choice)
            ),
            LinearizeError::Unsupported { name, kind } => {
                write!(f, "`{name}` cannot be linearised: {}", kind.what())
            }
            LinearizeError::DrivenInput { name } => write!(
                f,
                "`{name}` is imposed by a law of time: a force along it moves nothing (it becomes the drive's effort); name a free coordinate with --input"
            ),
            LinearizeError::ImposedMotion { name, context } => write!(
                f,
                "`{name}` is imposed by a law of time, which {} does not handle: {}",
                context.command(),
                context.help()
            ),
            LinearizeError::NotAnEquilibrium { coordinate, acceleration } => write!(
                f,
                "the initial configuration is not an equilibrium: `{coordinate}` accelerates at {acceleration:.6e} with the inputs holding it as well as they can; name inputs (--input) that can hold it"
            ),
            LinearizeError::RunFailed { time, message } => {
                write!(f, "the run to the operating point failed at t = {time}: {message}")
            }
            LinearizeError::Chart(ChartError::NotClosed { residual }) => write!(
                f,
                "the loops cannot be closed near the operating point (a row left at {residual:.3e}): it may be a singular configuration"
            ),
            LinearizeError::Chart(ChartError::Evaluation(error)) => {
                write!(f, "{}", SystemError::from(error.clone()))
            }
            LinearizeError::System(error) => write!(f, "{error}"),
            LinearizeError::NoEigenvalues => {
                write!(f, "the eigenvalues of A cannot be computed: it has a value that is not finite")
            }
        }
    }
}

fn quoted(names: &[String]) -> String {
    let names: Vec<String> = names.iter().map(|n| format!("`{n}`")).collect();
    names.join(", ")
}

impl std::error::Error for LinearizeError {}
