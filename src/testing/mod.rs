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

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

pub use case::{run_case, Outcome, Status};
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
) -> Vec<R> {
    let next = AtomicUsize::new(0);
    let results: Vec<Mutex<Option<R>>> = cases.iter().map(|_| Mutex::new(None)).collect();
    let work = || loop {
        let index = next.fetch_add(1, Ordering::Relaxed);
        let Some(case) = cases.get(index) else { break };
        let result = task(case);
        *results[index].lock().expect("no thread panics holding it") = Some(result);
    };
    std::thread::scope(|scope| {
        for _ in 0..jobs.clamp(1, cases.len().max(1)) {
            scope.spawn(work);
        }
    });
    (results.into_iter())
        .map(|r| {
            r.into_inner()
                .expect("not poisoned")
                .expect("every case ran")
        })
        .collect()
}

/// Runs every case on `jobs` threads.
pub fn run_all(cases: &[Case], jobs: usize) -> Vec<Outcome> {
    for_each_case(cases, jobs, run_case)
}
