//! Regenerates the LSD parser: runs LALRPOP on `grammar/lsd.lalrpop` and writes
//! `src/syntax/generated/lsd.rs`, stamped with the grammar's hash that lsdc's `build.rs` checks.
//! Run it after editing the grammar:
//!
//!     cargo run --release --manifest-path tools/parser-generator/Cargo.toml

use std::path::{Path, PathBuf};

#[path = "../../grammar_stamp.rs"]
mod grammar_stamp;

fn main() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let grammar = root.join("grammar/lsd.lalrpop");
    let scratch = std::env::temp_dir().join(format!("lsdc-parser-{}", std::process::id()));
    std::fs::create_dir_all(&scratch).expect("a scratch directory");
    lalrpop::Configuration::new()
        .set_in_dir(root.join("grammar"))
        .set_out_dir(&scratch)
        .force_build(true)
        .process()
        .expect("the LSD grammar must build");
    let generated = std::fs::read_to_string(scratch.join("lsd.rs")).expect("LALRPOP wrote lsd.rs");
    let text = std::fs::read(&grammar).expect("the grammar is readable");
    let target: PathBuf = root.join("src/syntax/generated/lsd.rs");
    let stamped = format!("{}\n{generated}", grammar_stamp::stamp_line(&text));
    std::fs::write(&target, stamped).expect("the generated parser is writable");
    std::fs::remove_dir_all(&scratch).ok();
    println!("wrote {}", target.display());
}
