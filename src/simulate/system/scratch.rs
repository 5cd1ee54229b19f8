//! The scratch of one evaluator of the equations of motion (Pinocchio's `Data` beside its
//! `Model`): the kinematics, efforts, factorisations and row stacks an evaluation writes, and how
//! this evaluator keeps the loops closed. A run has one for its integrator's evaluations and one
//! for its sampler's (`MechanicalSystem::sampling`); nothing here is read across evaluations but
//! for caches of the last state evaluated.

use crate::dynamics::planar::PlanarData;
use nalgebra::{DMatrix, DVector};

use crate::dynamics::algorithms::rnea_derivatives::RneaDerivatives;
use crate::dynamics::algorithms::Data;
use crate::dynamics::compiled::EffortScratch;
use crate::dynamics::contacts::ContactRows;
use crate::dynamics::coupled_aba::CouplingScratch;
use crate::dynamics::driven_points::PointRows;
use crate::dynamics::effort_derivatives::EffortDerivatives;
use crate::dynamics::efforts::Efforts;
use crate::dynamics::loops::{LoopScratch, ProjectionScratch, Stabilisation};
use crate::dynamics::mimics;
use crate::dynamics::model::{DeclaredState, Model};
use crate::dynamics::reduced_model::ReducedScratch;
use crate::dynamics::response::Response;
use crate::dynamics::rows::{HeldRow, RowStack};
use crate::simulate::constraints::LoopMonitor;

pub struct Scratch {
    pub data: Data,
    /// How this evaluator keeps the loops closed (its kept rows, its passages).
    pub loops: LoopMonitor,
    /// The power of the non-conservative efforts at the last `derivative`.
    pub power: f64,
    /// Scratch of `derivative` for a tree, kept so that it allocates nothing: the normalised
    /// positions, the accelerations, and the efforts of a mechanism without any.
    pub(in crate::simulate) positions: Vec<f64>,
    pub(in crate::simulate) accelerations: DVector<f64>,
    pub(in crate::simulate) no_efforts: Efforts,
    /// The efforts at the last evaluation, and the declared coordinates and rates they used.
    pub(in crate::simulate) efforts: Efforts,
    /// Whether `efforts.external` is known to be all zero: a planar block that applies no
    /// efforts then need not fill its 6-vectors with zeros again (81 bodies: 486 numbers per
    /// call). Whatever writes them clears it (`evaluate_efforts`, `stack_reactions`).
    pub(in crate::simulate) external_is_zero: bool,
    pub(in crate::simulate) declared: DeclaredState,
    /// The storage of the run's next reference angles (`follow_reference`).
    pub(in crate::simulate) next_reference: DeclaredState,
    /// Scratch of the constrained equations: the tree's inverse dynamics and Ma − f (for the
    /// multipliers), and the loops' rows, factorisation and solution.
    pub(in crate::simulate) inverse: DVector<f64>,
    pub(in crate::simulate) force: DVector<f64>,
    pub(in crate::simulate) loop_scratch: LoopScratch,
    /// Scratch of the projections: the constraints and factorisations, and the velocities.
    pub(in crate::simulate) projection: ProjectionScratch,
    pub(in crate::simulate) velocities: Vec<f64>,
    /// The loops' rows at a step's end before it is accepted, to tell whether it crossed a
    /// singular configuration (`MechanicalSystem::cut_at_passage`); made at the first.
    pub(in crate::simulate) crossing_rows: Option<crate::dynamics::loops::Constraints>,
    /// The state of the last evaluation of a mechanism with loops, while `loop_scratch` holds
    /// its rows (empty otherwise): a projection of that state adopts them.
    pub(in crate::simulate) evaluated: Vec<f64>,
    /// The contacts' normal rows, and every contact row at the last evaluation.
    pub(in crate::simulate) normal_rows: Vec<usize>,
    pub(in crate::simulate) contact_state: ContactRows,
    /// The position drives' rows at the last evaluation or projection.
    pub(in crate::simulate) point_state: PointRows,
    /// Zero velocities or accelerations (tree length), the tree's mass matrix (sized at its
    /// first use, `mass_storage`: a run by the articulated-body algorithm never forms it, and
    /// its n² entries would be most of a long chain's memory), the basis of the velocities a
    /// tree's mimic couplings allow (`mimics::basis`, empty without them), and the response X
    /// of the accelerations to generalised forces (`response`), with whether it was formed at
    /// the state of the current evaluation.
    pub(in crate::simulate) at_rest: Vec<f64>,
    pub(in crate::simulate) mass: DMatrix<f64>,
    pub(in crate::simulate) coupled: DMatrix<f64>,
    pub(in crate::simulate) response: Response,
    pub(in crate::simulate) response_here: bool,
    /// The mimic couplings' forces after ABA (`coupled_aba`), and the generalised forces with
    /// the joints' viscous friction that ABA takes.
    pub(in crate::simulate) coupling: CouplingScratch,
    pub(in crate::simulate) tau_with_friction: DVector<f64>,
    /// The rows solved on the response (`rows`): at each evaluation (contacts, couplings with
    /// loops, coordinates held or driven), and in the projections onto the velocity rows and
    /// onto the position rows; the coordinates held at the evaluation (the drives' first), and
    /// those with a position the projection keeps (`stacked`); a step of the velocities.
    pub(in crate::simulate) rows: RowStack,
    pub(in crate::simulate) velocity_stack: RowStack,
    pub(in crate::simulate) position_stack: RowStack,
    pub(in crate::simulate) held: Vec<HeldRow>,
    pub(in crate::simulate) position_held: Vec<HeldRow>,
    pub(in crate::simulate) step: DVector<f64>,
    /// Per drive (`Model::drives`), the effort that imposed it at the last evaluation (its
    /// held row's multiplier), and their power then.
    pub drive_efforts: Vec<f64>,
    /// Per position drive (`Model::position_drives`), the force along x, y, z at its frame's
    /// origin that imposed the path at the last evaluation (its rows' multipliers).
    pub point_forces: Vec<f64>,
    pub(in crate::simulate) drive_power: f64,
    /// Where the drives' laws are evaluated.
    pub(in crate::simulate) law_values: Vec<f64>,
    /// Per stop, the contact force holding its coordinate on it at the last evaluation
    /// (positive while it pushes the coordinate into its range); per joint with friction, the
    /// force holding it while it sticks then, and the power of the slipping friction.
    pub contact: Vec<f64>,
    pub holding: Vec<f64>,
    pub(in crate::simulate) friction_power: f64,
    /// The planar algorithms' scratch, when the evaluations in this scratch take the planar
    /// form (the run's integrator's, `MechanicalSystem::use_planar`).
    pub(in crate::simulate) planar: Option<Box<PlanarData>>,
    /// The model in the actuated coordinates at the last evaluation (made at the first), and
    /// where the actuators' laws are evaluated.
    pub model_laws: Option<ReducedScratch>,
    pub(in crate::simulate) actuator_tape: EffortScratch,
    /// The analytical derivatives of inverse dynamics and of the efforts, for the tree
    /// Jacobian where they cover the model (`jacobian`); made at its first.
    pub(in crate::simulate) exact_jacobian: Option<Box<(RneaDerivatives, EffortDerivatives)>>,
}

