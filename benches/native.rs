//! `simulate --compiled` against the simulator's own evaluation: the right-hand side
//! (`MechanicalSystem::derivative`) with the efforts from the compiled tape and the
//! articulated-body recursion, then with the native forward dynamics (`lsdc compile --emit c`,
//! compiled by the C compiler and loaded by `compiled::attach`), at the same state, in the same
//! process. Also the seconds `compiled::attach` takes (generating, compiling with an empty cache,
//! loading, checking). Run with `cargo bench --bench native`; without a C compiler every case
//! says why it is skipped. Times are CPU times of the timing thread, best over 7 rounds.

mod common;
use common::cpu_time_per_call;
use std::hint::black_box;
use std::time::Instant;

use lsdc::driver::compile_text;
use lsdc::load::LoadOptions;
use lsdc::prepare::{prepare, Prepared, Settings};
use lsdc::simulate::compiled;
use lsdc::simulate::system::MechanicalSystem;

/// ns per call of the right-hand side at the initial state, best over 7 rounds, with the
/// native code when `native`.
fn derivative_ns(prepared: &Prepared, native: bool) -> f64 {
    let model = &prepared.model;
    let (q, v) = model
        .state_from_declared(&prepared.coordinates, &prepared.rates)
        .expect("initial state");
    let reference = prepared.coordinates.clone();
    let mut system = MechanicalSystem::new(model, reference, prepared.settings.stabilisation);
    if native {
        system.use_native(prepared.native.as_ref());
    }
    let y: Vec<f64> = q.iter().chain(&v).copied().collect();
    let mut dydt = vec![0.0; y.len()];
    let mut best = f64::INFINITY;
    for _ in 0..7 {
        let (time, _) = cpu_time_per_call(|| {
            system
                .derivative(0.1, black_box(&y), &mut dydt)
                .expect("evaluates");
        });
        best = best.min(time);
    }
    best * 1e9
}

/// (simulator ns, native ns, seconds to attach), or why the native code does not serve.
fn compare(text: &str, cache: &std::path::Path) -> Result<(f64, f64, f64), String> {
    let options = LoadOptions {
        library_dirs: Vec::new(),
        use_environment: false,
        scene: None,
    };
    let directory = Some(std::path::Path::new("examples"));
    let compilation = compile_text("bench.lsd", text, directory, &options);
    let mechanism = compilation.mechanism.ok_or("does not compile")?;
    let mut prepared =
        prepare(&mechanism, &[], &Settings::default()).map_err(|e| format!("{e:?}"))?;
    std::env::set_var("LSDC_CACHE_DIR", cache);
    let start = Instant::now();
    compiled::attach(&mut prepared, &mechanism).map_err(|why| why.to_string())?;
    let attach = start.elapsed().as_secs_f64();
    Ok((
        derivative_ns(&prepared, false),
        derivative_ns(&prepared, true),
        attach,
    ))
}

/// A planar pendulum of `n` links 1 m long about parallel axes, each with its weight.
fn pendulum(n: usize) -> String {
    let mut text = String::from("import joints ; import gravity ;\n");
    let mut parent = "earth".to_string();
    for i in 0..n {
        text += &format!(
            "let l{i} = body mass = 1, iframe = [0, -0.5, 0] ++ 1, inertia = [0.1, 0.01, 0.1] end ;\n\
             join [0, {y}, 0] ++ 1 @ {parent} and l{i} with revolute([0, 0, 1]) as j{i} ;\n\
             apply weight(l{i}) on l{i}.iframe ;\n\
             initial j{i}.q = 0.{d}, j{i}.q' = 0.1 ;\n",
            y = if i == 0 { 0.0 } else { -1.0 },
            d = i % 9 + 1,
        );
        parent = format!("l{i}");
    }
    text
}

fn main() {
    let example = |file: &str| std::fs::read_to_string(file).expect("example");
    let cases = [
        ("pendulum", example("examples/pendulum.lsd")),
        ("double pendulum", example("examples/double_pendulum.lsd")),
        ("elastic pendulum", example("examples/elastic_pendulum.lsd")),
        ("governor", example("examples/governor.lsd")),
        ("5-link pendulum", pendulum(5)),
        ("20-link pendulum", pendulum(20)),
    ];
    let cache = std::env::temp_dir().join(format!("lsdc-native-bench-{}", std::process::id()));
    println!(
        "{:<18} {:>13} {:>10} {:>8} {:>10}",
        "case", "simulator ns", "native ns", "ratio", "attach s"
    );
    for (label, text) in &cases {
        match compare(text, &cache) {
            Ok((simulator, native, attach)) => println!(
                "{label:<18} {simulator:>13.0} {native:>10.0} {:>8.3} {attach:>10.2}",
                native / simulator
            ),
            Err(why) => println!("{label:<18} skipped: {why}"),
        }
    }
    let _ = std::fs::remove_dir_all(&cache);
}
