//! The graph of bodies and joins, its breadth-first spanning tree from `earth`, the numbering of
//! bodies and links (Papegay 1992, §3.2.4), and the split into principal (tree) and complementary
//! (loop-closing) links.
//!
//! Numbering: bodies are numbered 1..n in the order the breadth-first search discovers them;
//! from each body the search follows its joins in declaration order. The principal link reaching
//! body j is numbered j and comes from a parent numbered below j. A join met when both its bodies
//! are already discovered is complementary; complementary links are numbered n+1, n+2, … in
//! declaration order.

use std::collections::{HashMap, VecDeque};

pub mod notation;

use serde::Serialize;

use crate::diag::Diagnostic;
use crate::elab::mechanism::Mechanism;
use crate::elab::value::{BodyId, BodyRef, JoinId};

/// `earth` is vertex 0 of the graph.
pub const EARTH: usize = 0;

/// A principal link: the join through which the search reached body `child`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TreeLink {
    #[serde(skip)]
    pub join: JoinId,
    /// Number of the link, equal to `child`.
    pub number: usize,
    pub parent: usize,
    pub child: usize,
    /// Whether the join's first frame is on the parent (otherwise the link is traversed in
    /// reverse: its dof chain carries the child's frame onto the parent's).
    pub first_on_parent: bool,
}

/// A complementary link: a join that closes a loop.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LoopLink {
    #[serde(skip)]
    pub join: JoinId,
    /// n+1, n+2, …
    pub number: usize,
    /// Body numbers of the join's first and second frames.
    pub first: usize,
    pub second: usize,
}

#[derive(Clone, Debug)]
pub struct Topology {
    /// `bodies[j - 1]` is body number j.
    pub bodies: Vec<BodyId>,
    pub number_of: HashMap<BodyId, usize>,
    /// `principal[j - 1]` reaches body j.
    pub principal: Vec<TreeLink>,
    pub complementary: Vec<LoopLink>,
}

impl Topology {
    pub fn body_count(&self) -> usize {
        self.bodies.len()
    }

    /// Number of a body (0 for `earth`).
    pub fn number(&self, body: BodyRef) -> usize {
        match body {
            BodyRef::Earth => EARTH,
            BodyRef::Body(id) => self.number_of[&id],
        }
    }

    /// Parent number of body j (0 for earth).
    pub fn parent(&self, j: usize) -> usize {
        self.principal[j - 1].parent
    }

    /// Bodies from `j` up to (and excluding) earth.
    pub fn path_to_earth(&self, mut j: usize) -> Vec<usize> {
        let mut path = Vec::new();
        while j != EARTH {
            path.push(j);
            j = self.parent(j);
        }
        path
    }
}

fn vertex(body: BodyRef, index: &HashMap<BodyId, usize>) -> usize {
    match body {
        BodyRef::Earth => EARTH,
        BodyRef::Body(id) => index[&id],
    }
}

/// Builds the spanning tree. Errors: a join of a body with itself, a body not connected to earth.
pub fn build(mechanism: &Mechanism) -> Result<Topology, Vec<Diagnostic>> {
    // Vertices: earth, then every body a join or an application mentions, in first-mention order.
    let mut vertex_of: HashMap<BodyId, usize> = HashMap::new();
    let mut vertices: Vec<BodyId> = Vec::new();
    let mut mention = |body: BodyRef, vertex_of: &mut HashMap<BodyId, usize>| {
        if let BodyRef::Body(id) = body {
            vertex_of.entry(id).or_insert_with(|| {
                vertices.push(id);
                vertices.len()
            });
        }
    };
    for join in &mechanism.joins {
        mention(join.first.body, &mut vertex_of);
        mention(join.second.body, &mut vertex_of);
    }
    for application in &mechanism.applications {
        mention(application.target.body, &mut vertex_of);
    }
    let mut errors = Vec::new();
    let mut incident: Vec<Vec<(JoinId, usize)>> = vec![Vec::new(); vertices.len() + 1];
    for (index, join) in mechanism.joins.iter().enumerate() {
        let id = JoinId(index as u32);
        let (a, b) = (
            vertex(join.first.body, &vertex_of),
            vertex(join.second.body, &vertex_of),
        );
        if a == b {
            errors.push(self_join(mechanism, id));
            continue;
        }
        incident[a].push((id, b));
        incident[b].push((id, a));
    }
    if !errors.is_empty() {
        return Err(errors);
    }
    let (order, tree, loops) = breadth_first(&incident);
    for (v, &id) in vertices.iter().enumerate() {
        if !order.contains(&(v + 1)) {
            errors.push(not_connected(mechanism, id));
        }
    }
    if !errors.is_empty() {
        return Err(errors);
    }
    Ok(number(
        mechanism, &vertices, &vertex_of, &order, &tree, loops,
    ))
}

