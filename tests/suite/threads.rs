//! One prepared mechanism shared by threads: the model is only read during a run (its efforts'
//! tape, its joints), so a parameter sweep runs from many starting states at once without a
//! copy of the model per run.

use lsdc::prepare::Prepared;
use lsdc::simulate::run::{run_from, Start};

use crate::common::programs::prepared;

fn shared<T: Send + Sync>(value: &T) -> &T {
    value
}

#[test]
fn a_sweep_over_starting_angles_shares_one_prepared_pendulum_across_threads() {
    /// The pendulum's angle at the end of a run started at `angle`.
    fn final_angle(pendulum: &Prepared, angle: f64) -> f64 {
        let mut coordinates = pendulum.coordinates.clone();
        coordinates[0] = angle;
        let start = Start {
            coordinates: &coordinates,
            rates: &pendulum.rates,
        };
        let simulation = run_from(pendulum, &start, &mut |_| {});
        assert!(simulation.report.failure.is_none());
        simulation.samples.last().expect("outputs").coordinates[0]
    }

    let prepared = prepared("pendulum", &[]);
    let pendulum: &Prepared = shared(&prepared);
    let angles = [0.1, 0.5, 1.0, 2.0];
    let finals: Vec<f64> = std::thread::scope(|scope| {
        let runs: Vec<_> = angles
            .iter()
            .map(|&angle| scope.spawn(move || final_angle(pendulum, angle)))
            .collect();
        runs.into_iter().map(|r| r.join().expect("runs")).collect()
    });
    // Each thread's run is the run from that start on one thread alone.
    for (&angle, &end) in angles.iter().zip(&finals) {
        assert_eq!(final_angle(pendulum, angle), end);
    }
    // Different amplitudes, different motions.
    assert!(finals.windows(2).all(|w| w[0] != w[1]), "{finals:?}");
}
