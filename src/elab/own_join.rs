//! A join read inside its own link: `join a and b with motor(axis, 2 - 0.05 * crank.q') as
//! crank;`. The join's number is known before its link is evaluated, but not the link's
//! coordinate names: `crank.q` is first a placeholder, numbered in the order the names are read,
//! and becomes the link's own coordinate `q` once the link is built.

use std::sync::Arc;

use super::elaborator::{Elaborator, OwnJoin};
use super::value::{Displacement, Elementary, JoinId, LinkId, SExpr, Scalar, Value, Vector};
use crate::diag::Diagnostic;
use crate::source::Span;
use crate::syntax::ast::Name;

impl Elaborator<'_, '_> {
    /// `crank.q` while `crank`'s link is evaluated: a placeholder coordinate whose index is the
    /// position of `q` among the names read so far.
    pub(super) fn own_coordinate(
        &mut self,
        id: JoinId,
        coordinate: &Name,
        span: Span,
    ) -> Option<Value> {
        let own = self.own_join.as_mut().filter(|own| own.id == id)?;
        let index = match own.read.iter().position(|(name, _)| name == coordinate) {
            Some(index) => index,
            None => {
                own.read.push((*coordinate, span));
                own.read.len() - 1
            }
        };
        Some(Value::Scalar(Arc::new(SExpr::JoinCoordinate {
            join: id,
            index: index as u32,
            order: 0,
        })))
    }

    /// Once the link of the join is built: each placeholder becomes the link's coordinate of
    /// that name. A name the link does not declare is E0603.
    pub(super) fn resolve_own_coordinates(
        &mut self,
        own: OwnJoin,
        link: LinkId,
        join_span: Span,
    ) -> Result<(), Diagnostic> {
        if own.read.is_empty() {
            return Ok(());
        }
        let coordinates = &self.mechanism.link(link).coordinates;
        let mut indices = Vec::with_capacity(own.read.len());
        for (name, span) in &own.read {
            match coordinates.iter().position(|c| c == name) {
                Some(index) => indices.push(index as u32),
                None => {
                    return Err(super::eval::no_such_coordinate(
                        &own.name,
                        coordinates,
                        name,
                        *span,
                        join_span,
                    ))
                }
            }
        }
        let replace = Replacement {
            join: own.id,
            indices,
        };
        let link = &mut self.mechanism.links[link.0 as usize];
        link.dofs = link.dofs.iter().map(|d| replace.displacement(d)).collect();
        for (_, vector) in link.forces.iter_mut().chain(link.torques.iter_mut()) {
            *vector = replace.vector(vector);
        }
        link.potential = link.potential.as_ref().map(|p| replace.scalar(p));
        Ok(())
    }
}

/// Placeholders of one join's coordinates replaced by its link's coordinates.
struct Replacement {
    join: JoinId,
    /// The link's index of the coordinate of each placeholder.
    indices: Vec<u32>,
}

impl Replacement {
    fn scalar(&self, s: &Scalar) -> Scalar {
        match &**s {
            SExpr::JoinCoordinate { join, index, order } if *join == self.join => {
                Arc::new(SExpr::Coordinate {
                    index: self.indices[*index as usize],
                    order: *order,
                })
            }
            // A frame's state is geometric: it cannot hold a join's coordinate (a frame's
            // state has no operands to rewrite).
            other => {
                (other.with_operands(&mut |a| self.scalar(a))).map_or_else(|| s.clone(), Arc::new)
            }
        }
    }

    fn vector(&self, v: &Vector) -> Vector {
        v.clone().map(|s| self.scalar(&s))
    }

    fn displacement(&self, d: &Displacement) -> Displacement {
        Displacement(
            d.0.iter()
                .map(|step| match step {
                    Elementary::Translation(t) => Elementary::Translation(self.vector(t)),
                    Elementary::Rotation { angle, axis } => Elementary::Rotation {
                        angle: self.scalar(angle),
                        axis: self.vector(axis),
                    },
                })
                .collect(),
        )
    }
}
