//! `input`: the program's inputs, each with its start value, a number (E0422), which an
//! importer, a caller stepping the run or a study sets, and which every run holds at its start
//! value until set. `input swing.q = 0;` declares the generalised effort along a joint
//! coordinate an input (a coordinate declared an input once, E0423); `input voltage = 0;`
//! declares a value, the scalar `voltage` that expressions after it read: a state held at its
//! start value (its rate zero) until set, read through the same slot as any state's value.
//! What reads the declarations: the runs (`Simulator`), `lsdc export-fmu` (the unit's inputs),
//! `lsdc linearize` (the linear model's inputs), through `Mechanism::declared_inputs` and the
//! states marked `input`.

use std::sync::Arc;

use super::elaborator::{internal, Elaborator, Global};
use super::eval::Locals;
use super::mechanism::{DeclaredInput, StateVariable};
use super::operations::as_scalar;
use super::value::{constant, num, SExpr, StateId, Value};
use crate::check::scope::ScopeId;
use crate::diag::Diagnostic;
use crate::syntax::ast::{DriveDecl, Ident};

type Result<T> = std::result::Result<T, Diagnostic>;

impl Elaborator<'_, '_> {
    pub(super) fn input_decl(
        &mut self,
        decl: &DriveDecl,
        scope: ScopeId,
        locals: &mut Locals,
    ) -> Result<()> {
        let start = self.start_value(decl, locals)?;
        if let Some(name) = decl.value_input_name() {
            return self.value_input(&name, start, scope);
        }
        let Value::Scalar(target) = self.expr(&decl.target, locals)? else {
            return Err(internal("input of a non-coordinate"));
        };
        let SExpr::JoinCoordinate { join, index, .. } = *target else {
            return Err(internal("input of a non-coordinate"));
        };
        let coordinate = index as usize;
        let inputs = &self.mechanism.inputs;
        if let Some(first) = inputs
            .iter()
            .find(|i| i.join == join && i.coordinate == coordinate)
        {
            let name = self.mechanism.coordinate_name(join, coordinate);
            return Err(
                Diagnostic::error("E0423", format!("`{name}` is declared an input twice"))
                    .primary(decl.target.span, "second declaration")
                    .secondary(first.span, "first declaration")
                    .help(
                        "an effort along a coordinate is one input: keep one `input` declaration",
                    ),
            );
        }
        self.mechanism.inputs.push(DeclaredInput {
            join,
            coordinate,
            start,
            span: decl.target.span,
        });
        Ok(())
    }

    /// The start value of an input, a number known before the run (E0422).
    fn start_value(&mut self, decl: &DriveDecl, locals: &mut Locals) -> Result<f64> {
        let value = self
            .expr(&decl.value, locals)
            .and_then(|v| as_scalar(v, decl.value.span))?;
        constant(&value).ok_or_else(|| {
            let example = match decl.value_input_name() {
                Some(name) => format!("`input {} = 0;`", name.name),
                None => "`input swing.q = 0;`".to_string(),
            };
            Diagnostic::error("E0422", "an input's start value is a number")
                .primary(decl.value.span, "not a number known before the run")
                .help(format!("write the value the input holds until it is set, {example}; a law of the motion or of the time is an `actuate` declaration or a `let`"))
        })
    }

    /// `input voltage = start`: a state held at `start` (its rate zero) until the run's caller
    /// sets it, named `voltage` (with its instance, `motor[2]:voltage`), bound in its scope
    /// from here on.
    fn value_input(&mut self, name: &Ident, start: f64, scope: ScopeId) -> Result<()> {
        let instance = self.instance_of(scope)?;
        let id = StateId(self.mechanism.states.len() as u32);
        self.mechanism.states.push(StateVariable {
            name: Some(self.qualified_name(&name.name, instance)),
            initial: num(start),
            rate: Some((num(0.0), name.span)),
            period: None,
            span: name.span,
            input: true,
        });
        let value = Value::Scalar(Arc::new(SExpr::State(id)));
        let key = (scope, instance, name.name);
        self.globals.insert(key, Global::Ready(value));
        Ok(())
    }
}
