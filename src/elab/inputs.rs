//! `input swing.q = 0;`: the generalised effort along a joint coordinate declared an input of
//! the program, with its start value, a number (E0422); a coordinate declared an input once
//! (E0423). What reads the declarations: `lsdc export-fmu` (the unit's inputs), `lsdc
//! linearize` (the linear model's inputs), through `Mechanism::declared_inputs`.

use super::elaborator::{internal, Elaborator};
use super::eval::Locals;
use super::mechanism::DeclaredInput;
use super::operations::as_scalar;
use super::value::{constant, SExpr, Value};
use crate::diag::Diagnostic;
use crate::syntax::ast::DriveDecl;

type Result<T> = std::result::Result<T, Diagnostic>;

impl Elaborator<'_, '_> {
    pub(super) fn input_decl(&mut self, decl: &DriveDecl, locals: &mut Locals) -> Result<()> {
        let Value::Scalar(target) = self.expr(&decl.target, locals)? else {
            return Err(internal("input of a non-coordinate"));
        };
        let SExpr::JoinCoordinate { join, index, .. } = *target else {
            return Err(internal("input of a non-coordinate"));
        };
        let coordinate = index as usize;
        let value = self
            .expr(&decl.value, locals)
            .and_then(|v| as_scalar(v, decl.value.span))?;
        let Some(start) = constant(&value) else {
            return Err(Diagnostic::error("E0422", "an input's start value is a number")
                .primary(decl.value.span, "not a number known before the run")
                .help("write the effort the input holds until an importer sets it, `input swing.q = 0;`; a law of the motion or of the time is an `actuate` declaration"));
        };
        let inputs = &self.mechanism.inputs;
        if let Some(first) = inputs.iter().find(|i| i.join == join && i.coordinate == coordinate) {
            let name = self.mechanism.coordinate_name(join, coordinate);
            return Err(Diagnostic::error(
                "E0423",
                format!("`{name}` is declared an input twice"),
            )
            .primary(decl.target.span, "second declaration")
            .secondary(first.span, "first declaration")
            .help("an effort along a coordinate is one input: keep one `input` declaration"));
        }
        self.mechanism.inputs.push(DeclaredInput {
            join,
            coordinate,
            start,
            span: decl.target.span,
        });
        Ok(())
    }
}
