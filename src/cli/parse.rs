//! `lsdc parse FILE`: the syntax tree of a file (for debugging the parser).

use std::path::PathBuf;
use std::process::ExitCode;

use super::shared::{err, out, usage_error};
use lsdc::diag::render;

#[derive(clap::Args)]
pub struct ParseArgs {
    file: PathBuf,
}

pub fn run(args: &ParseArgs) -> ExitCode {
    let file = &args.file;
    let text = match lsdc::load::read_source(file) {
        Ok(t) => t,
        Err(e) => return usage_error(&format!("cannot read `{}`: {e}", file.display())),
    };
    let mut sources = lsdc::source::SourceMap::new();
    let id = sources.add(file.display().to_string(), text);
    let (program, diagnostics) = lsdc::syntax::parser::parse(id, &sources.file(id).text);
    out(&lsdc::syntax::debug_tree::pretty(&format!("{program:?}")));
    out("\n");
    err(&render::to_text(&sources, &diagnostics));
    if diagnostics.is_empty() {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    }
}
