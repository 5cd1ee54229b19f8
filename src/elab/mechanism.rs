//! The elaborated mechanism: the bodies, links, joins, efforts and unknowns a program declares,
//! and the summary `lsdc check` prints.

use std::collections::{BTreeSet, HashMap};
use std::fmt::Write;

use serde::Serialize;

use super::value::*;
use crate::syntax::ast::Name;
use crate::syntax::span::Span;

#[derive(Clone, Debug)]
pub struct Body {
    /// The `let` name the body was first bound to.
    pub name: Option<Name>,
    pub span: Span,
    /// `None`: generic (the compiler names it). Likewise for `iframe` and `inertia`.
    pub mass: Option<Scalar>,
    pub iframe: Option<Displacement>,
    pub inertia: Option<Vector>,
}

/// A link: its joint coordinates, its dof chain in them, and the known link efforts.
#[derive(Clone, Debug)]
pub struct Link {
    pub name: Option<Name>,
    pub span: Span,
    pub coordinates: Vec<Name>,
    /// `dof` (one element) or `dof1`, `dof2`, … in order.
    pub dofs: Vec<Displacement>,
    /// `force`/`torque` (index 0) and `forceN`/`torqueN` (index N), vectors in the joint frame.
    pub forces: Vec<(u8, Vector)>,
    pub torques: Vec<(u8, Vector)>,
}

#[derive(Clone, Debug)]
pub struct Join {
    pub first: Frame,
    pub second: Frame,
    pub link: LinkId,
    pub span: Span,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum EffortKind {
    Force,
    Torque,
}

#[derive(Clone, Debug)]
pub struct Effort {
    pub kind: EffortKind,
    pub name: Option<Name>,
    pub span: Span,
    /// `None`: a generic vector.
    pub value: Option<Vector>,
    /// The body whose basis the vector is written in (`None`: generic, `earth`: the fixed basis).
    pub basis: Option<BodyRef>,
}

/// `apply <effort> on <frame>`; for a torque the frame is the body's reference frame.
#[derive(Clone, Debug)]
pub struct Application {
    pub effort: EffortId,
    pub target: Frame,
    pub span: Span,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum UnknownKind {
    Scalar,
    Vector,
    Function,
}

#[derive(Clone, Debug)]
pub struct Unknown {
    pub kind: UnknownKind,
    /// The `?s` occurrence that created it.
    pub span: Span,
    /// Set by `let L = ?s;`.
    pub name: Option<Name>,
}

#[derive(Clone, Debug, Default)]
pub struct Mechanism {
    pub bodies: Vec<Body>,
    pub links: Vec<Link>,
    pub joins: Vec<Join>,
    pub efforts: Vec<Effort>,
    pub applications: Vec<Application>,
    pub unknowns: Vec<Unknown>,
}

/// Counts `lsdc check` prints: only what the joins and applications reach.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Summary {
    pub bodies: usize,
    pub links: usize,
    pub joins: usize,
    pub applied_forces: usize,
    pub applied_torques: usize,
    pub unknown_scalars: usize,
    pub unknown_vectors: usize,
    pub unknown_functions: usize,
    pub body_names: Vec<String>,
}

/// Bodies, links and unknowns the joins and applications reach.
#[derive(Default)]
struct Reached {
    bodies: BTreeSet<BodyId>,
    links: BTreeSet<LinkId>,
    unknowns: BTreeSet<UnknownId>,
}

impl Reached {
    fn scalar(&mut self, s: &SExpr) {
        match s {
            SExpr::Num(_) | SExpr::Coordinate { .. } => {}
            SExpr::Unknown(id) => {
                self.unknowns.insert(*id);
            }
            SExpr::UnknownFunction(id, args) => {
                self.unknowns.insert(*id);
                args.iter().for_each(|a| self.scalar(a));
            }
            SExpr::Neg(a) => self.scalar(a),
            SExpr::Add(a, b) | SExpr::Sub(a, b) | SExpr::Mul(a, b) | SExpr::Div(a, b) | SExpr::Pow(a, b) => {
                self.scalar(a);
                self.scalar(b);
            }
            SExpr::Call(_, args) => args.iter().for_each(|a| self.scalar(a)),
        }
    }

    fn vector(&mut self, v: &Vector) {
        v.iter().for_each(|s| self.scalar(s));
    }

    fn displacement(&mut self, d: &Displacement) {
        for step in &d.0 {
            match step {
                Elementary::Translation(t) => self.vector(t),
                Elementary::Rotation { angle, axis } => {
                    self.scalar(angle);
                    self.vector(axis);
                }
            }
        }
    }

    fn body_ref(&mut self, body: BodyRef) {
        if let BodyRef::Body(id) = body {
            self.bodies.insert(id);
        }
    }

    fn frame(&mut self, frame: &Frame) {
        self.body_ref(frame.body);
        self.displacement(&frame.displacement);
    }
}

impl Mechanism {
    pub fn body(&self, id: BodyId) -> &Body {
        &self.bodies[id.0 as usize]
    }

    pub fn link(&self, id: LinkId) -> &Link {
        &self.links[id.0 as usize]
    }

    pub fn effort(&self, id: EffortId) -> &Effort {
        &self.efforts[id.0 as usize]
    }

