//! Quasi-static dragging with the loops kept closed: a point of a body follows a target as
//! closely as the mechanism allows. At each target the closure equations Φ(q) = 0 hold exactly
//! (to the assembly tolerance) and the dragged point is a soft goal: Levenberg–Marquardt on
//! ½|p(q) − target|² restricted to the closed configurations. Each step moves the coordinates
//! by the least-norm solution of the linearised closure plus a damped least-squares step
//! towards the target in the closure's null space, and the result is closed again by assembly.
//! A target out of reach ends at the closed configuration nearest to it: the distance left is
//! reported, never hidden.

use nalgebra::{DMatrix, DVector, Vector3};

use super::assembly::{assemble, least_norm, AssemblyError, AssemblyOptions};
use super::closure::closure;
use super::eval::EvalError;
use super::frames::FramePoint;
use super::model::KinematicModel;
use crate::corrector::{correct, Acceptance, Correction, Damping, Progress, Settings};
use crate::spatial;

#[derive(Clone, Debug)]
pub struct DragOptions {
    /// Iterations at most per target.
    pub max_iterations: usize,
    /// A target is reached when the dragged point ends this close to it (metres).
    pub reach_tolerance: f64,
    pub assembly: AssemblyOptions,
}

impl Default for DragOptions {
    fn default() -> Self {
        DragOptions {
            max_iterations: 100,
            reach_tolerance: 1e-9,
            assembly: AssemblyOptions::default(),
        }
    }
}

/// The configuration reached for one target.
#[derive(Clone, Debug)]
pub struct Dragged {
    pub q: Vec<f64>,
    /// Where the dragged point ended.
    pub point: Vector3<f64>,
    /// Its distance to the target.
    pub distance: f64,
    /// Largest closure residual component left (metres, ≈ radians).
    pub loop_residual: f64,
    pub iterations: usize,
}

impl Dragged {
    pub fn reached(&self, options: &DragOptions) -> bool {
        self.distance <= options.reach_tolerance
    }
}

#[derive(Debug)]
pub enum DragError {
    Evaluation(EvalError),
    /// The loops could not be closed at the start or after a step.
    NoAssembly {
        loop_residual: f64,
    },
}

impl From<EvalError> for DragError {
    fn from(e: EvalError) -> Self {
        DragError::Evaluation(e)
    }
}

impl From<AssemblyError> for DragError {
    fn from(e: AssemblyError) -> Self {
        match e {
            AssemblyError::Evaluation(e) => DragError::Evaluation(e),
            AssemblyError::NoAssembly { loop_errors, .. } => DragError::NoAssembly {
                loop_residual: loop_errors
                    .iter()
                    .map(|(p, r)| p.max(*r))
                    .fold(0.0, f64::max),
            },
        }
    }
}

/// The point's position and its Jacobian (3 × coordinates) at `q`, with the loops' residual
/// and Jacobian.
pub(crate) struct Linearised {
    pub point: Vector3<f64>,
    pub point_jacobian: DMatrix<f64>,
    pub residual: DVector<f64>,
    pub closure_jacobian: DMatrix<f64>,
}

pub(crate) fn linearise(
    model: &KinematicModel,
    frame: &FramePoint,
    q: &[f64],
) -> Result<Linearised, EvalError> {
    let closed = closure(model, q)?;
    let point = frame.pose(&closed.configuration).translation.vector;
    let twists = &closed.configuration.jacobian(frame.body);
    let mut point_jacobian = DMatrix::zeros(3, q.len());
    for c in 0..q.len() {
        let twist = spatial::Twist::from_column_slice(twists.column(c).as_slice());
        let velocity = spatial::point_velocity(&twist, &point);
        point_jacobian.column_mut(c).copy_from(&velocity);
    }
    Ok(Linearised {
        point,
        point_jacobian,
        residual: closed.residual,
        closure_jacobian: closed.jacobian.dense(),
    })
}

/// Moves the mechanism from the closed configuration `q` so that `frame`'s origin comes as
/// close as it can to `target`.
pub fn drag(
    model: &KinematicModel,
    frame: &FramePoint,
    q: &[f64],
    target: &Vector3<f64>,
    options: &DragOptions,
) -> Result<Dragged, DragError> {
    let free = vec![false; q.len()];
    let q = assemble(model, q, &free, &options.assembly)?.q;
    let current = linearise(model, frame, &q)?;
    let mut steps = DragSteps {
        model,
        frame,
        target,
        assembly: &options.assembly,
        free,
        q,
        distance: (current.point - target).norm(),
        current,
        steps: None,
        trial: Vec::new(),
        tried: None,
    };
    let settings = Settings {
        iterations: options.max_iterations,
        ..DRAGGING
    };
    let outcome = correct(&mut steps, &settings)?;
    Ok(Dragged {
        point: steps.current.point,
        distance: steps.distance,
        loop_residual: steps.current.residual.amax(),
        q: steps.q,
        iterations: outcome.iterations,
    })
}

