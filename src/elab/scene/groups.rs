//! The independent parts of a mechanism: bodies joined to one another, or coupled by an effort,
//! a mimic, a law or a state that reads another part's motion, belong to one group. `earth` is
//! fixed and belongs to none: groups that meet only at `earth` move independently, as the
//! equations of motion of a forest of subtrees of `earth` are independent blocks (the mass
//! matrix is block diagonal and no constraint row spans two blocks), so that leaving one out
//! changes nothing in another's motion.

use std::collections::{BTreeSet, HashSet};
use std::sync::Arc;

use crate::elab::mechanism::{Mechanism, OutputValue};
use crate::elab::value::{BodyId, BodyRef, Frame, JoinId, SExpr, Scalar};

use super::values;

/// The bodies (nodes `0..n`) and the states (nodes `n..`) in groups, with the nodes whose
/// groups must stay: what the outputs read, and the parts that cannot be left out (contacts,
/// states: other parts of the run refer to them by number).
pub(super) struct Groups {
    parent: Vec<usize>,
    bodies: usize,
    /// The node each join hangs from: its first body other than `earth` (`None`: a join of
    /// `earth` to itself).
    join_anchors: Vec<Option<usize>>,
    pub(super) kept: Vec<usize>,
}

/// What a value reads of the motion (joins' coordinates, frames' states, states) as nodes,
/// and the expressions already read (they are shared: a law's subexpressions are read once).
#[derive(Default)]
struct Reads(Vec<usize>, HashSet<*const SExpr>);

impl Groups {
    /// Groups the mechanism's parts and marks those the scene reads (its outputs).
    pub(super) fn of(mechanism: &mut Mechanism) -> Groups {
        let bodies = mechanism.bodies.len();
        let node = |b: BodyRef| match b {
            BodyRef::Earth => None,
            BodyRef::Body(BodyId(id)) => Some(id as usize),
        };
        let join_anchors = (mechanism.joins.iter())
            .map(|j| node(j.first.body).or(node(j.second.body)))
            .collect();
        let mut groups = Groups {
            parent: (0..bodies + mechanism.states.len()).collect(),
            bodies,
            join_anchors,
            kept: Vec::new(),
        };
        for index in 0..mechanism.joins.len() {
            let join = &mut mechanism.joins[index];
            let (first, second) = (node(join.first.body), node(join.second.body));
            let mut reads = Reads::default();
            reads.frame(&mut join.first, &groups);
            reads.frame(&mut join.second, &groups);
            let link = &mut mechanism.links[join.link.0 as usize];
            values::link(link, &mut |s| reads.scalar(s, &groups));
            if let Some((leader, _)) = link.mimic().leader {
                reads.join(leader, &groups);
            }
            reads.0.extend(second);
            groups.couple(first.or(second), reads);
        }
        for index in 0..mechanism.contacts.len() {
            let contact = &mut mechanism.contacts[index];
            let (first, second) = (node(contact.first.body), node(contact.second.body));
            let mut reads = Reads::default();
            reads.frame(&mut contact.first, &groups);
            reads.frame(&mut contact.second, &groups);
            values::link(&mut mechanism.links[contact.link.0 as usize], &mut |s| {
                reads.scalar(s, &groups)
            });
            reads.0.extend(second);
            let anchor = first.or(second);
            groups.kept.extend(anchor);
            groups.couple(anchor, reads);
        }
        for index in 0..mechanism.applications.len() {
            let application = &mut mechanism.applications[index];
            let mut reads = Reads::default();
            reads.frame(&mut application.target, &groups);
            let effort = &mut mechanism.efforts[application.effort.0 as usize];
            values::effort(effort, &mut |s| reads.scalar(s, &groups));
            reads.0.extend(node(effort.basis));
            groups.couple(node(application.target.body), reads);
        }
        for index in 0..mechanism.drives.len() {
            let drive = &mut mechanism.drives[index];
            let mut reads = Reads::default();
            reads.scalar(&drive.law, &groups);
            groups.couple(groups.join_anchor(drive.join), reads);
        }
        for index in 0..mechanism.actuators.len() {
            let actuator = &mut mechanism.actuators[index];
            let mut reads = Reads::default();
            reads.scalar(&actuator.law, &groups);
            groups.couple(groups.join_anchor(actuator.join), reads);
        }
        for index in 0..mechanism.position_drives.len() {
            let drive = &mut mechanism.position_drives[index];
            let mut reads = Reads::default();
            reads.frame(&mut drive.frame, &groups);
            values::vector(&mut drive.law, &mut |s| reads.scalar(s, &groups));
            groups.couple(node(drive.frame.body), reads);
        }
        for index in 0..mechanism.states.len() {
            let state = &mechanism.states[index];
            let mut reads = Reads::default();
            reads.scalar(&state.initial, &groups);
            if let Some((rate, _)) = &state.rate {
                reads.scalar(rate, &groups);
            }
            if let Some(period) = &state.period {
                reads.scalar(period, &groups);
            }
            let state_node = bodies + index;
            groups.kept.push(state_node);
            groups.couple(Some(state_node), reads);
        }
        for index in 0..mechanism.outputs.len() {
            let output = &mut mechanism.outputs[index];
            let mut reads = Reads::default();
            if let OutputValue::Frame(frame) = &output.value {
                reads.0.extend(node(frame.body));
            }
            values::output(output, &mut |s| reads.scalar(s, &groups));
            groups.kept.extend(reads.0);
        }
        groups
    }