    fn reached(&self) -> Reached {
        let mut reached = Reached::default();
        for join in &self.joins {
            reached.frame(&join.first);
            reached.frame(&join.second);
            reached.links.insert(join.link);
        }
        for application in &self.applications {
            reached.frame(&application.target);
            let effort = self.effort(application.effort);
            if let Some(v) = &effort.value {
                reached.vector(v);
            }
            if let Some(basis) = effort.basis {
                reached.body_ref(basis);
            }
        }
        for &id in &reached.bodies.clone() {
            let body = self.body(id);
            if let Some(m) = &body.mass {
                reached.scalar(m);
            }
            if let Some(d) = &body.iframe {
                reached.displacement(d);
            }
            if let Some(i) = &body.inertia {
                reached.vector(i);
            }
        }
        for &id in &reached.links.clone() {
            let link = self.link(id);
            link.dofs.iter().for_each(|d| reached.displacement(d));
            link.forces.iter().chain(&link.torques).for_each(|(_, v)| reached.vector(v));
        }
        reached
    }

    pub fn summary(&self) -> Summary {
        let reached = self.reached();
        let count = |kind| reached.unknowns.iter().filter(|id| self.unknowns[id.0 as usize].kind == kind).count();
        let applied = |kind| self.applications.iter().filter(|a| self.effort(a.effort).kind == kind).count();
        Summary {
            bodies: reached.bodies.len(),
            links: reached.links.len(),
            joins: self.joins.len(),
            applied_forces: applied(EffortKind::Force),
            applied_torques: applied(EffortKind::Torque),
            unknown_scalars: count(UnknownKind::Scalar),
            unknown_vectors: count(UnknownKind::Vector),
            unknown_functions: count(UnknownKind::Function),
            body_names: reached.bodies.iter().map(|&id| self.body_name(BodyRef::Body(id))).collect(),
        }
    }

    pub fn body_name(&self, body: BodyRef) -> String {
        match body {
            BodyRef::Earth => "earth".to_string(),
            BodyRef::Body(id) => self.body(id).name.as_deref().map_or_else(|| format!("body#{}", id.0 + 1), str::to_string),
        }
    }

    /// A canonical text form of what the joins and applications reach, with unknowns numbered in
    /// order of appearance: two programs describing the same mechanism dump the same text.
    pub fn dump(&self) -> String {
        let mut text = Dumper { mechanism: self, numbering: HashMap::new() };
        let mut out = String::new();
        for join in &self.joins {
            let link = self.link(join.link);
            let first = text.frame(&join.first);
            let second = text.frame(&join.second);
            let _ = writeln!(out, "join {first} and {second} with link({})", link.coordinates.join(", "));
            for (i, dof) in link.dofs.iter().enumerate() {
                let _ = writeln!(out, "  dof{} = {}", i + 1, text.displacement(dof));
            }
            for (label, efforts) in [("force", &link.forces), ("torque", &link.torques)] {
                for (index, v) in efforts.iter() {
                    let _ = writeln!(out, "  {label}{index} = {}", text.vector(v));
                }
            }
        }
        for application in &self.applications {
            let effort = self.effort(application.effort);
            let value = effort.value.as_ref().map_or("generic".to_string(), |v| text.vector(v));
            let basis = effort.basis.map_or("generic".to_string(), |b| self.body_name(b));
            let target = text.frame(&application.target);
            let _ = writeln!(out, "apply {:?} value {value} basis {basis} on {target}", effort.kind);
        }
        for &id in &self.reached().bodies {
            let body = self.body(id);
            let mass = body.mass.as_ref().map_or("generic".to_string(), |m| text.scalar(m));
            let iframe = body.iframe.as_ref().map_or("generic".to_string(), |d| text.displacement(d));
            let inertia = body.inertia.as_ref().map_or("generic".to_string(), |v| text.vector(v));
            let _ = writeln!(out, "body {}: mass {mass}, iframe {iframe}, inertia {inertia}", self.body_name(BodyRef::Body(id)));
        }
        out
    }
}

/// Writes values with unknowns renumbered in order of first appearance.
struct Dumper<'m> {
    mechanism: &'m Mechanism,
    numbering: HashMap<UnknownId, usize>,
}

impl Dumper<'_> {
    fn scalar(&mut self, s: &Scalar) -> String {
        let numbering = &mut self.numbering;
        let unknowns = &self.mechanism.unknowns;
        s.render(&mut |id| {
            let next = numbering.len() + 1;
            let n = *numbering.entry(id).or_insert(next);
            let prefix = if unknowns[id.0 as usize].kind == UnknownKind::Function { "f" } else { "s" };
            format!("{prefix}{n}")
        })
    }

    fn vector(&mut self, v: &Vector) -> String {
        format!("[{}, {}, {}]", self.scalar(&v[0]), self.scalar(&v[1]), self.scalar(&v[2]))
    }

    fn displacement(&mut self, d: &Displacement) -> String {
        if d.is_identity() {
            return "1".to_string();
        }
        let steps: Vec<String> = d
            .0
            .iter()
            .map(|step| match step {
                Elementary::Translation(t) => format!("T{}", self.vector(t)),
                Elementary::Rotation { angle, axis } => format!("R({}, {})", self.scalar(angle), self.vector(axis)),
            })
            .collect();
        steps.join(" ")
    }

    fn frame(&mut self, frame: &Frame) -> String {
        format!("{} @ {}", self.displacement(&frame.displacement), self.mechanism.body_name(frame.body))
    }
}
