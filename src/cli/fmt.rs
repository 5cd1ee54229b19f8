//! `lsdc fmt PATH...`: formats LSD files in place (`docs/formatting.md`).

use std::path::PathBuf;
use std::process::ExitCode;

use super::shared::{err, out, usage_error};
use lsdc::diag::render;

#[derive(clap::Args)]
pub struct FmtArgs {
    #[arg(required = true)]
    paths: Vec<PathBuf>,
    /// Change nothing; list the files that are not formatted, each with a unified diff of what
    /// formatting would change, and fail if there are any.
    #[arg(long)]
    check: bool,
}

/// Formats each file in place, or with `--check` lists those that would change, with a diff. Exit status 1
/// when a file cannot be read or parsed, or (with `--check`) is not formatted.
pub fn run(args: &FmtArgs) -> ExitCode {
    let files = match lsdc::ide::format::lsd_files(&args.paths) {
        Ok(files) => files,
        Err(error) => return usage_error(&error),
    };
    let mut failed = false;
    for file in files {
        let text = match std::fs::read_to_string(&file) {
            Ok(text) => text,
            Err(e) => {
                err(&format!("error: cannot read `{}`: {e}\n", file.display()));
                failed = true;
                continue;
            }
        };
        let mut sources = lsdc::source::SourceMap::new();
        let id = sources.add(file.display().to_string(), text);
        let text = &sources.file(id).text;
        let formatted = match lsdc::ide::format::format(id, text) {
            Ok(formatted) => formatted,
            Err(diagnostics) => {
                err(&render::to_text(&sources, &diagnostics));
                failed = true;
                continue;
            }
        };
        if formatted == *text {
            continue;
        }
        if args.check {
            let name = file.display().to_string();
            out(&format!("{name}: not formatted\n"));
            out(&lsdc::ide::line_diff::unified(
                text,
                &formatted,
                &name,
                &format!("{name} (formatted)"),
            ));
            failed = true;
        } else if let Err(e) = std::fs::write(&file, formatted) {
            err(&format!("error: cannot write `{}`: {e}\n", file.display()));
            failed = true;
        }
    }
    if failed {
        ExitCode::from(1)
    } else {
        ExitCode::SUCCESS
    }
}
