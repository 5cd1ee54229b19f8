//! A scene compiled to the smallest model that serves it ("model only what a scene needs").
//!
//! A scene reads its outputs (`output` declarations: what `simulate`, `test` and `view` show
//! beside the kept coordinates). The parts of the mechanism that no output depends on are
//! left out before the mechanism is numbered: the groups of bodies that meet the parts read
//! only at `earth` and that no effort, law, mimic or state couples to them (`groups.rs`). The
//! reduction is exact: the equations of the groups kept are those of the full model (block
//! diagonal mass matrix, no constraint row across groups), so that their motion and the
//! outputs are the full model's to round-off (`tests/suite/scenes.rs` compares them).
//!
//! What is kept whatever the outputs: every part when the scene declares no output (its runs
//! write every coordinate), the groups with a contact or a state (other parts of a run name
//! them by number). Bodies no join reaches are never in a model; links and efforts that only
//! left-out parts use stay in the mechanism's tables, unread.

mod groups;
mod massless;
mod renumber;
mod values;

use std::collections::{BTreeMap, BTreeSet};

use super::mechanism::Mechanism;
use super::scene_model::{LeftOut, SceneModel, MASSLESS, NOT_READ};
use super::value::{BodyId, BodyRef, JoinId, LinkId};
use crate::diag::Diagnostic;
use crate::source::Span;
use groups::{Groups, Staying};
use renumber::Renumbering;

/// The bodies joins reach, and the loops: joins beyond one per body (each group hangs from
/// `earth` by a tree of joins).
fn extent(mechanism: &Mechanism) -> (usize, usize) {
    let bodies: BTreeSet<BodyId> = (mechanism.joins.iter())
        .flat_map(|j| [j.first.body, j.second.body])
        .filter_map(|b| match b {
            BodyRef::Body(id) => Some(id),
            BodyRef::Earth => None,
        })
        .collect();
    let loops = mechanism.joins.len().saturating_sub(bodies.len());
    (bodies.len(), loops)
}

/// The mechanism reduced for the scene `scene` (declared at `scene_span`), with its
/// [`SceneModel`], and the warnings (W0710) for the scene's own declarations on parts left out.
pub fn reduce(
    mut mechanism: Mechanism,
    scene: &str,
    scene_span: Option<Span>,
) -> (Mechanism, Vec<Diagnostic>) {
    let (bodies_total, loops_total) = extent(&mechanism);
    let mut model = SceneModel {
        scene: scene.to_string(),
        bodies: bodies_total,
        bodies_total,
        loops: loops_total,
        loops_total,
        left_out: Vec::new(),
        zero_efforts: leave_out_zero_efforts(&mut mechanism),
        efforts_not_chosen: mechanism.applications_not_chosen,
        welded: weld_locks(&mut mechanism),
        kinematics_only: false,
        driven_kinematics: 0,
    };
    if mechanism.outputs.is_empty() {
        mechanism.scene = Some(model);
        return (mechanism, Vec::new());
    }
    let staying = Groups::of(&mut mechanism).staying();
    let mut kept_joins: Vec<bool> = (0..mechanism.joins.len())
        .map(|j| staying.join(JoinId(j as u32)))
        .collect();
    let massless = massless::unread_subtrees(&mut mechanism, &kept_joins);
    for join in &massless.joins {
        kept_joins[join.0 as usize] = false;
    }
    if kept_joins.iter().all(|&k| k) {
        mechanism.scene = Some(model);
        return (mechanism, Vec::new());
    }
    let full = mechanism.clone();
    let kept = Kept {
        joins: kept_joins,
        staying: &staying,
        massless: &massless.bodies,
    };
    let mut left_out: BTreeMap<usize, Vec<String>> = BTreeMap::new();
    let mut massless_left_out = Vec::new();
    let mut seen = BTreeSet::new();
    for join in &mechanism.joins {
        for body in [join.first.body, join.second.body] {
            let BodyRef::Body(id) = body else { continue };
            if !seen.insert(id) {
                continue;
            }
            if !staying.body(body) {
                let group = staying.roots[id.0 as usize];
                left_out
                    .entry(group)
                    .or_default()
                    .push(mechanism.body_name(body));
            } else if massless.bodies.contains(&id) {
                massless_left_out.push(mechanism.body_name(body));
            }
        }
    }
    let warnings = scene_declarations_left_out(&mechanism, &kept, scene, scene_span);
    let mut renumbering = Renumbering::new(&kept.joins);
    let joins = std::mem::take(&mut mechanism.joins);
    mechanism.joins = (joins.into_iter().zip(&kept.joins))
        .filter_map(|(join, &kept)| kept.then_some(join))
        .collect();
    mechanism.initial.retain(|v| kept.join(v.join));
    mechanism.drives.retain(|d| kept.join(d.join));
    mechanism.actuators.retain(|a| kept.join(a.join));
    (mechanism.applications).retain(|a| kept.body(a.target.body));
    (mechanism.position_drives).retain(|d| kept.body(d.frame.body));
    (mechanism.frames).retain(|f| kept.body(f.frame.body));
    rewrite_values(&mut mechanism, &mut renumbering, &BTreeSet::new());
    if renumbering.stale {
        // Not expected (the groups couple whatever reads a join); the full model is exact.
        let mut full = full;
        full.scene = Some(model);
        return (full, warnings);
    }
    (model.bodies, model.loops) = extent(&mechanism);
    model.left_out = (left_out.into_values())
        .map(|bodies| LeftOut {
            bodies,
            reason: NOT_READ.to_string(),
        })
        .collect();
    if !massless_left_out.is_empty() {
        model.left_out.push(LeftOut {
            bodies: massless_left_out,
            reason: MASSLESS.to_string(),
        });
    }
    mechanism.scene = Some(model);
    (mechanism, warnings)
}