    /// The node a join hangs from.
    fn join_anchor(&self, join: JoinId) -> Option<usize> {
        self.join_anchors.get(join.0 as usize).copied().flatten()
    }

    /// The group of a node.
    fn find(&mut self, mut node: usize) -> usize {
        while self.parent[node] != node {
            self.parent[node] = self.parent[self.parent[node]];
            node = self.parent[node];
        }
        node
    }

    /// Puts `anchor` and everything `reads` names in one group. A part that hangs from no body
    /// (an effort on `earth` that reads a coordinate) keeps what it reads.
    fn couple(&mut self, anchor: Option<usize>, reads: Reads) {
        let Some(anchor) = anchor else {
            self.kept.extend(reads.0);
            return;
        };
        for read in reads.0 {
            let (a, b) = (self.find(anchor), self.find(read));
            self.parent[a] = b;
        }
    }

    /// Which nodes stay, by node: those in the group of a node kept.
    pub(super) fn staying(mut self) -> Staying {
        let roots: Vec<usize> = (0..self.parent.len()).map(|n| self.find(n)).collect();
        let kept: BTreeSet<usize> = self.kept.iter().map(|&n| roots[n]).collect();
        Staying {
            stays: roots.iter().map(|r| kept.contains(r)).collect(),
            roots,
            join_anchors: self.join_anchors,
        }
    }
}

/// The groups decided: which nodes stay and each node's group.
pub(super) struct Staying {
    stays: Vec<bool>,
    pub(super) roots: Vec<usize>,
    join_anchors: Vec<Option<usize>>,
}

impl Staying {
    pub(super) fn body(&self, body: BodyRef) -> bool {
        match body {
            BodyRef::Earth => true,
            BodyRef::Body(BodyId(id)) => self.stays[id as usize],
        }
    }

    /// Whether a join stays: it hangs from a body that stays (or from none).
    pub(super) fn join(&self, join: JoinId) -> bool {
        let anchor = self.join_anchors.get(join.0 as usize).copied().flatten();
        anchor.is_none_or(|a| self.stays[a])
    }
}

impl Reads {
    fn join(&mut self, join: JoinId, groups: &Groups) {
        self.0.extend(groups.join_anchor(join));
    }

    fn frame(&mut self, frame: &mut Frame, groups: &Groups) {
        values::frame(frame, &mut |s| self.scalar(s, groups));
    }

    /// What a scalar reads: the joins whose coordinates it names, the bodies whose frames'
    /// states it reads, the states.
    fn scalar(&mut self, s: &Scalar, groups: &Groups) {
        motion_read(s, &mut self.1, &mut |read| match read {
            MotionRead::Join(join) => self.0.extend(groups.join_anchor(join)),
            MotionRead::Body(BodyId(id)) => self.0.push(id as usize),
            MotionRead::State(id) => self.0.push(groups.bodies + id as usize),
        });
    }
}

/// A part of the motion a value reads.
#[derive(Clone, Copy)]
pub(super) enum MotionRead {
    /// A join's coordinate or rate (`crank.q`, `crank.q'`).
    Join(JoinId),
    /// The state of a frame of a body (`position(arm.tip)`).
    Body(BodyId),
    /// A state (`state i = ...`), by index.
    State(u32),
}

/// Calls `found` with what a scalar reads of the motion; the expressions in `seen` are not
/// read again (a law's subexpressions are shared).
pub(super) fn motion_read(
    s: &Scalar,
    seen: &mut HashSet<*const SExpr>,
    found: &mut dyn FnMut(MotionRead),
) {
    if !seen.insert(Arc::as_ptr(s)) {
        return;
    }
    match &**s {
        SExpr::JoinCoordinate { join, .. } => found(MotionRead::Join(*join)),
        SExpr::FrameState(frame, _) => {
            if let BodyRef::Body(id) = frame.body {
                found(MotionRead::Body(id));
            }
            let mut frame = (**frame).clone();
            values::frame(&mut frame, &mut |s| motion_read(s, seen, found));
        }
        SExpr::State(id) => found(MotionRead::State(id.0)),
        SExpr::Neg(a) => motion_read(a, seen, found),
        SExpr::Add(a, b)
        | SExpr::Sub(a, b)
        | SExpr::Mul(a, b)
        | SExpr::Div(a, b)
        | SExpr::Pow(a, b) => {
            motion_read(a, seen, found);
            motion_read(b, seen, found);
        }
        SExpr::Call(_) | SExpr::UnknownFunction(_) => s
            .arguments()
            .iter()
            .for_each(|a| motion_read(a, seen, found)),
        SExpr::Num(_) | SExpr::Time | SExpr::Unknown(_) | SExpr::Coordinate { .. } => {}
    }
}
