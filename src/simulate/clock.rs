//! The CPU time of the calling thread: what a computation cost, leaving out the time the machine
//! gave to other work (on a shared machine the wall clock can be several times longer).

/// This thread's CPU time in seconds, or `None` where the clock cannot be read.
pub fn thread_cpu_seconds() -> Option<f64> {
    let mut now = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `now` is a valid timespec for the call to write into.
    let status = unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut now) };
    (status == 0).then_some(now.tv_sec as f64 + now.tv_nsec as f64 * 1e-9)
}
