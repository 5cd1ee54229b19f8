//! Timing shared by the benchmarks that report a time per call.

use std::time::Instant;

/// Best time per call, in seconds, over 7 batches sized to about 20 ms each: the minimum is the
/// run least disturbed by the rest of the machine.
pub fn best_time_per_call(mut f: impl FnMut()) -> f64 {
    let start = Instant::now();
    let mut calls = 0u64;
    while start.elapsed().as_secs_f64() < 0.02 {
        f();
        calls += 1;
    }
    (0..7)
        .map(|_| {
            let start = Instant::now();
            for _ in 0..calls {
                f();
            }
            start.elapsed().as_secs_f64() / calls as f64
        })
        .fold(f64::INFINITY, f64::min)
}
