//! `simulate --compiled` for a prepared simulation: its native forward dynamics
//! (`native.rs`) attached once it agrees with the simulator's own evaluation, or the warning
//! that says why the runs go on without it.

use super::system::MechanicalSystem;
use crate::diag::Diagnostic;
use crate::dynamics::energy::conservative_forces;
use crate::dynamics::joint::{Joint, JointType};
use crate::dynamics::loops::Stabilisation;
use crate::dynamics::model::Model;
use crate::elab::mechanism::Mechanism;
use crate::prepare::native::{build, disagreement, LoopRows, Unavailable};
use crate::prepare::Prepared;
use crate::symbolic::quaternion_joints::{BallKind, QuaternionJoins};

/// Compiles `prepared`'s forward dynamics and keeps it for its runs, once it agrees with the
/// simulator's evaluation at the initial state (to 1e-9 of the largest acceleration); otherwise
/// says why the runs go on without it. With loops, the initial state is the run's start (the
/// loops closed, their structure decided), and the code solves on the rows kept there.
pub fn attach(prepared: &mut Prepared, mechanism: &Mechanism) -> Result<(), Unavailable> {
    let model = &prepared.model;
    if model.has_contacts() {
        return Err(Unavailable::Unsupported(
            "the mechanism has contacts (the native code serves trees and loops without other constraints)".into(),
        ));
    }
    if !model.drives.is_empty() || !model.position_drives.is_empty() {
        return Err(Unavailable::Unsupported(
            "the mechanism has motions imposed in time (`drive`, `time` in a dof chain), which the native code does not impose".into(),
        ));
    }
    if model.actuation.is_some() {
        return Err(Unavailable::Unsupported(
            "the mechanism has actuators (`actuate`), whose laws the native code does not compute"
                .into(),
        ));
    }
    if model.has_loops() && prepared.settings.stabilisation != Stabilisation::Projection {
        return Err(Unavailable::Unsupported(
            "the loops are kept by other means than the projection after each step, whose accelerations the native code does not compute".into(),
        ));
    }
    let (q, v) = model
        .state_from_declared(&prepared.coordinates, &prepared.rates)
        .map_err(|e| Unavailable::Unsupported(format!("the start cannot be evaluated: {e:?}")))?;
    let reference = prepared.coordinates.clone();
    let mut system = MechanicalSystem::new(model, reference, prepared.settings.stabilisation);
    let mut y: Vec<f64> = q.iter().chain(&v).copied().collect();
    // With loops, the run's start: the loops closed and their structure decided (the rows the
    // native code keeps).
    let unserved =
        |e: String| Unavailable::Unsupported(format!("the start cannot be evaluated: {e}"));
    system
        .start_loops(&mut y)
        .map_err(|e| unserved(e.to_string()))?;
    // The simulator's own evaluation at the start: the accelerations to agree with, and, where
    // the loops allow motions without mass, its choice of those it holds at rest.
    let mut dydt = vec![0.0; y.len()];
    system
        .derivative(0.0, &y, &mut dydt)
        .map_err(|e| unserved(e.to_string()))?;
    let structure = &system.scratch.loops.structure;
    let held = system.scratch.loop_scratch.left_at_rest(structure);
    if model.has_loops() && held.len() != structure.massless {
        return Err(Unavailable::Unsupported(
            "its loops allow motions without mass, and the run has not chosen which it holds at rest"
                .into(),
        ));
    }
    let (positions, rates) = y.split_at(model.positions());
    let loops = model.has_loops().then(|| LoopRows {
        rows: &structure.choice.rows,
        at_rest: &structure.idle,
        held,
        tree: model.nv,
        state: (positions, rates),
    });
    let native = build(
        mechanism,
        &prepared.topology,
        quaternion_joins(model),
        &model.unknowns,
        loops,
    )?;
    if native.dimension != model.velocities() || native.positions != model.positions() {
        return Err(Unavailable::Unsupported(
            "its coordinates are not the joints' own".into(),
        ));
    }
    let (positions, rates) = y.split_at(model.positions());
    let largest = disagreement(&native, 0.0, positions, rates, &dydt[model.positions()..]);
    if largest > AGREEMENT {
        return Err(Unavailable::Disagrees { largest });
    }
    prepared.native = Some(native);
    Ok(())
}

/// The joins the simulator integrates as quaternions (`dynamics::joint`), for equations in its
/// state.
fn quaternion_joins(model: &Model) -> QuaternionJoins {
    let ball = |joint: &Joint| match joint.kind {
        JointType::Chain => None,
        JointType::Spherical { .. } => Some((joint.chain.join, BallKind::Spherical)),
        JointType::Free { .. } => Some((joint.chain.join, BallKind::Free)),
    };
    model.joints.iter().filter_map(ball).collect()
}

/// The warnings of `simulate --compiled`: why the native code does not serve (W0904), or what
/// a run with it leaves out (W0905: the work of non-conservative efforts, which the native
/// code does not compute, so the report has no energy balance).
pub fn attach_with_warnings(prepared: &mut Prepared, mechanism: &Mechanism) -> Vec<Diagnostic> {
    match attach(prepared, mechanism) {
        Err(why) => vec![Diagnostic::warning(
            "W0904",
            format!("--compiled: {why}; the run evaluates the equations without native code"),
        )],
        Ok(()) if !conservative_forces(&prepared.model).complete => vec![Diagnostic::warning(
            "W0905",
            "--compiled: the native code computes the accelerations only, so the work of the \
             non-conservative efforts is not tracked and the report has no energy balance",
        )
        .help("run without --compiled for the energy balance")],
        Ok(()) => Vec::new(),
    }
}

/// How far, relative to the largest acceleration, the native accelerations may be from the
/// simulator's: both evaluate the same equations, by other sums (measured: 1e-15 to 4e-12).
const AGREEMENT: f64 = 1e-9;
