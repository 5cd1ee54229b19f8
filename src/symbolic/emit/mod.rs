//! The equations of motion written out: for people (`text`, `latex`), for computer algebra
//! (`sympy`, `maple`), as the expression DAG itself (`json`), and as code that evaluates them and the
//! forward dynamics (`rust`, `c`).
//!
//! Every format shares the common subexpressions the same way (`shared`): a node used more than
//! once, other than a constant or a symbol, is computed once as a temporary `x0`, `x1`, … (in
//! evaluation order); a node used once is written where it is used.

mod c;
mod code;
mod json;
mod latex;
mod maple;
mod rust;
mod shared;
mod sympy;
mod text;
mod zero_products;

pub use c::c;
pub use json::json;
pub use latex::latex;
pub use maple::maple;
pub use rust::rust;
pub use sympy::sympy;
pub use text::text;
