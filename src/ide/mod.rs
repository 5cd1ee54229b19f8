//! Editor support: the formatter (`lsdc fmt`) and the language server (`lsdc lsp`), which
//! share the compiler's front end: its lexer, parser, checker and diagnostics.

mod across;
mod actions;
pub mod analysis;
mod complete;
pub mod convert;
pub mod format;
pub mod line_diff;
mod manifest;
mod navigate;
mod outline;
pub mod server;

#[cfg(lsdc_internals)]
pub use outline::semantic_tokens;