/// The tree edge reaching each vertex, with its parent vertex.
pub type TreeEdges = HashMap<usize, (JoinId, usize)>;

/// Discovery order of vertices, the tree edge reaching each vertex (with its parent vertex), and
/// the loop-closing joins in the order met.
pub fn breadth_first(incident: &[Vec<(JoinId, usize)>]) -> (Vec<usize>, TreeEdges, Vec<JoinId>) {
    let mut discovered = vec![false; incident.len()];
    let mut used = std::collections::HashSet::new();
    let mut order = Vec::new();
    let mut tree = HashMap::new();
    let mut loops = Vec::new();
    let mut queue = VecDeque::from([EARTH]);
    discovered[EARTH] = true;
    while let Some(v) = queue.pop_front() {
        if v != EARTH {
            order.push(v);
        }
        for &(join, other) in &incident[v] {
            if !used.insert(join) {
                continue;
            }
            if discovered[other] {
                loops.push(join);
            } else {
                discovered[other] = true;
                tree.insert(other, (join, v));
                queue.push_back(other);
            }
        }
    }
    (order, tree, loops)
}

fn number(
    mechanism: &Mechanism,
    vertices: &[BodyId],
    vertex_of: &HashMap<BodyId, usize>,
    order: &[usize],
    tree: &TreeEdges,
    mut loops: Vec<JoinId>,
) -> Topology {
    let mut number_of_vertex = vec![EARTH; vertices.len() + 1];
    for (k, &v) in order.iter().enumerate() {
        number_of_vertex[v] = k + 1;
    }
    let bodies: Vec<BodyId> = order.iter().map(|&v| vertices[v - 1]).collect();
    let number_of: HashMap<BodyId, usize> = bodies
        .iter()
        .enumerate()
        .map(|(k, &b)| (b, k + 1))
        .collect();
    let principal = order
        .iter()
        .map(|&v| {
            let (join, parent_vertex) = tree[&v];
            let first_vertex = vertex(mechanism.join(join).first.body, vertex_of);
            TreeLink {
                join,
                number: number_of_vertex[v],
                parent: number_of_vertex[parent_vertex],
                child: number_of_vertex[v],
                first_on_parent: first_vertex == parent_vertex,
            }
        })
        .collect();
    loops.sort();
    let n = bodies.len();
    let complementary = loops
        .into_iter()
        .enumerate()
        .map(|(k, join)| {
            let j = mechanism.join(join);
            LoopLink {
                join,
                number: n + 1 + k,
                first: number_of_vertex[vertex(j.first.body, vertex_of)],
                second: number_of_vertex[vertex(j.second.body, vertex_of)],
            }
        })
        .collect();
    Topology {
        bodies,
        number_of,
        principal,
        complementary,
    }
}

fn self_join(mechanism: &Mechanism, id: JoinId) -> Diagnostic {
    let join = mechanism.join(id);
    let body = mechanism.body_name(join.first.body);
    Diagnostic::error("E0702", format!("join `{}` connects `{body}` to itself", mechanism.join_name(id)))
        .primary(join.span, "both frames belong to the same body")
        .help("a link relates frames of two different bodies; to place a frame on a body use `<displacement> @ <body>`")
}

fn not_connected(mechanism: &Mechanism, id: BodyId) -> Diagnostic {
    let name = mechanism.body_name(BodyRef::Body(id));
    Diagnostic::error("E0701", format!("body `{name}` is not connected to earth"))
        .primary(mechanism.body(id).span, "declared here")
        .note("every body must be reachable from `earth` through joins")
        .help(format!(
            "join it to earth or to a connected body, e.g. `join earth and {name} with <link>;`"
        ))
}
