//! Editor support: the formatter (`lsdc fmt`) and the language server (`lsdc lsp`).

pub mod format;
pub mod server;
