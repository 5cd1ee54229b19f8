//! The joins renumbered once parts are left out, and the coordinates held by locks replaced by
//! their values once the locked joints are welded: every value that names a join's coordinate
//! (`crank.q` in a law, an effort, an output) names it by its new number, or becomes the held
//! value (its rates 0). Shared expressions stay shared (rewritten once each).

use std::collections::{BTreeMap, HashMap};
use std::sync::Arc;

use crate::elab::value::{num, Frame, JoinId, SExpr, Scalar};

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
    /// The coordinates held by locks, by join (its number before renumbering): each held
    /// coordinate's index and value.
    held: BTreeMap<u32, Vec<(u32, f64)>>,
    /// The held coordinates of the link being rewritten, which it names as its own.
    own: Vec<(u32, f64)>,
}

/// A coordinate `index` (differentiated `order` times) of a chain whose coordinates `held`
/// are held: its value (`Err`), or its index among the others.
fn held_or_shifted(held: &[(u32, f64)], index: u32, order: u32) -> Result<u32, Scalar> {
    if let Some(&(_, value)) = held.iter().find(|(i, _)| *i == index) {
        return Err(num(if order == 0 { value } else { 0.0 }));
    }
    Ok(index - held.iter().filter(|(i, _)| *i < index).count() as u32)
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
            held: BTreeMap::new(),
            own: Vec::new(),
        }
    }

    /// With coordinates held by locks (see [`Renumbering::held`]).
    pub(super) fn holding(mut self, held: BTreeMap<u32, Vec<(u32, f64)>>) -> Renumbering {
        self.held = held;
        self
    }

    /// The held coordinates of the link rewritten next (none: a link not welded).
    pub(super) fn own_held(&mut self, own: Vec<(u32, f64)>) {
        // Its own coordinates mean another thing in another link.
        self.done.clear();
        self.own = own;
    }

    /// Whether a join's coordinate is held by a lock.
    pub(super) fn is_held(&self, join: JoinId, coordinate: usize) -> bool {
        let held = self.held.get(&join.0).map_or(&[][..], Vec::as_slice);
        held.iter().any(|(i, _)| *i as usize == coordinate)
    }

    /// A coordinate of a join not held, renumbered: its join's new number and its index among
    /// the join's coordinates left.
    pub(super) fn coordinate(&mut self, join: JoinId, coordinate: usize) -> (JoinId, usize) {
        let held = self.held.get(&join.0).map_or(&[][..], Vec::as_slice);
        let index = held_or_shifted(held, coordinate as u32, 0).unwrap_or(coordinate as u32);
        (self.join(join), index as usize)
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
            SExpr::JoinCoordinate { join, index, order } => {
                let held = self.held.get(&join.0).map_or(&[][..], Vec::as_slice);
                match held_or_shifted(held, *index, *order) {
                    Err(value) => return value,
                    Ok(index) => SExpr::JoinCoordinate {
                        join: self.join(*join),
                        index,
                        order: *order,
                    },
                }
            }
            SExpr::Coordinate { index, order } if !self.own.is_empty() => {
                match held_or_shifted(&self.own, *index, *order) {
                    Err(value) => return value,
                    Ok(index) => SExpr::Coordinate {
                        index,
                        order: *order,
                    },
                }
            }
            SExpr::FrameState(frame, quantity) => {
                let mut frame = (**frame).clone();
                self.frame(&mut frame);
                SExpr::FrameState(Arc::new(frame), *quantity)
            }
            other => match other.with_operands(&mut |a| self.scalar(a)) {
                Some(rewritten) => rewritten,
                None => return s.clone(),
            },
        };
        let rewritten = Arc::new(rewritten);
        self.done.insert(key, (s.clone(), rewritten.clone()));
        rewritten
    }
}
