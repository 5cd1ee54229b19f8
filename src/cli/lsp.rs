//! `lsdc lsp`: the language server on standard input and output (`docs/editors.md`).

use super::shared::err;
use std::process::ExitCode;

pub fn run() -> ExitCode {
    match lsdc::ide::server::run_stdio() {
        Ok(()) => ExitCode::SUCCESS,
        Err(error) => {
            err(&format!("error: the language server stopped: {error}\n"));
            ExitCode::from(1)
        }
    }
}
