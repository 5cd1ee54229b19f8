//! The CPU time of the calling thread: unlike the wall clock, it leaves out the time the machine
//! gave to other work (on a shared machine, the main noise of a timing).

/// This thread's CPU time, in seconds since an arbitrary origin; NaN where the system cannot
/// tell it (a timing is then reported as unknown rather than replaced by the wall clock).
pub fn thread_cpu_seconds() -> f64 {
    let mut now = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `now` is a valid timespec for the call to write into.
    let status = unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut now) };
    if status != 0 {
        return f64::NAN;
    }
    now.tv_sec as f64 + now.tv_nsec as f64 * 1e-9
}
