//! Forward dynamics (ABA) over a batch of states read from a file, through the library's
//! boundary alone (`lsdc::api::StateBatch`): the Rust side of `bench/python_aba.py`, which
//! times the same batch from Python (`Prepared.aba` on NumPy arrays) in interleaved rounds.
//!
//! An example of the package's crate, so that it links the very build of lsdc the extension
//! links (the same profile and flags, without `lsdc_internals`): from `python/`,
//! `CARGO_TARGET_DIR=../target/python cargo run --release --example aba_batch -- PROGRAM STATES
//! OUT`. STATES holds N states as
//! little-endian f64, the N rows of q (N × nq), then of v and of τ (N × nv each); the
//! accelerations are written to OUT the same way (N × nv), and the thread CPU time of the
//! evaluation alone (seconds) is printed on standard output.

use lsdc::api::{Program, StateBatch};

/// The CPU time of the calling thread, in seconds.
fn thread_cpu_seconds() -> f64 {
    let mut time = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: clock_gettime writes the timespec it is given.
    unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut time) };
    time.tv_sec as f64 + time.tv_nsec as f64 * 1e-9
}

fn read_f64s(path: &str) -> Vec<f64> {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("cannot read `{path}`: {e}"));
    (bytes.chunks_exact(8))
        .map(|b| f64::from_le_bytes(b.try_into().expect("8 bytes")))
        .collect()
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let [_, program, states, out] = args.as_slice() else {
        return Err("usage: aba_batch PROGRAM STATES OUT".into());
    };
    let program = Program::from_file(program, &Default::default())?;
    let prepared = program.prepare(&[], &Default::default())?;
    let mut batch = StateBatch::new(&prepared);
    let (nq, nv) = batch.dimensions();
    let values = read_f64s(states);
    let count = values.len() / (nq + 2 * nv);
    let (q, rest) = values.split_at(count * nq);
    let (v, tau) = rest.split_at(count * nv);
    let mut a = vec![0.0; count * nv];
    let started = thread_cpu_seconds();
    batch.aba(count, (q, v, tau), &mut a)?;
    let seconds = thread_cpu_seconds() - started;
    let bytes: Vec<u8> = a.iter().flat_map(|x| x.to_le_bytes()).collect();
    std::fs::write(out, bytes)?;
    println!("{seconds}");
    Ok(())
}
