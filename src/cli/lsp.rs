//! `lsdc lsp`: the language server on standard input and output (`docs/editors.md`).

use std::process::ExitCode;

pub fn run() -> ExitCode {
    match lsdc::ide::server::run_stdio() {
        Ok(()) => ExitCode::SUCCESS,
        Err(error) => {
            eprintln!("error: the language server stopped: {error}");
            ExitCode::from(1)
        }
    }
}
