//! Massless subtrees nothing reads: bodies of zero mass and inertia that hang from the rest of
//! the mechanism by one join (a sensor's frame, a tool's mount written as a body), with no
//! effort applied to them, no effort of their joints, no loop through them and nothing kept
//! reading their motion (no output, law, effort or drive of another part names their
//! coordinates or frames). Such a subtree adds nothing to the mass matrix, the bias or the
//! efforts of the rest, which therefore moves as if it were not there: it is left out. Its own
//! drives and initial values go with it; a free coordinate of such a subtree would make the
//! full model's mass matrix singular, so that leaving it out also lets the scene run.
//!
//! The subtrees are found by peeling leaves (a body with one join left, repeatedly), which
//! never removes a body of a loop (it keeps two joins to the end).

use std::collections::{BTreeSet, HashSet};

use super::groups::{motion_read, MotionRead};
use super::values;
use crate::elab::mechanism::{Body, Mechanism, OutputValue};
use crate::elab::value::{constant, BodyId, BodyRef, JoinId, Scalar};

/// The joins and bodies of the massless subtrees nothing reads, among the joins `kept`.
pub(super) struct Massless {
    pub(super) joins: BTreeSet<JoinId>,
    pub(super) bodies: BTreeSet<BodyId>,
}

fn is_massless(body: &Body) -> bool {
    let zero = |s: &Scalar| constant(s) == Some(0.0);
    body.mass.is_declared()
        && body.inertia.is_declared()
        && zero(body.mass.value())
        && body.inertia.value().iter().all(zero)
}

/// What must stay whatever its mass: the bodies something applies an effort on or reads the
/// frames of, and the joins something reads the coordinates of or that carry efforts.
struct Held {
    bodies: Vec<bool>,
    joins: Vec<bool>,
    seen: HashSet<*const crate::elab::value::SExpr>,
}

impl Held {
    fn body(&mut self, body: BodyRef) {
        if let BodyRef::Body(BodyId(id)) = body {
            self.bodies[id as usize] = true;
        }
    }

    fn reads(&mut self, s: &Scalar) {
        let (bodies, joins) = (&mut self.bodies, &mut self.joins);
        motion_read(s, &mut self.seen, &mut |read| match read {
            MotionRead::Join(JoinId(j)) => joins[j as usize] = true,
            MotionRead::Body(BodyId(b)) => bodies[b as usize] = true,
            MotionRead::State(_) => {}
        });
    }
}

/// The massless subtrees of the joins `kept` that nothing reads.
pub(super) fn unread_subtrees(mechanism: &mut Mechanism, kept: &[bool]) -> Massless {
    let mut held = Held {
        bodies: mechanism.bodies.iter().map(|b| !is_massless(b)).collect(),
        joins: vec![false; mechanism.joins.len()],
        seen: HashSet::new(),
    };
    for (index, join) in mechanism.joins.iter_mut().enumerate() {
        if !kept[index] {
            continue;
        }
        values::frame(&mut join.first, &mut |s| held.reads(s));
        values::frame(&mut join.second, &mut |s| held.reads(s));
        let link = &mut mechanism.links[join.link.0 as usize];
        if link.has_extras() || !link.forces.is_empty() || !link.torques.is_empty() {
            held.joins[index] = true;
        }
        if link.potential.is_some() {
            held.joins[index] = true;
        }
        if let Some((leader, _)) = link.mimic().leader {
            held.joins[leader.0 as usize] = true;
        }
        values::link(link, &mut |s| held.reads(s));
    }
    for contact in &mut mechanism.contacts {
        held.body(contact.first.body);
        held.body(contact.second.body);
        values::frame(&mut contact.first, &mut |s| held.reads(s));
        values::frame(&mut contact.second, &mut |s| held.reads(s));
    }
    for application in &mut mechanism.applications {
        held.body(application.target.body);
        values::frame(&mut application.target, &mut |s| held.reads(s));
        let effort = &mut mechanism.efforts[application.effort.0 as usize];
        held.body(effort.basis);
        values::effort(effort, &mut |s| held.reads(s));
    }
    for drive in &mechanism.drives {
        held.reads(&drive.law);
    }
    for actuator in &mechanism.actuators {
        held.joins[actuator.join.0 as usize] = true;
        held.reads(&actuator.law);
    }
    for drive in &mut mechanism.position_drives {
        held.body(drive.frame.body);
        values::frame(&mut drive.frame, &mut |s| held.reads(s));
        values::vector(&mut drive.law, &mut |s| held.reads(s));
    }
    for state in &mechanism.states {
        held.reads(&state.initial);
        if let Some((rate, _)) = &state.rate {
            held.reads(rate);
        }
        if let Some(period) = &state.period {
            held.reads(period);
        }
    }
    for output in &mut mechanism.outputs {
        if let OutputValue::Frame(frame) = &output.value {
            held.body(frame.body);
        }
        values::output(output, &mut |s| held.reads(s));
    }
    peel(mechanism, kept, &held)
}

/// Peels the leaves that are neither held nor hung by a held join, until none is left.
fn peel(mechanism: &Mechanism, kept: &[bool], held: &Held) -> Massless {
    let ends = |j: usize| {
        let join = &mechanism.joins[j];
        [join.first.body, join.second.body].map(|b| match b {
            BodyRef::Body(BodyId(id)) => Some(id as usize),
            BodyRef::Earth => None,
        })
    };
    let mut joins_of: Vec<Vec<usize>> = vec![Vec::new(); mechanism.bodies.len()];
    for j in (0..mechanism.joins.len()).filter(|&j| kept[j]) {
        let [first, second] = ends(j);
        if first == second {
            continue;
        }
        for body in [first, second].into_iter().flatten() {
            joins_of[body].push(j);
        }
    }
    let mut removed_joins = BTreeSet::new();
    let mut removed_bodies = BTreeSet::new();
    let mut leaves: Vec<usize> = (0..joins_of.len())
        .filter(|&b| joins_of[b].len() == 1)
        .collect();
    while let Some(body) = leaves.pop() {
        let remaining: Vec<usize> = (joins_of[body].iter().copied())
            .filter(|j| !removed_joins.contains(&JoinId(*j as u32)))
            .collect();
        let [join] = remaining[..] else {
            continue;
        };
        if held.bodies[body] || held.joins[join] || removed_bodies.contains(&BodyId(body as u32)) {
            continue;
        }
        removed_joins.insert(JoinId(join as u32));
        removed_bodies.insert(BodyId(body as u32));
        let [first, second] = ends(join);
        let other = if first == Some(body) { second } else { first };
        if let Some(other) = other {
            let left = (joins_of[other].iter())
                .filter(|j| !removed_joins.contains(&JoinId(**j as u32)))
                .count();
            if left == 1 {
                leaves.push(other);
            }
        }
    }
    Massless {
        joins: removed_joins,
        bodies: removed_bodies,
    }
}
