//! Timing shared by the closed-loop benchmarks (`loops`, `loop_scaling`): medians of calls and
//! of runs, and the cost of one constrained right-hand side and one projection.

use std::cell::RefCell;
use std::hint::black_box;
use std::rc::Rc;
use std::time::Instant;

use lsdc::simulate::prepare::Prepared;
use lsdc::simulate::system::MechanicalSystem;

pub fn median(mut values: Vec<f64>) -> f64 {
    values.sort_by(f64::total_cmp);
    values[values.len() / 2]
}

/// Median time of one call of `f` over batches of about 10 ms.
pub fn time_per_call(mut f: impl FnMut()) -> f64 {
    let start = Instant::now();
    let mut calls = 0u64;
    while start.elapsed().as_secs_f64() < 0.01 {
        f();
        calls += 1;
    }
    let batches = (0..9)
        .map(|_| {
            let start = Instant::now();
            (0..calls).for_each(|_| f());
            start.elapsed().as_secs_f64() / calls as f64
        })
        .collect();
    median(batches)
}

/// Median cost (µs) of one constrained right-hand side and of one projection onto the loops,
/// at the initial state.
pub fn call_costs(prepared: &Prepared) -> (f64, f64) {
    let model = &prepared.model;
    let (mut y, v) = model
        .state_from_declared(&prepared.coordinates, &prepared.rates)
        .expect("initial state");
    y.extend_from_slice(&v);
    let reference = Rc::new(RefCell::new(prepared.coordinates.clone()));
    let mut system = MechanicalSystem::new(model, reference, prepared.settings.stabilisation);
    system.start_loops(&mut y).expect("loops close");
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
