//! Timing shared by the benchmarks that report a time per call.

use std::time::Instant;

use lsdc::driver::compile_files;
use lsdc::dynamics::model::Model;
use lsdc::load::LoadOptions;
use lsdc::prepare::{prepare, Prepared, Settings};
use lsdc::simulate::system::MechanicalSystem;

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

#[allow(dead_code)] // each benchmark uses the timer it needs
/// Thread CPU time per call of each of `tasks`, in `rounds` rounds that run each task in turn
/// (so that a change of the machine's load falls on all of them alike), each task's batch sized
/// to about `batch_seconds`: (best, median) per task.
pub fn interleaved<const N: usize>(
    mut tasks: [&mut dyn FnMut(); N],
    batch_seconds: f64,
    rounds: usize,
) -> [(f64, f64); N] {
    let calls = tasks.each_mut().map(|task| {
        let start = thread_cpu_seconds();
        let mut calls = 0u64;
        while thread_cpu_seconds() - start < batch_seconds {
            task();
            calls += 1;
        }
        calls
    });
    let mut times: [Vec<f64>; N] = std::array::from_fn(|_| Vec::new());
    for _ in 0..rounds {
        for k in 0..N {
            let start = thread_cpu_seconds();
            for _ in 0..calls[k] {
                tasks[k]();
            }
            times[k].push((thread_cpu_seconds() - start) / calls[k] as f64);
        }
    }
    times.map(|mut t| {
        t.sort_by(f64::total_cmp);
        (t[0], t[t.len() / 2])
    })
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

#[allow(dead_code)]
/// The median of `values` (the upper one of an even count).
pub fn median(mut values: Vec<f64>) -> f64 {
    values.sort_by(f64::total_cmp);
    values[values.len() / 2]
}

#[allow(dead_code)]
/// The smallest of `values`.
pub fn best(values: &[f64]) -> f64 {
    values.iter().copied().fold(f64::INFINITY, f64::min)
}

#[allow(dead_code)]
/// The state `(q, v)` of `prepared`'s initial positions and rates, as the integrators hold it.
pub fn initial_state(prepared: &Prepared) -> Vec<f64> {
    let (mut y, v) = (prepared.model)
        .state_from_declared(&prepared.coordinates, &prepared.rates)
        .expect("initial state");
    y.extend_from_slice(&v);
    y
}

#[allow(dead_code)]
/// The right-hand side of `system` at `y` (t = 0.1), timed by `cpu_time_per_call`.
pub fn rhs_cpu_time(system: &mut MechanicalSystem<'_>, y: &[f64]) -> (f64, f64) {
    let mut dydt = vec![0.0; y.len()];
    cpu_time_per_call(|| {
        system
            .derivative(0.1, std::hint::black_box(y), &mut dydt)
            .expect("evaluates");
    })
}

#[allow(dead_code)]
/// The thread CPU time of a whole run of `prepared`, its samples dropped.
pub fn run_cpu_seconds(prepared: &Prepared) -> f64 {
    let start = thread_cpu_seconds();
    let simulation = lsdc::api::run(prepared, &mut |s| {
        std::hint::black_box(s);
    });
    assert!(simulation.report.failure.is_none());
    thread_cpu_seconds() - start
}

#[allow(dead_code)]
/// A small deterministic generator (xorshift64*), so both runs see the same kind of states.
pub struct Random(pub u64);

impl Random {
    pub fn uniform(&mut self, low: f64, high: f64) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        let unit = (self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64;
        low + (high - low) * unit
    }

    pub fn vector(&mut self, n: usize, bound: f64) -> Vec<f64> {
        (0..n).map(|_| self.uniform(-bound, bound)).collect()
    }
}

#[allow(dead_code)]
/// The files named on the command line (flags left out), or `defaults` when none is.
pub fn files_or(defaults: Vec<std::path::PathBuf>) -> Vec<std::path::PathBuf> {
    let named: Vec<std::path::PathBuf> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with("--"))
        .map(std::path::PathBuf::from)
        .collect();
    match named.is_empty() {
        true => defaults,
        false => named,
    }
}

#[allow(dead_code)]
/// A program or URDF robot prepared with its own values and default settings (a URDF robot: a
/// fixed base and gravity, as every command reads a `.urdf` file).
pub fn prepared_file(path: &std::path::Path) -> Prepared {
    let options = LoadOptions {
        library_dirs: Vec::new(),
        use_environment: false,
        scene: None,
    };
    let compilation = compile_files(&[path.to_path_buf()], &options).expect("readable");
    let mechanism = compilation.mechanism.unwrap_or_else(|| {
        panic!(
            "{} does not compile: {:?}",
            path.display(),
            compilation.diagnostics
        )
    });
    prepare(&mechanism, &[], &Settings::default())
        .unwrap_or_else(|d| panic!("{}: {:?}", path.display(), d[0].message))
}

#[allow(dead_code)]
/// 256 random states (q, v, a, τ) of `model`: q uniform in [−π, π], the rest in [−1, 1], the same
/// from run to run.
pub fn random_states(model: &Model) -> Vec<[Vec<f64>; 4]> {
    let mut random = Random(0x9E37_79B9_7F4A_7C15);
    (0..256)
        .map(|_| {
            [
                random.vector(model.nq, std::f64::consts::PI),
                random.vector(model.nv, 1.0),
                random.vector(model.nv, 1.0),
                random.vector(model.nv, 1.0),
            ]
        })
        .collect()
}

#[allow(dead_code)] // the benchmarks that print their profile
/// The profile this benchmark was built in, for its headings: `release` (Cargo's `bench`
/// profile) or `dev` (`cargo bench --profile dev`, the repository's opt-level 1 with lsdc at 2,
/// and debug assertions, which only it has).
pub fn build_profile() -> &'static str {
    if cfg!(debug_assertions) {
        "dev build"
    } else {
        "release build"
    }
}
