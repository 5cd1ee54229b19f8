//! `output name = value;`: the value evaluated once, as an expression of the state that a run
//! writes at each output, and named like the other objects of its instance (`leg[2]:tip`).

use super::elaborator::{internal, Elaborator};
use super::eval::Locals;
use super::mechanism::{NamedOutput, OutputValue};
use super::operations::{as_frame, as_scalar};
use super::value::Value;
use crate::diag::Diagnostic;
use crate::syntax::ast::OutputDecl;

impl<'c, 'w> Elaborator<'c, 'w> {
    pub(super) fn output(&mut self, output: &OutputDecl) -> Result<(), Diagnostic> {
        let mut locals = Locals::new();
        let span = output.value.span;
        let value = match self.expr(&output.value, &mut locals)? {
            Value::Vector(v) => OutputValue::Vector(v),
            Value::Matrix(m) => OutputValue::Matrix(m),
            frame @ (Value::Frame(_) | Value::Body(_)) => {
                OutputValue::Frame(as_frame(frame, span)?)
            }
            scalar @ (Value::Scalar(_) | Value::Zero | Value::One) => {
                OutputValue::Scalar(as_scalar(scalar, span)?)
            }
            _ => return Err(internal("an output that is not a quantity of the state")),
        };
        let name = self.qualified_name(&output.name.name, self.instances.current);
        if let Some(first) = self.mechanism.outputs.iter().find(|o| o.name == name) {
            return Err(Diagnostic::error(
                "E0660",
                format!("two outputs are named `{name}`"),
            )
            .primary(output.name.span, "second output of this name")
            .secondary(first.span, "first output of this name")
            .help("outputs of different files or packages share one table of columns: rename one of them"));
        }
        self.mechanism.outputs.push(NamedOutput {
            name,
            value,
            span: output.name.span,
        });
        Ok(())
    }
}
