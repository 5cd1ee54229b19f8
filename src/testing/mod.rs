//! `lsdc test`: regression tests of mechanisms from manifests (`lsdtest.toml`). Each case runs a
//! program through the `simulate` pipeline, compares its outputs with a reference within
//! per-variable tolerances and makes its checks; cases run on several threads. `--calibrate`
//! proposes tolerances from two runs, `--update` records references (`docs/commands.md`, *test*).

pub mod calibrate;
pub mod case;
pub mod compare;
pub mod manifest;
pub mod record;
pub mod report;

use rayon::prelude::*;

#[cfg(lsdc_internals)]
pub use case::Status;
pub use case::{run_case, Outcome};
pub use manifest::{Case, ManifestError};

/// Every case of the manifests under `paths` (files, or folders searched for `lsdtest.toml`).
pub fn load(paths: &[std::path::PathBuf]) -> Result<Vec<Case>, ManifestError> {
    let mut cases = Vec::new();
    for manifest in manifest::discover(paths)? {
        cases.extend(manifest::read(&manifest)?);
    }
    Ok(cases)
}

/// Applies `task` to every case on `jobs` threads (at least one), the results in the cases'
/// order. Threads take the next case as they finish one, so a long case does not hold others.
pub fn for_each_case<R: Send>(
    cases: &[Case],
    jobs: usize,
    task: impl Fn(&Case) -> R + Sync,
) -> Result<Vec<R>, String> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(jobs.max(1))
        .build()
        .map_err(|error| format!("cannot start {jobs} threads: {error}"))?;
    // One case per task: cases take from milliseconds to seconds, so no batching.
    Ok(pool.install(|| cases.par_iter().with_max_len(1).map(&task).collect()))
}

/// Runs every case on `jobs` threads.
pub fn run_all(cases: &[Case], jobs: usize) -> Result<Vec<Outcome>, String> {
    for_each_case(cases, jobs, run_case)
}