impl Scratch {
    pub fn new(model: &Model, stabilisation: Stabilisation) -> Scratch {
        Scratch {
            data: Data::new(model),
            loops: LoopMonitor::new(stabilisation),
            power: 0.0,
            positions: Vec::new(),
            accelerations: DVector::zeros(model.velocities()),
            no_efforts: Efforts::none(model),
            efforts: Efforts::none(model),
            external_is_zero: false,
            declared: DeclaredState::default(),
            model_laws: None,
            actuator_tape: EffortScratch::default(),
            exact_jacobian: None,
            next_reference: DeclaredState::default(),
            inverse: DVector::zeros(model.nv),
            force: DVector::zeros(model.velocities()),
            loop_scratch: LoopScratch::new(model),
            projection: ProjectionScratch::new(model),
            velocities: Vec::new(),
            crossing_rows: None,
            evaluated: Vec::new(),
            normal_rows: Vec::with_capacity(model.contacts.len()),
            contact_state: ContactRows::new(model),
            point_state: PointRows::new(model),
            at_rest: vec![0.0; model.nv],
            mass: DMatrix::zeros(0, 0),
            // Read only with couplings: an identity of n² entries otherwise.
            coupled: match model.mimics.is_empty() {
                true => DMatrix::zeros(0, 0),
                false => mimics::basis(&model.mimics, model.nv),
            },
            response: Response::default(),
            response_here: false,
            coupling: CouplingScratch::new(model),
            tau_with_friction: DVector::zeros(model.velocities()),
            rows: RowStack::new(model),
            velocity_stack: RowStack::new(model),
            position_stack: RowStack::new(model),
            held: Vec::with_capacity(
                model.drives.len() + model.stops.len() + model.frictions.len(),
            ),
            position_held: Vec::with_capacity(model.drives.len() + model.stops.len()),
            step: DVector::zeros(model.velocities()),
            drive_efforts: vec![0.0; model.drives.len()],
            point_forces: vec![0.0; 3 * model.position_drives.len()],
            drive_power: 0.0,
            law_values: Vec::new(),
            contact: vec![0.0; model.stops.len()],
            holding: vec![0.0; model.frictions.len()],
            friction_power: 0.0,
            planar: None,
        }
    }
}

/// `mass` sized n × n (zero when it was not), the storage of a mass matrix made at its first use.
pub(in crate::simulate) fn mass_storage(mass: &mut DMatrix<f64>, n: usize) -> &mut DMatrix<f64> {
    if mass.nrows() != n {
        *mass = DMatrix::zeros(n, n);
    }
    mass
}
