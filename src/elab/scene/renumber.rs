//! The joins renumbered once parts are left out: every value that names a join's coordinate
//! (`crank.q` in a law, an effort, an output) names it by its new number. Shared expressions
//! stay shared (rewritten once each).

use std::collections::HashMap;
use std::sync::Arc;

use crate::elab::value::{Applied, Frame, JoinId, SExpr, Scalar};

use super::values;

pub(super) struct Renumbering {
    /// The new number of each join, `None` for a join left out.
    new: Vec<Option<u32>>,
    /// Each expression rewritten, by address, with the original kept alive so that its
    /// address is not given to another expression while the map is in use.
    done: HashMap<*const SExpr, (Scalar, Scalar)>,
    /// A value of a kept part named a join left out: the reduction is then not made (the
    /// groups make this impossible; checked rather than assumed).
    pub(super) stale: bool,
}

impl Renumbering {
    pub(super) fn new(kept: &[bool]) -> Renumbering {
        let mut next = 0;
        let new = (kept.iter())
            .map(|&k| {
                k.then(|| {
                    next += 1;
                    next - 1
                })
            })
            .collect();
        Renumbering {
            new,
            done: HashMap::new(),
            stale: false,
        }
    }

    pub(super) fn join(&mut self, join: JoinId) -> JoinId {
        match self.new.get(join.0 as usize).copied().flatten() {
            Some(new) => JoinId(new),
            None => {
                self.stale = true;
                join
            }
        }
    }

    pub(super) fn frame(&mut self, frame: &mut Frame) {
        values::frame(frame, &mut |s| *s = self.scalar(s));
    }

    pub(super) fn in_place(&mut self, s: &mut Scalar) {
        *s = self.scalar(s);
    }

    pub(super) fn scalar(&mut self, s: &Scalar) -> Scalar {
        let key = Arc::as_ptr(s);
        if let Some((_, done)) = self.done.get(&key) {
            return done.clone();
        }
        let rewritten = match &**s {
            SExpr::JoinCoordinate { join, index, order } => SExpr::JoinCoordinate {
                join: self.join(*join),
                index: *index,
                order: *order,
            },
            SExpr::Neg(a) => SExpr::Neg(self.scalar(a)),
            SExpr::Add(a, b) => SExpr::Add(self.scalar(a), self.scalar(b)),
            SExpr::Sub(a, b) => SExpr::Sub(self.scalar(a), self.scalar(b)),
            SExpr::Mul(a, b) => SExpr::Mul(self.scalar(a), self.scalar(b)),
            SExpr::Div(a, b) => SExpr::Div(self.scalar(a), self.scalar(b)),
            SExpr::Pow(a, b) => SExpr::Pow(self.scalar(a), self.scalar(b)),
            SExpr::Call(call) => SExpr::Call(Box::new(Applied {
                function: call.function,
                args: call.args.iter().map(|a| self.scalar(a)).collect(),
            })),
            SExpr::UnknownFunction(call) => SExpr::UnknownFunction(Box::new(Applied {
                function: call.function,
                args: call.args.iter().map(|a| self.scalar(a)).collect(),
            })),
            SExpr::FrameState(frame, quantity) => {
                let mut frame = (**frame).clone();
                self.frame(&mut frame);
                SExpr::FrameState(Arc::new(frame), *quantity)
            }
            SExpr::Num(_)
            | SExpr::Time
            | SExpr::Unknown(_)
            | SExpr::Coordinate { .. }
            | SExpr::State(_) => return s.clone(),
        };
        let rewritten = Arc::new(rewritten);
        self.done.insert(key, (s.clone(), rewritten.clone()));
        rewritten
    }
}
