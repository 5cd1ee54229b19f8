//! Symbolic expressions for the equations of motion: a hash-consed expression DAG (`expr`),
//! where equal subexpressions are one node, and its evaluation in topological order (`Tape`), the
//! form code emitters walk.

pub mod expr;
