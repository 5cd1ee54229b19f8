//! `simulate --compiled` against the simulator's own evaluation: the right-hand side
//! (`MechanicalSystem::derivative`) with the efforts from the compiled tape and the
//! articulated-body recursion, then with the native forward dynamics (`lsdc compile --emit c`,
//! compiled by the C compiler and loaded by `compiled::attach`), at the same state, in the same
//! process. Also the seconds `compiled::attach` takes (generating, compiling with an empty cache,
//! loading, checking). Run with `cargo bench --bench native`; without a C compiler every case
//! says why it is skipped. Times are CPU times of the timing thread, the interpreted and the
//! native evaluation in interleaved rounds (7), best and median. Beside the trees: the row of 10
//! four-bars (loops solved on the kept rows in the native code, `kept_rows_solve`), the same row
//! without its closing joins (the tree alone: what the interpreted right-hand side spends
//! outside the loops' solve), the reduced Delta (its universal joints' loops solved with P1's
//! coordinates pivoted on kept rows, M being singular on its tree), the Delta (its ball joints
//! in the simulator's quaternion state, its rods' spins held at rest as the run holds them),
//! and two trees of quaternion states: a free body and a heavy top. Words after `--` keep only
//! the cases whose label holds one of them (`cargo bench --bench native -- Delta`).

mod common;
#[path = "common/rows.rs"]
mod rows;
use common::{cpu_time_per_call, median};
use rows::row_program;
use std::hint::black_box;
use std::time::Instant;

use lsdc::driver::compile_text;
use lsdc::load::LoadOptions;
use lsdc::prepare::{prepare, Prepared, Settings};
use lsdc::simulate::compiled;
use lsdc::simulate::system::MechanicalSystem;

/// The right-hand side at the run's start (the loops closed) without and with the native code,
/// in interleaved rounds: ns per call, (best, median) of each.
fn derivative_ns(prepared: &Prepared) -> [(f64, f64); 2] {
    let model = &prepared.model;
    let (q, v) = model
        .state_from_declared(&prepared.coordinates, &prepared.rates)
        .expect("initial state");
    let mut y: Vec<f64> = q.iter().chain(&v).copied().collect();
    let system = |native: bool| {
        let reference = prepared.coordinates.clone();
        let mut system = MechanicalSystem::new(model, reference, prepared.settings.stabilisation);
        system.use_planar(prepared.planar_form());
        if native {
            system.use_native(prepared.native.as_ref());
        }
        system
    };
    let mut systems = [system(false), system(true)];
    systems[0].start_loops(&mut y).expect("closes");
    for s in &mut systems {
        let mut start = y.clone();
        s.start_loops(&mut start).expect("closes");
    }
    let mut dydt = vec![0.0; y.len()];
    let mut rounds = [Vec::new(), Vec::new()];
    for _ in 0..7 {
        for (system, times) in systems.iter_mut().zip(&mut rounds) {
            let (time, _) = cpu_time_per_call(|| {
                system
                    .derivative(0.1, black_box(&y), &mut dydt)
                    .expect("evaluates");
            });
            times.push(time * 1e9);
        }
    }
    rounds.map(|times| {
        (
            times.iter().copied().fold(f64::INFINITY, f64::min),
            median(times),
        )
    })
}

/// The program `text` prepared, or why not.
fn prepared(text: &str) -> Result<(lsdc::elab::mechanism::Mechanism, Prepared), String> {
    let options = LoadOptions {
        library_dirs: Vec::new(),
        use_environment: false,
        scene: None,
    };
    let directory = Some(std::path::Path::new("examples"));
    let compilation = compile_text("bench.lsd", text, directory, &options);
    let mechanism = compilation.mechanism.ok_or("does not compile")?;
    let prepared = prepare(&mechanism, &[], &Settings::default()).map_err(|e| format!("{e:?}"))?;
    Ok((mechanism, prepared))
}

/// (simulator ns, native ns as (best, median), seconds to attach), or why the native code does
/// not serve.
fn compare(text: &str, cache: &std::path::Path) -> Result<([(f64, f64); 2], f64), String> {
    let (mechanism, mut prepared) = prepared(text)?;
    std::env::set_var("LSDC_CACHE_DIR", cache);
    let start = Instant::now();
    compiled::attach(&mut prepared, &mechanism).map_err(|why| why.to_string())?;
    let attach = start.elapsed().as_secs_f64();
    Ok((derivative_ns(&prepared), attach))
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
        ("four-bar", example("examples/four_bar.lsd")),
        ("row of 10 four-bars", row_program(10, true)),
        ("row of 40 four-bars", row_program(40, true)),
        (
            "Delta, reduced",
            example("examples/delta_isir88_reduced.lsd"),
        ),
        ("Delta (ISIR88)", example("examples/delta_isir88.lsd")),
        ("free body", example("examples/free_body.lsd")),
        ("heavy top", example("examples/heavy_top.lsd")),
    ];
    // `cargo bench --bench native -- WORD...`: only the cases whose label holds one of the words.
    let asked: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with("--"))
        .collect();
    let wanted =
        |label: &str| asked.is_empty() || asked.iter().any(|word| label.contains(word.as_str()));
    let cache = std::env::temp_dir().join(format!("lsdc-native-bench-{}", std::process::id()));
    println!(
        "{:<20} {:>19} {:>19} {:>14} {:>9}",
        "case", "simulator ns", "native ns", "ratio", "attach s"
    );
    println!(
        "{:<20} {:>9} {:>9} {:>9} {:>9} {:>6} {:>7}",
        "", "best", "median", "best", "median", "best", "median"
    );
    for (label, text) in cases.iter().filter(|(label, _)| wanted(label)) {
        match compare(text, &cache) {
            Ok(([(simulator, simulator_median), (native, native_median)], attach)) => println!(
                "{label:<20} {simulator:>9.0} {simulator_median:>9.0} {native:>9.0} {native_median:>9.0} {:>6.3} {:>7.3} {attach:>9.2}",
                native / simulator,
                native_median / simulator_median,
            ),
            Err(why) => println!("{label:<20} skipped: {why}"),
        }
    }
    // The row without its closing joins: the interpreted tree alone, what a native tree under
    // the loops' interpreted solve could at best save of the row's right-hand side.
    let open_row = wanted("row of 10, open")
        .then(|| prepared(&row_program(10, false)).ok())
        .flatten();
    if let Some((_, prepared)) = open_row {
        let [(open, open_median), _] = derivative_ns(&prepared);
        println!(
            "{:<20} {open:>9.0} {open_median:>9.0}   (interpreted, the tree alone)",
            "row of 10, open"
        );
    }
    let _ = std::fs::remove_dir_all(&cache);
}