/// What the scene's model keeps: the joins, and the bodies of the groups staying but for the
/// massless subtrees nothing reads.
struct Kept<'s> {
    joins: Vec<bool>,
    staying: &'s Staying,
    massless: &'s BTreeSet<BodyId>,
}

impl Kept<'_> {
    fn join(&self, join: JoinId) -> bool {
        self.joins[join.0 as usize]
    }

    fn body(&self, body: BodyRef) -> bool {
        let massless = matches!(body, BodyRef::Body(id) if self.massless.contains(&id));
        self.staying.body(body) && !massless
    }
}

/// Leaves out the applications of efforts whose value is identically zero: they change no
/// equation. An effort with a potential or a field is kept (the energy report reads it).
/// Rewrites every value the mechanism's kept parts hold (each once: a value rewritten twice
/// would have its joins renumbered twice): the joins and the coordinates they name renumbered,
/// held coordinates replaced by their values. The links in `done` were rewritten already.
fn rewrite_values(mechanism: &mut Mechanism, r: &mut Renumbering, done: &BTreeSet<LinkId>) {
    let mut links = BTreeSet::new();
    for join in &mut mechanism.joins {
        r.frame(&mut join.first);
        r.frame(&mut join.second);
        links.insert(join.link);
    }
    for contact in &mut mechanism.contacts {
        r.frame(&mut contact.first);
        r.frame(&mut contact.second);
        links.insert(contact.link);
    }
    for &id in links.difference(done) {
        let link = &mut mechanism.links[id.0 as usize];
        values::link(link, &mut |s| r.in_place(s));
        if let Some(extras) = link.written_extras_mut() {
            if let Some((leader, _)) = &mut extras.mimic.leader {
                *leader = r.join(*leader);
            }
        }
    }
    for body in &mut mechanism.bodies {
        values::body(body, &mut |s| r.in_place(s));
    }
    for value in &mut mechanism.initial {
        (value.join, value.coordinate) = r.coordinate(value.join, value.coordinate);
        r.in_place(&mut value.value);
    }
    for drive in &mut mechanism.drives {
        (drive.join, drive.coordinate) = r.coordinate(drive.join, drive.coordinate);
        r.in_place(&mut drive.law);
    }
    for actuator in &mut mechanism.actuators {
        (actuator.join, actuator.coordinate) = r.coordinate(actuator.join, actuator.coordinate);
        r.in_place(&mut actuator.law);
    }
    let mut efforts = BTreeSet::new();
    for application in &mut mechanism.applications {
        r.frame(&mut application.target);
        efforts.insert(application.effort);
    }
    for &id in &efforts {
        values::effort(&mut mechanism.efforts[id.0 as usize], &mut |s| {
            r.in_place(s)
        });
    }
    for drive in &mut mechanism.position_drives {
        r.frame(&mut drive.frame);
        values::vector(&mut drive.law, &mut |s| r.in_place(s));
    }
    for state in &mut mechanism.states {
        r.in_place(&mut state.initial);
        if let Some((rate, _)) = &mut state.rate {
            r.in_place(rate);
        }
        if let Some(period) = &mut state.period {
            r.in_place(period);
        }
    }
    for (_, value, _) in &mut mechanism.given {
        r.in_place(value);
    }
    for frame in &mut mechanism.frames {
        r.frame(&mut frame.frame);
    }
    for output in &mut mechanism.outputs {
        values::output(output, &mut |s| r.in_place(s));
    }
}

