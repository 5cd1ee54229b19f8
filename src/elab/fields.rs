//! Uniform fields: `apply F` with `F = force field = g end` gives every body of the mechanism
//! that has mass its weight m g at its centre of mass, exactly as `apply weight_in(b, g) on
//! b.iframe` would, one declaration for the whole mechanism.

use std::collections::BTreeSet;

use super::elaborator::Elaborator;
use super::mechanism::{Application, Effort, Quantity};
use super::operations::{as_vector, binary};
use super::value::{constant, BodyRef, Frame, Value};
use crate::diag::Diagnostic;
use crate::syntax::ast::BinaryOp;

impl Elaborator<'_, '_> {
    /// Expands the `apply F` of fields, once every join is known.
    pub(super) fn apply_fields(&mut self) -> Result<(), Diagnostic> {
        for (id, span) in std::mem::take(&mut self.fields) {
            let effort = self.mechanism.effort(id).clone();
            let Some(field) = effort.field.clone() else {
                return Err(Diagnostic::error("E0605", "`apply` without `on` applies a field, and this effort has none")
                    .primary(span, "no `on <frame>` here")
                    .help("apply the effort on a frame (`apply f on b.iframe`), or give a force a `field = [0, 0, -9.81]` to weigh every body"));
            };
            let joined: BTreeSet<_> = self
                .mechanism
                .joins
                .iter()
                .flat_map(|j| [j.first.body, j.second.body])
                .filter_map(|b| match b {
                    BodyRef::Body(id) => Some(id),
                    BodyRef::Earth => None,
                })
                .collect();
            for body_id in joined {
                let body = self.mechanism.body(body_id).clone();
                if constant(body.mass.value()) == Some(0.0) {
                    continue;
                }
                // The same operation as `b.mass * field` in a program.
                let weight = binary(
                    BinaryOp::Mul,
                    Value::Scalar(body.mass.value().clone()),
                    Value::Vector(field.clone()),
                    span,
                )?;
                let value = Quantity::Declared(as_vector(weight, span)?);
                self.mechanism.efforts.push(Effort {
                    value,
                    basis: BodyRef::Earth,
                    potential: None,
                    field: None,
                    ..effort.clone()
                });
                let weight_id = super::value::EffortId(self.mechanism.efforts.len() as u32 - 1);
                let target = Frame {
                    body: BodyRef::Body(body_id),
                    displacement: body.iframe.value().clone(),
                };
                self.mechanism.applications.push(Application {
                    effort: weight_id,
                    target,
                    span,
                });
            }
        }
        Ok(())
    }
}
