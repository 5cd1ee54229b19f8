//! Calls one program's constrained right-hand side (or its tree's, or a projection, or a
//! right-hand side followed by the projection of the same state, as after a dopri5 step, or the
//! constrained right-hand side in the planar form of a planar mechanism) a given number of times
//! at the initial state, for an instruction counter:
//!
//! ```text
//! cargo bench --bench call_counts -- FILE [loops|planar|tree|projection|evaluated] CALLS
//! valgrind --tool=callgrind target/release/deps/call_counts-HASH FILE loops 600
//! ```
//!
//! The cost of one call is the difference of two runs' counts (600 and 100 calls, say) over the
//! difference of their calls: exact, independent of the machine's load, and without the
//! compilation and set-up both runs share. The tree is the same bodies with the closing joins
//! removed (`loop_costs::tree_model`).

use std::hint::black_box;
use std::path::PathBuf;

use lsdc::driver::compile_files;
use lsdc::load::LoadOptions;
use lsdc::prepare::{prepare, Prepared, Settings};

mod common;
#[path = "common/loop_costs.rs"]
mod loop_costs;
use loop_costs::{loop_system, tree_call, tree_model};

fn load(file: &str) -> Prepared {
    let options = LoadOptions {
        library_dirs: Vec::new(),
        use_environment: false,
        scene: None,
    };
    let compilation = compile_files(&[PathBuf::from(file)], &options).expect("the program loads");
    let mechanism = compilation.mechanism.expect("the program elaborates");
    prepare(&mechanism, &[], &Settings::default()).expect("the program prepares")
}

fn main() {
    // `cargo bench` passes `--bench` to every benchmark: the arguments are the others.
    let args: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with("--"))
        .collect();
    let [file, what, calls] = &args[..] else {
        println!("usage: call_counts FILE [loops|planar|tree|projection|evaluated] CALLS");
        return;
    };
    let calls: usize = calls.parse().expect("CALLS is a number");
    let mut prepared = load(file);
    match what.as_str() {
        "planar" => {
            prepared.take_planar().expect("the mechanism is planar");
            let (mut system, y) = loop_system(&prepared);
            system.use_planar(prepared.planar_form());
            let mut dydt = vec![0.0; y.len()];
            for _ in 0..calls {
                system
                    .derivative(0.0, black_box(&y), &mut dydt)
                    .expect("evaluates");
            }
        }
        "loops" => {
            let (mut system, y) = loop_system(&prepared);
            let mut dydt = vec![0.0; y.len()];
            for _ in 0..calls {
                system
                    .derivative(0.0, black_box(&y), &mut dydt)
                    .expect("evaluates");
            }
        }
        "projection" => {
            let (mut system, y) = loop_system(&prepared);
            for _ in 0..calls {
                let mut z = y.clone();
                black_box(system.keep_closed(0.0, &mut z).expect("projects"));
            }
        }
        "evaluated" => {
            let (mut system, y) = loop_system(&prepared);
            let mut dydt = vec![0.0; y.len()];
            for _ in 0..calls {
                let mut z = y.clone();
                system.derivative(0.0, &z, &mut dydt).expect("evaluates");
                black_box(system.keep_closed(0.0, &mut z).expect("projects"));
            }
        }
        "tree" => {
            let (tree, y) = tree_model(&prepared);
            let mut call = tree_call(&prepared, &tree, &y);
            for _ in 0..calls {
                call();
            }
        }
        other => println!("unknown mode {other}: loops, planar, tree, projection or evaluated"),
    }
}