/// Welds the joints the scene locks (`lock elbow.q = 0.4`): each locked coordinate replaced by
/// its value in its link (a copy) and wherever it is read, its rates by 0, so that a join
/// whose coordinates are all locked is a weld and its bodies are merged into one composite
/// body for the recursions (`dynamics::welds`). The motion is the one of the lock as a drive at
/// that value (`tests/suite/scenes.rs`). Not welded, left a drive: a lock whose value is not a
/// number, on a link with stops, a rotor, friction, a mimic or a contact, on a mimic's leader,
/// or on a coordinate something else imposes or starts (E0710 is then reported as for any
/// drive). Returns how many coordinates were welded.
fn weld_locks(mechanism: &mut Mechanism) -> usize {
    let leaders: BTreeSet<JoinId> = (mechanism.links.iter())
        .filter_map(|l| l.mimic().leader.map(|(join, _)| join))
        .collect();
    let targets = |join: JoinId, coordinate: usize| {
        let drives = mechanism.drives.iter().map(|d| (d.join, d.coordinate));
        let actuators = mechanism.actuators.iter().map(|a| (a.join, a.coordinate));
        let initial = mechanism.initial.iter().map(|v| (v.join, v.coordinate));
        (drives.chain(actuators).chain(initial))
            .filter(|&target| target == (join, coordinate))
            .count()
    };
    let mut held: BTreeMap<u32, Vec<(u32, f64)>> = BTreeMap::new();
    for drive in mechanism.drives.iter().filter(|d| d.locked) {
        let link = mechanism.link(mechanism.join(drive.join).link);
        let weldable = !link.has_extras()
            && !leaders.contains(&drive.join)
            && targets(drive.join, drive.coordinate) == 1;
        if let (Some(value), true) = (super::value::constant(&drive.law), weldable) {
            let coordinates = held.entry(drive.join.0).or_default();
            coordinates.push((drive.coordinate as u32, value));
        }
    }
    if held.is_empty() {
        return 0;
    }
    let welded_count = held.values().map(Vec::len).sum();
    let mut r = Renumbering::new(&vec![true; mechanism.joins.len()]).holding(held.clone());
    let mut welded = BTreeSet::new();
    for (&join, coordinates) in &held {
        let mut link = mechanism.link(mechanism.joins[join as usize].link).clone();
        r.own_held(coordinates.clone());
        values::link(&mut link, &mut |s| r.in_place(s));
        let mut indices: Vec<usize> = coordinates.iter().map(|&(i, _)| i as usize).collect();
        indices.sort_unstable_by(|a, b| b.cmp(a));
        for index in indices {
            link.coordinates.remove(index);
        }
        mechanism.links.push(link);
        let id = LinkId(mechanism.links.len() as u32 - 1);
        mechanism.joins[join as usize].link = id;
        welded.insert(id);
    }
    r.own_held(Vec::new());
    mechanism
        .drives
        .retain(|d| !r.is_held(d.join, d.coordinate));
    rewrite_values(mechanism, &mut r, &welded);
    welded_count
}

fn leave_out_zero_efforts(mechanism: &mut Mechanism) -> usize {
    let efforts = &mechanism.efforts;
    let zero = |id: super::value::EffortId| {
        let effort = &efforts[id.0 as usize];
        let value = effort.value.value();
        effort.value.is_declared()
            && effort.potential.is_none()
            && effort.field.is_none()
            && value.iter().all(|s| super::value::constant(s) == Some(0.0))
    };
    let before = mechanism.applications.len();
    mechanism.applications.retain(|a| !zero(a.effort));
    before - mechanism.applications.len()
}

/// W0710: a declaration of the scene itself (a drive, a lock, an initial value, an applied
/// effort) on a part left out: the user named it in this scene, so its absence from the model
/// is said, never silent.
fn scene_declarations_left_out(
    mechanism: &Mechanism,
    kept: &Kept,
    scene: &str,
    scene_span: Option<Span>,
) -> Vec<Diagnostic> {
    let Some(scene_span) = scene_span else {
        return Vec::new();
    };
    let inside = |span: Span| {
        span.file() == scene_span.file()
            && span.start() >= scene_span.start()
            && span.end() <= scene_span.end()
    };
    let mut named: Vec<(Span, String)> = Vec::new();
    let join_left_out = |join: JoinId| !kept.join(join);
    for value in mechanism.initial.iter().filter(|v| join_left_out(v.join)) {
        named.push((
            value.span,
            format!(
                "gives `{}` an initial value",
                mechanism.join_name(value.join)
            ),
        ));
    }
    for drive in mechanism.drives.iter().filter(|d| join_left_out(d.join)) {
        let what = if drive.locked { "locks" } else { "drives" };
        named.push((
            drive.span,
            format!("{what} `{}`", mechanism.join_name(drive.join)),
        ));
    }
    for actuator in mechanism.actuators.iter().filter(|a| join_left_out(a.join)) {
        named.push((
            actuator.span,
            format!("actuates `{}`", mechanism.join_name(actuator.join)),
        ));
    }
    for application in &mechanism.applications {
        if !kept.body(application.target.body) {
            let body = mechanism.body_name(application.target.body);
            named.push((application.span, format!("applies an effort on `{body}`")));
        }
    }
    named
        .into_iter()
        .filter(|(span, _)| inside(*span))
        .map(|(span, what)| {
            Diagnostic::warning(
                "W0710",
                format!("the scene `{scene}` {what}, in a part none of its outputs reads: that part is left out of its model"),
            )
            .primary(span, "left out with its part")
            .help("add an output that reads this part (`output elbow = arm.q;`), or take the declaration out of the scene")
        })
        .collect()
}