/// Dragging's iteration: Levenberg–Marquardt on the distance to the target, from a small
/// damping; a step that brings the point nearer by round-off only ends it.
const DRAGGING: Settings = Settings {
    iterations: 100,
    damping: Damping::Levenberg {
        initial: 1e-6,
        floor: 1e-15,
        tries: 30,
        smallest_step: 0.0,
    },
    acceptance: Acceptance::Descent,
    progress: Progress::Absolute(1e-15),
};

/// The drag's steps, for the corrector: each one the closure's least-norm correction plus a
/// damped step towards the target along the closed motions, closed again by assembly (a step
/// that assembly cannot close is taken again with more damping).
struct DragSteps<'a> {
    model: &'a KinematicModel,
    frame: &'a FramePoint,
    target: &'a Vector3<f64>,
    assembly: &'a AssemblyOptions,
    /// No coordinate is held.
    free: Vec<bool>,
    q: Vec<f64>,
    current: Linearised,
    /// The point's distance to the target at `q`.
    distance: f64,
    steps: Option<Steps>,
    /// The closed coordinates the step leads to.
    trial: Vec<f64>,
    /// Their linearisation and distance, once tried.
    tried: Option<(Linearised, f64)>,
}

impl Correction for DragSteps<'_> {
    type Error = DragError;

    fn settled(&self) -> bool {
        self.distance <= 0.0 || self.distance.is_nan()
    }

    fn merit(&self) -> f64 {
        self.distance
    }

    fn linearise(&mut self) -> Result<(), DragError> {
        self.steps = Some(Steps::new(&self.current, self.target));
        Ok(())
    }

    fn step(&mut self, damping: f64) -> Result<Option<f64>, DragError> {
        let steps = self.steps.as_ref().expect("linearised");
        let step = steps.at(damping);
        let trial: Vec<f64> = self.q.iter().zip(step.iter()).map(|(a, b)| a + b).collect();
        match assemble(self.model, &trial, &self.free, self.assembly) {
            Ok(closed) => {
                (self.trial, self.tried) = (closed.q, None);
                Ok(Some(step.amax()))
            }
            Err(AssemblyError::NoAssembly { .. }) => Ok(None),
            Err(e) => Err(e.into()),
        }
    }

    fn try_step(&mut self) -> Result<f64, DragError> {
        let candidate = linearise(self.model, self.frame, &self.trial)?;
        let distance = (candidate.point - self.target).norm();
        self.tried = Some((candidate, distance));
        Ok(distance)
    }

    fn accept(&mut self) {
        if let Some((current, distance)) = self.tried.take() {
            let q = std::mem::take(&mut self.trial);
            (self.q, self.current, self.distance) = (q, current, distance);
        }
    }
}

/// The pieces of a step: the least-norm correction of the linearised closure, and the normal
/// equations of the goal in the closure's null space, solved for a given damping.
struct Steps {
    correction: DVector<f64>,
    normal: DMatrix<f64>,
    right: DVector<f64>,
    projector: DMatrix<f64>,
}

impl Steps {
    fn new(current: &Linearised, target: &Vector3<f64>) -> Steps {
        let n = current.point_jacobian.ncols();
        let correction = least_norm(current.closure_jacobian.clone(), &-&current.residual)
            .unwrap_or_else(|| DVector::zeros(n));
        let projector = null_space_projector(&current.closure_jacobian, n);
        let along = &current.point_jacobian * &projector;
        let error = current.point - target + &current.point_jacobian * &correction;
        Steps {
            correction,
            normal: along.transpose() * &along,
            right: -(along.transpose() * error),
            projector,
        }
    }

    /// The step for a damping relative to the normal matrix's largest diagonal term.
    fn at(&self, damping: f64) -> DVector<f64> {
        let scale = self.normal.diagonal().max().max(1e-12);
        let mut damped = self.normal.clone();
        for i in 0..damped.nrows() {
            damped[(i, i)] += damping * scale;
        }
        let goal = damped.cholesky().map_or_else(
            || DVector::zeros(self.right.len()),
            |c| c.solve(&self.right),
        );
        &self.correction + &self.projector * goal
    }
}

/// I − RᵀR with R an orthonormal basis of the rows of `jacobian` (singular values above 1e-10
/// of the largest): the projection onto the motions that keep the loops closed to first order.
fn null_space_projector(jacobian: &DMatrix<f64>, n: usize) -> DMatrix<f64> {
    let mut projector = DMatrix::identity(n, n);
    if jacobian.nrows() == 0 {
        return projector;
    }
    // A non-finite Jacobian has no decomposition: a projector of NaN makes the step fail.
    let Some(svd) = crate::linalg::svd(jacobian.clone(), false, true) else {
        return DMatrix::from_element(n, n, f64::NAN);
    };
    let Some(v_t) = svd.v_t else {
        return projector;
    };
    let largest = svd.singular_values.max();
    for (k, &s) in svd.singular_values.iter().enumerate() {
        if s > 1e-10 * largest {
            let row = v_t.row(k);
            projector -= row.transpose() * row;
        }
    }
    projector
}
