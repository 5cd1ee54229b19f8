//! The language server's work on each change of a 1,000-line file: the whole file compiled
//! again with its libraries and indexed (`Analysis::new`), its diagnostics converted, and its
//! semantic tokens computed, as after each keystroke. Run with `cargo bench --bench editor`.
//! Prints the thread CPU time of 30 repetitions, best and median.

use std::path::Path;

use lsdc::ide::analysis::Analysis;
use lsdc::ide::convert;
use lsdc::load::LoadOptions;
use lsdc::simulate::clock::thread_cpu_seconds;

/// About 1,000 lines: a chain of bodies on standard revolute joints, three lines per body, with
/// comments.
fn program() -> String {
    let mut text = String::from("(* A generated chain. *)\nimport joints ;\nimport gravity ;\n");
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

fn main() {
    let text = program();
    let options = LoadOptions {
        library_dirs: Vec::new(),
        use_environment: false,
    };
    let path = Path::new("chain.lsd");
    let mut times = Vec::new();
    for _ in 0..30 {
        let start = thread_cpu_seconds().unwrap_or(0.0);
        let analysis = Analysis::new(path, &text, &options);
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
        "{} lines: re-check, diagnostics and semantic tokens: best {:.1} ms, median {:.1} ms CPU",
        text.lines().count(),
        times[0] * 1e3,
        times[times.len() / 2] * 1e3
    );
}
