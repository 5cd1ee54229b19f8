//! Timing shared by the benchmarks that report a time per call.

use std::time::Instant;

#[allow(dead_code)] // each benchmark uses the timer it needs
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

/// This thread's CPU time, in seconds: unlike the wall clock, it leaves out the time the machine
/// gave to others (on a shared virtual machine, the main noise of a timing).
pub fn thread_cpu_seconds() -> f64 {
    lsdc::simulate::clock::thread_cpu_seconds().expect("the thread's CPU clock is readable")
}

#[allow(dead_code)]
/// CPU time per call, in seconds, over 7 batches sized to about 20 ms each: (best, median).
pub fn cpu_time_per_call(mut f: impl FnMut()) -> (f64, f64) {
    let start = thread_cpu_seconds();
    let mut calls = 0u64;
    while thread_cpu_seconds() - start < 0.02 {
        f();
        calls += 1;
    }
    let mut times: Vec<f64> = (0..7)
        .map(|_| {
            let start = thread_cpu_seconds();
            for _ in 0..calls {
                f();
            }
            (thread_cpu_seconds() - start) / calls as f64
        })
        .collect();
    times.sort_by(f64::total_cmp);
    (times[0], times[times.len() / 2])
}
