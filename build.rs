//! The LSD parser is generated from `grammar/lsd.lalrpop` by LALRPOP ahead of time and checked in
//! (`src/syntax/generated/lsd.rs`), so that a build does not compile LALRPOP and its ~30 crates
//! nor run its table construction (BENCHMARKS.md, "Cold build and test"). This script only checks
//! that the checked-in parser was generated from the grammar as it is now.

#[path = "tools/grammar_stamp.rs"]
mod grammar_stamp;

const GRAMMAR: &str = "grammar/lsd.lalrpop";
const PARSER: &str = "src/syntax/generated/lsd.rs";

fn main() {
    println!("cargo:rerun-if-changed={GRAMMAR}");
    println!("cargo:rerun-if-changed={PARSER}");
    let grammar = std::fs::read(GRAMMAR).expect("the grammar is part of the source tree");
    let parser = std::fs::read_to_string(PARSER).expect("the generated parser is checked in");
    let expected = grammar_stamp::stamp_line(&grammar);
    if parser.lines().next() != Some(expected.as_str()) {
        panic!(
            "{PARSER} was not generated from the current {GRAMMAR}; regenerate it with\n    \
             cargo run --release --manifest-path tools/parser-generator/Cargo.toml"
        );
    }
}
