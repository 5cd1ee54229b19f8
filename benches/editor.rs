//! The language server's work on each change of a 1,000-line file: the whole file compiled
//! again with its libraries and indexed (`Analysis::new`, the values of its numeric constants
//! included), its diagnostics converted, and its semantic tokens computed, as after each
//! keystroke. Run with `cargo bench --bench editor`. Prints the thread CPU time of 30
//! repetitions, best and median, for two files: a chain of bodies, and a chain whose lengths are
//! named constants (one per body, each computed from the one before).

use std::path::Path;

use lsdc::ide::analysis::Analysis;
use lsdc::ide::convert;
use lsdc::load::LoadOptions;
use lsdc::simulate::clock::thread_cpu_seconds;

const HEADER: &str = "(* A generated chain. *)\nimport joints ;\nimport gravity ;\n";

/// About 1,000 lines: a chain of bodies on standard revolute joints, three lines per body, with
/// comments.
fn chain() -> String {
    let mut text = String::from(HEADER);
    for i in 1..=332 {
        let parent = if i == 1 {
            "earth".to_string()
        } else {
            format!("[0.5, 0, 0] ++ 1 @ b{}", i - 1)
        };
        text.push_str(&format!("let b{i} = body mass = 1.5, iframe = [0.25, 0, 0] ++ 1, inertia = [0.01, 0.02, 0.02] end ; (* link {i} *)\n"));
        text.push_str(&format!(
            "join {parent} and b{i}\n  with revolute([0, 0, 1]) as j{i} ;\n"
        ));
    }
    text
}

/// About 1,000 lines: the chain with a named length per body, four lines per body.
fn chain_with_constants() -> String {
    let mut text = String::from(HEADER);
    text.push_str("let l0 = 0.5 ;\n");
    for i in 1..=249 {
        let parent = if i == 1 {
            "earth".to_string()
        } else {
            format!("[l{}, 0, 0] ++ 1 @ b{}", i - 1, i - 1)
        };
        text.push_str(&format!(
            "let l{i} = 0.99 * l{} + 0.01 ; (* length {i} *)\n",
            i - 1
        ));
        text.push_str(&format!("let b{i} = body mass = 1.5, iframe = [l{i} / 2, 0, 0] ++ 1, inertia = [0.01, 0.02, 0.02] end ;\n"));
        text.push_str(&format!(
            "join {parent} and b{i}\n  with revolute([0, 0, 1]) as j{i} ;\n"
        ));
    }
    text
}

fn measure(name: &str, text: &str) {
    let options = LoadOptions {
        library_dirs: Vec::new(),
        use_environment: false,
        scene: None,
    };
    let path = Path::new("chain.lsd");
    let mut times = Vec::new();
    for _ in 0..30 {
        let start = thread_cpu_seconds().unwrap_or(0.0);
        let analysis = Analysis::new(path, text, &options);
        let diagnostics: Vec<_> = analysis
            .compilation
            .diagnostics
            .iter()
            .map(|d| convert::diagnostic(&analysis, d))
            .collect();
        let tokens = lsdc::ide::semantic_tokens(&analysis);
        times.push(thread_cpu_seconds().unwrap_or(0.0) - start);
        assert!(diagnostics.is_empty() && !tokens.is_empty());
    }
    times.sort_by(f64::total_cmp);
    println!(
        "{name}, {} lines: re-check, diagnostics and semantic tokens: best {:.1} ms, median {:.1} ms CPU",
        text.lines().count(),
        times[0] * 1e3,
        times[times.len() / 2] * 1e3
    );
}

fn main() {
    measure("chain", &chain());
    measure("chain with constants", &chain_with_constants());
}
