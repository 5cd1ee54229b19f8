//! Timing shared by the closed-loop benchmarks (`loops`, `loop_scaling`, `call_counts`): CPU time
//! per call (best batch), medians of runs, and the cost of one constrained right-hand side and
//! one projection.

use std::hint::black_box;

use lsdc::dynamics::algorithms::{crba, rnea, Data};
use lsdc::dynamics::model::Model;
use lsdc::prepare::Prepared;
use lsdc::simulate::system::MechanicalSystem;
use lsdc::spatial::Force;

#[allow(unused_imports)] // the loops benchmark takes medians of runs, the scaling one does not
pub use crate::common::median;

/// CPU time of one call of `f` (this thread's clock, so that the time the shared machine gives
/// to others is left out): the best of 7 batches of about 20 ms, the batch least disturbed.
#[allow(dead_code)] // the call counts run calls without timing them
pub fn time_per_call(f: impl FnMut()) -> f64 {
    crate::common::cpu_time_per_call(f).0
}

/// The constrained system of `prepared` at its initial state, closed (the state is returned).
pub fn loop_system(prepared: &Prepared) -> (MechanicalSystem<'_>, Vec<f64>) {
    let model = &prepared.model;
    let (mut y, v) = model
        .state_from_declared(&prepared.coordinates, &prepared.rates)
        .expect("initial state");
    y.extend_from_slice(&v);
    let reference = prepared.coordinates.clone();
    let mut system = MechanicalSystem::new(model, reference, prepared.settings.stabilisation);
    system.force_loop_method(prepared.loop_method);
    system.close_in_plane(prepared.planar.as_deref().ok());
    system.start_loops(&mut y).expect("loops close");
    (system, y)
}

/// Cost (µs of CPU, best batch) of one constrained right-hand side and of one projection onto the loops,
/// at the initial state.
#[allow(dead_code)]
pub fn call_costs(prepared: &Prepared) -> (f64, f64) {
    let (mut system, y) = loop_system(prepared);
    let mut dydt = vec![0.0; y.len()];
    let rhs = time_per_call(|| {
        system
            .derivative(0.0, black_box(&y), &mut dydt)
            .expect("evaluates")
    });
    // At the closed initial state (round-off residual) the projection still tries a Newton step
    // and corrects the velocities: about its cost after an integration step.
    let projection = time_per_call(|| {
        let mut z = y.clone();
        black_box(system.keep_closed(0.0, &mut z).expect("projects"));
    });
    (rhs * 1e6, projection * 1e6)
}

/// The same bodies as a tree: `prepared`'s model with its closing joins removed (and the
/// efforts on them), and the tree part of the initial state.
#[allow(dead_code)] // the loop derivatives' benchmark times no tree
pub fn tree_model(prepared: &Prepared) -> (Model, Vec<f64>) {
    let mut tree = prepared.model.clone();
    tree.link_efforts.retain(|e| e.joint < tree.joints.len());
    tree.link_potentials.retain(|p| p.joint < tree.joints.len());
    tree.loops.clear();
    tree.loop_balls.clear();
    tree.declared_count -= tree.nc;
    tree.nc = 0;
    tree.compile_efforts();
    let model = &prepared.model;
    let (q, v) = model
        .state_from_declared(&prepared.coordinates, &prepared.rates)
        .expect("initial state");
    let mut y = q[..model.nq].to_vec();
    y.extend_from_slice(&v[..model.nv]);
    (tree, y)
}

/// A right-hand side of the tree of `tree_model`, to call repeatedly. Without its loops the
/// tree may have motions without inertia (the Delta's rods spinning about their axes), which
/// its forward dynamics refuses: the call is then the mass matrix and the bias forces, which any
/// method of solving the loops needs.
#[allow(dead_code)] // the loop derivatives' benchmark times no tree
pub fn tree_call<'m>(prepared: &Prepared, tree: &'m Model, y: &'m [f64]) -> Box<dyn FnMut() + 'm> {
    let model = &prepared.model;
    let declared = prepared.coordinates[..prepared.coordinates.len() - model.nc].to_vec();
    let reference = declared;
    let mut system = MechanicalSystem::new(tree, reference, prepared.settings.stabilisation);
    let mut dydt = vec![0.0; y.len()];
    if system.derivative(0.0, y, &mut dydt).is_ok() {
        return Box::new(move || {
            system
                .derivative(0.0, black_box(y), &mut dydt)
                .expect("evaluates")
        });
    }
    let (nq, nv) = (model.nq, model.nv);
    let mut data = Data::new(tree);
    let zero = vec![0.0; nv];
    let external = vec![Force::zeros(); tree.joints.len() + 1];
    Box::new(move || {
        let (q, v) = (&y[..nq], &y[nq..]);
        black_box(crba(tree, &mut data, black_box(q)).expect("mass matrix"));
        black_box(rnea(tree, &mut data, q, v, &zero, &external).expect("bias forces"));
    })
}

/// Cost (µs of CPU, best batch) of one right-hand side of the same bodies as a tree
/// (`tree_model`, `tree_call`).
#[allow(dead_code)]
pub fn tree_cost(prepared: &Prepared) -> f64 {
    let (tree, y) = tree_model(prepared);
    let call = tree_call(prepared, &tree, &y);
    time_per_call(call) * 1e6
}
