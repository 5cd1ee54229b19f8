//! The CPU time of the calling thread (and of the whole process, for work spread over threads): what a computation cost, leaving out the time the machine
//! gave to other work (on a shared machine the wall clock can be several times longer).

/// This thread's CPU time in seconds, or `None` where the clock cannot be read.
pub fn thread_cpu_seconds() -> Option<f64> {
    cpu_seconds(libc::CLOCK_THREAD_CPUTIME_ID)
}

/// The CPU time of every thread of the process in seconds (a sweep's runs on every core), or
/// `None` where the clock cannot be read.
pub fn process_cpu_seconds() -> Option<f64> {
    cpu_seconds(libc::CLOCK_PROCESS_CPUTIME_ID)
}

fn cpu_seconds(clock: libc::clockid_t) -> Option<f64> {
    let mut now = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `now` is a valid timespec for the call to write into.
    let status = unsafe { libc::clock_gettime(clock, &mut now) };
    (status == 0).then_some(now.tv_sec as f64 + now.tv_nsec as f64 * 1e-9)
}
