//! Text to syntax tree: the lexer (logos), the grammar (LALRPOP, `grammar/lsd.lalrpop`) and the
//! abstract syntax with spans.

pub mod arena;
pub mod ast;
pub mod debug_tree;
pub mod lexer;
pub mod names;
pub mod nesting;
pub mod parser;
mod repair;
pub mod symbol;
