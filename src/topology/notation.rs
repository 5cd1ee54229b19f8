//! The notation table (Papegay 1992, §3.2.4): the structure of the mechanism, the variables the
//! equations are written in, the properties the program declares ("declared assignments") and
//! their immediate consequences ("deduced assignments").
//!
//! Naming convention (it fixes the thesis's ambiguities, notes §8 #12): indices are separated by
//! `_`, so `D_1_15` reads unambiguously with 10 or more bodies; the inertia frame of body i is
//! `R_i_G` (not `R_i(n+1)`, which collides with complementary link n+1); the frame of link k on
//! body i is `R_i_k`. Displacement `D_a` has translation `T_a` and rotation `R_a`; their components
//! in the basis of frame b are `VbT_a` and `MbR_a`, with `O` for the fixed basis. Body i has mass
//! `mu_i`, central inertia `MIg_i` in its inertia basis, `MOIg_i` in the fixed basis and `MOIo_i`
//! about its origin in the fixed basis. Coordinates of link j are `xj[k](t)`. An unknown written
//! `?s` is named after the component it stands for, in lower case (`v4T_4_G_z`); an unknown
//! function in a link effort is named after the effort (`cL2_x` for a torque of link 2, `fL3_y`
//! for a force); other unknowns are `u1`, `u2`, … in order of appearance.

use std::collections::HashMap;
use std::fmt::Write;

use crate::elab::mechanism::{Mechanism, Quantity};
use crate::elab::value::{constant, BodyRef, Displacement, Elementary, Scalar, UnknownId, Vector};
use crate::topology::Topology;

const AXES: [&str; 3] = ["x", "y", "z"];

/// How much the table holds (Papegay 1992, §3.1.1, the levels of detail).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Level {
    /// The table of §3.2.4: structure, variables, assignments, relations.
    #[default]
    Table,
    /// The table and the mass matrix's blocks `MMassMax_i` (§3.3.2, §6.1 of the notes).
    Vector,
    /// The above and the scalar assignments: `MOR_0_i` as the Bryant matrix of `pi[4..6](t)`,
    /// the inertias as matrices.
    Scalar,
}

/// The table's options.
#[derive(Clone, Copy, Debug, Default)]
pub struct Options {
    pub level: Level,
    /// The thesis's own indices, concatenated: the inertia frame of body i is `i(n+1)`
    /// (`V4T_4_45` with n = 4), the frame on body i of the link with body j is `ij`
    /// (`V1T_1_12`), that of complementary link k on body i is `ik`. Ambiguous from 10 bodies
    /// on, and `i(n+1)` collides with complementary link n+1's frame (notes §8 #12): the
    /// default separates and names them (`V4T_4_G`, `V1T_1_2`).
    pub thesis_indices: bool,
}

/// Frame names in the table's convention.
struct FrameNames {
    thesis: bool,
    bodies: usize,
}

impl FrameNames {
    /// The inertia frame of body i.
    fn inertia(&self, i: usize) -> String {
        match self.thesis {
            true => format!("{i}{}", self.bodies + 1),
            false => "G".to_string(),
        }
    }

    /// The frame on body i of link `number`, whose other body is `other` (for a principal
    /// link; `None` for a complementary one).
    fn link(&self, i: usize, number: usize, other: Option<usize>) -> String {
        match (self.thesis, other) {
            (true, Some(j)) => format!("{i}{j}"),
            (true, None) => format!("{i}{number}"),
            (false, _) => number.to_string(),
        }
    }
}

/// Names given to the written unknowns, assigned in the order the table meets them.
struct Names<'m> {
    mechanism: &'m Mechanism,
    assigned: HashMap<UnknownId, String>,
    next_anonymous: usize,
    /// Number of the link whose coordinates the current expression uses.
    link: usize,
    /// Link number of every join.
    link_numbers: HashMap<crate::elab::value::JoinId, usize>,
}

impl Names<'_> {
    fn name(&mut self, id: UnknownId, suggestion: &str) -> String {
        if let Some(name) = self.assigned.get(&id) {
            return name.clone();
        }
        let unknown = &self.mechanism.unknowns[id.0 as usize];
        let name = match (&unknown.name, suggestion) {
            (Some(declared), _) => declared.to_string(),
            (None, "") => {
                self.next_anonymous += 1;
                format!("u{}", self.next_anonymous)
            }
            (None, s) => s.to_string(),
        };
        self.assigned.insert(id, name.clone());
        name
    }

    fn scalar(&mut self, s: &Scalar, slot: &str) -> String {
        let link = self.link;
        let numbers = self.link_numbers.clone();
        let mut render = |id: UnknownId| {
            let origin = self.mechanism.unknowns[id.0 as usize].origin;
            if origin != crate::elab::mechanism::Origin::Written {
                return self.mechanism.generic_name(origin);
            }
            self.name(id, slot)
        };
        s.render_with(&mut render, &|join, index, order| {
            let number = join.and_then(|j| numbers.get(&j).copied()).unwrap_or(link);
            format!("x{number}[{}]{}(t)", index + 1, "'".repeat(order as usize))
        })
    }

    fn vector(&mut self, v: &Vector, slot: &str) -> String {
        if v.iter().all(|c| constant(c) == Some(0.0)) {
            return "0".to_string();
        }
        let parts: Vec<String> = (0..3)
            .map(|i| self.scalar(&v[i], &format!("{slot}_{}", AXES[i])))
            .collect();
        format!("[{}]", parts.join(", "))
    }
}

/// The translation and rotation of a displacement `t ++ r` (or a lone translation or rotation);
/// `None` when the chain has another shape.
fn translation_rotation(d: &Displacement) -> Option<(Option<&Vector>, &[Elementary])> {
    match d.0.split_first() {
        None => Some((None, &[])),
        Some((Elementary::Translation(t), rest))
            if rest
                .iter()
                .all(|e| matches!(e, Elementary::Rotation { .. })) =>
        {
            Some((Some(t), rest))
        }
        Some(_) if d.0.iter().all(|e| matches!(e, Elementary::Rotation { .. })) => {
            Some((None, &d.0))
        }
        _ => None,
    }
}

fn is_zero_scalar(s: &Scalar) -> bool {
    constant(s) == Some(0.0)
}

fn is_zero_vector(v: &Vector) -> bool {
    v.iter().all(is_zero_scalar)
}

/// `Vb T_a := ...` and `Mb R_a := ...` lines for a declared displacement of frame `a` in body `b`.
fn displacement_lines(
    names: &mut Names<'_>,
    body: usize,
    frame: &str,
    d: &Displacement,
    out: &mut Vec<String>,
) {
    let Some((translation, rotations)) = translation_rotation(d) else {
        out.push(format!(
            "D_{body}_{frame} := (a chain of {} steps)",
            d.0.len()
        ));
        return;
    };
    let slot = format!("v{body}T_{body}_{frame}");
    let t = translation.map_or("0".to_string(), |t| names.vector(t, &slot));
    out.push(format!("V{body}T_{body}_{frame} := {t}"));
    let r = if rotations.is_empty() {
        "Id".to_string()
    } else {
        let parts: Vec<String> = rotations
            .iter()
            .map(|e| match e {
                Elementary::Rotation { angle, axis } => {
                    let angle = names.scalar(angle, &format!("a{body}R_{body}_{frame}"));
                    format!(
                        "Rot({angle}, {})",
                        names.vector(axis, &format!("k{body}R_{body}_{frame}"))
                    )
                }
                Elementary::Translation(_) => String::new(),
            })
            .collect();
        parts.join(" &* ")
    };
    out.push(format!("M{body}R_{body}_{frame} := {r}"));
}

#[cfg_attr(not(lsdc_internals), allow(dead_code))]
pub fn notation(mechanism: &Mechanism, topology: &Topology) -> String {
    notation_and_names(mechanism, topology, Options::default()).0
}

/// The table at a level of detail, with the separated or the thesis's indices.
pub fn notation_with(mechanism: &Mechanism, topology: &Topology, options: Options) -> String {
    notation_and_names(mechanism, topology, options).0
}

/// The names the notation table gives the written unknowns (`v4T_4_G_z`, `cL2_x`, `u1`, …):
/// the names `--set` accepts for unknowns the program did not name.
pub fn unknown_names(mechanism: &Mechanism, topology: &Topology) -> HashMap<UnknownId, String> {
    notation_and_names(mechanism, topology, Options::default()).1
}

fn notation_and_names(
    mechanism: &Mechanism,
    topology: &Topology,
    options: Options,
) -> (String, HashMap<UnknownId, String>) {
    let link_numbers = topology
        .principal
        .iter()
        .map(|l| (l.join, l.number))
        .chain(topology.complementary.iter().map(|l| (l.join, l.number)))
        .collect();
    let mut names = Names {
        mechanism,
        assigned: HashMap::new(),
        next_anonymous: 0,
        link: 0,
        link_numbers,
    };
    let n = topology.body_count();
    let frames = FrameNames {
        thesis: options.thesis_indices,
        bodies: n,
    };
    let mut out = String::new();
    let _ = writeln!(out, "(* structure *)\nN := {n} ;");
    let bodies: Vec<String> = topology
        .bodies
        .iter()
        .enumerate()
        .map(|(k, &id)| format!("S_{} = '{}'", k + 1, mechanism.body_name(BodyRef::Body(id))))
        .collect();
    let _ = writeln!(out, "BODIES := {} ;", bodies.join(",\n          "));
    let link_line = |number: usize, join: crate::elab::value::JoinId, a: usize, b: usize| {
        format!(
            "L_{number} = '{}' (S_{a}, S_{b})",
            mechanism.join_name(join)
        )
    };
    let principal: Vec<String> = topology
        .principal
        .iter()
        .map(|l| link_line(l.number, l.join, l.parent, l.child))
        .collect();
    let _ = writeln!(out, "PRINCIPAL := {} ;", principal.join(",\n             "));
    let complementary: Vec<String> = topology
        .complementary
        .iter()
        .map(|l| link_line(l.number, l.join, l.first, l.second))
        .collect();
    let _ = writeln!(
        out,
        "COMPLEMENTARY := {} ;",
        if complementary.is_empty() {
            "none".to_string()
        } else {
            complementary.join(",\n                 ")
        }
    );

    let _ = writeln!(out, "\n(* variables *)");
    for i in 1..=n {
        let _ = writeln!(
            out,
            "p{i}[1..6](t), q{i}[1..6](t) : position and velocity parameters of S_{i}"
        );
    }
    let links = topology
        .principal
        .iter()
        .map(|l| (l.number, l.join))
        .chain(topology.complementary.iter().map(|l| (l.number, l.join)));
    for (number, join) in links {
        let coordinates = &mechanism.link(mechanism.join(join).link).coordinates;
        for (k, c) in coordinates.iter().enumerate() {
            let _ = writeln!(
                out,
                "x{number}[{}](t) : coordinate `{c}` of L_{number}",
                k + 1
            );
        }
    }

    let mut declared = Vec::new();
    let mut deduced = Vec::new();
    let mut relations = Vec::new();
    let mut blocks = Vec::new();
    let mut scalars = Vec::new();
    for (k, &id) in topology.bodies.iter().enumerate() {
        let i = k + 1;
        let g = frames.inertia(i);
        let body = mechanism.body(id);
        if let Quantity::Declared(d) = &body.iframe {
            displacement_lines(&mut names, i, &g, d, &mut declared);
        }
        let massless = matches!(&body.mass, Quantity::Declared(m) if is_zero_scalar(m));
        if let Quantity::Declared(m) = &body.mass {
            let value = names.scalar(m, &format!("mu_{i}"));
            declared.push(format!("mu_{i} := {value}"));
        }
        let no_inertia = matches!(&body.inertia, Quantity::Declared(v) if is_zero_vector(v));
        if let Quantity::Declared(v) = &body.inertia {
            let value = if no_inertia {
                "0".to_string()
            } else {
                format!(
                    "diag({})",
                    names
                        .vector(v, &format!("mIg_{i}"))
                        .trim_matches(['[', ']'])
                )
            };
            declared.push(format!("MIg_{i} := {value}"));
        }
        let centred = match &body.iframe {
            Quantity::Declared(d) => {
                translation_rotation(d).is_some_and(|(t, _)| t.is_none_or(is_zero_vector))
            }
            Quantity::Generic(_) => false,
        };
        if centred {
            deduced.push(format!("VOT_{i}_{g} = 0"));
        }
        scalars.push(format!("MOR_0_{i} := {}", bryant_matrix(i)));
        let weighs = !(massless && no_inertia);
        if weighs && !matches!(&body.inertia, Quantity::Declared(_)) {
            scalars.push(format!(
                "MIg_{i} := matrix([[MIg_{i}_xx, 0, 0], [0, MIg_{i}_yy, 0], [0, 0, MIg_{i}_zz]])"
            ));
        }
        if weighs && !matches!(&body.iframe, Quantity::Declared(_)) {
            scalars.push(format!(
                "V{i}T_{i}_{g} := [V{i}T_{i}_{g}_x, V{i}T_{i}_{g}_y, V{i}T_{i}_{g}_z]"
            ));
        }
        if massless && no_inertia {
            deduced.push(format!("MOIo_{i} := 0"));
            blocks.push(format!("MMassMax_{i} = 0"));
            continue;
        }
        blocks.push(match centred {
            true => format!("MMassMax_{i} = [[mu_{i} &s Id, 0], [0, MOIo_{i}]]"),
            false => format!(
                "MMassMax_{i} = [[mu_{i} &s Id, - mu_{i} &s ~VOT_{i}_{g}], [mu_{i} &s ~VOT_{i}_{g}, MOIo_{i}]]"
            ),
        });
        if centred {
            relations.push(format!("MOIo_{i} = MOIg_{i}"));
        } else {
            relations.push(format!("VOT_{i}_{g} = MOR_0_{i} &* V{i}T_{i}_{g}"));
            let central = if no_inertia {
                String::new()
            } else {
                format!("MOIg_{i} ")
            };
            relations.push(format!(
                "MOIo_{i} = {central}- mu_{i} &* ~VOT_{i}_{g} &* ~VOT_{i}_{g}"
            ));
        }
        if !no_inertia {
            relations.push(format!(
                "MOIg_{i} = MOR_0_{i} &* M{i}R_{i}_{g} &* MIg_{i} &* &t(MOR_0_{i} &* M{i}R_{i}_{g})"
            ));
        }
    }
    for link in topology
        .principal
        .iter()
        .map(|l| l.join)
        .chain(topology.complementary.iter().map(|l| l.join))
    {
        let number = link_number(topology, link);
        let join = mechanism.join(link);
        let number_of = |body: BodyRef| match body {
            BodyRef::Earth => 0,
            BodyRef::Body(id) => topology.number_of[&id],
        };
        let principal = topology.principal.iter().any(|l| l.join == link);
        let ends = [number_of(join.first.body), number_of(join.second.body)];
        for (side, frame) in [&join.first, &join.second].into_iter().enumerate() {
            if let BodyRef::Body(id) = frame.body {
                let i = topology.number_of[&id];
                let other = principal.then_some(ends[1 - side]);
                displacement_lines(
                    &mut names,
                    i,
                    &frames.link(i, number, other),
                    &frame.displacement,
                    &mut declared,
                );
            }
        }
        let l = mechanism.link(join.link);
        names.link = number;
        for (prefix, efforts) in [("fL", &l.forces), ("cL", &l.torques)] {
            for (index, v) in efforts {
                let suffix = if *index == 0 {
                    String::new()
                } else {
                    format!("{index}")
                };
                let value = names.vector(v, &format!("{prefix}{number}{suffix}"));
                let label = if prefix == "fL" { "VFL" } else { "VCL" };
                declared.push(format!("{label}{suffix}_{number} := {value}"));
            }
        }
    }
    let _ = writeln!(out, "\n(* declared assignments *)");
    for line in declared {
        let _ = writeln!(out, "{line} ;");
    }
    let _ = writeln!(out, "\n(* deduced assignments *)");
    for line in deduced {
        let _ = writeln!(out, "{line} ;");
    }
    let _ = writeln!(out, "\n(* relations *)");
    for line in relations {
        let _ = writeln!(out, "{line} ;");
    }
    if options.level != Level::Table {
        out.push_str(&mass_blocks(n, &blocks));
    }
    if options.level == Level::Scalar {
        let _ = writeln!(out, "\n(* scalar assignments *)");
        for line in scalars {
            let _ = writeln!(out, "{line} ;");
        }
    }
    (out, names.assigned)
}

fn link_number(topology: &Topology, join: crate::elab::value::JoinId) -> usize {
    topology
        .principal
        .iter()
        .find(|l| l.join == join)
        .map(|l| l.number)
        .or_else(|| {
            topology
                .complementary
                .iter()
                .find(|l| l.join == join)
                .map(|l| l.number)
        })
        .unwrap_or(0)
}

/// The generalised mass matrix of the free bodies, block by block (Papegay 1992, §3.3.2, step
/// 2, and its worked use on the satellite): `&s` is the product by a scalar, `~v` the
/// cross-product matrix of v, in the fixed basis.
fn mass_blocks(n: usize, blocks: &[String]) -> String {
    let mut out = String::new();
    let all: Vec<String> = (1..=n).map(|i| format!("MMassMax_{i}")).collect();
    let _ = writeln!(out, "\n(* mass matrix blocks *)");
    let _ = writeln!(out, "MMassMax = BlockDiagonal({}) ;", all.join(", "));
    for line in blocks {
        let _ = writeln!(out, "{line} ;");
    }
    out
}

/// The orientation of body i in the fixed basis as the thesis writes it at the scalar level:
/// the Bryant matrix of the body's angles `pi[4..6](t)`, whatever its link's parametrisation.
fn bryant_matrix(i: usize) -> String {
    let (c, s) = (
        |k: usize| format!("cos(p{i}[{k}](t))"),
        |k: usize| format!("sin(p{i}[{k}](t))"),
    );
    let rows = [
        [
            format!("{} {}", c(5), c(6)),
            format!("- {} {}", c(5), s(6)),
            s(5),
        ],
        [
            format!("{} {} {} + {} {}", s(4), s(5), c(6), c(4), s(6)),
            format!("- {} {} {} + {} {}", s(4), s(5), s(6), c(4), c(6)),
            format!("- {} {}", s(4), c(5)),
        ],
        [
            format!("- {} {} {} + {} {}", c(4), s(5), c(6), s(4), s(6)),
            format!("{} {} {} + {} {}", c(4), s(5), s(6), s(4), c(6)),
            format!("{} {}", c(4), c(5)),
        ],
    ];
    let rows: Vec<String> = rows.iter().map(|r| format!("[{}]", r.join(", "))).collect();
    format!("[{}]", rows.join(", "))
}

/// The equations at the level of vectors and matrices (Papegay 1992, §3.1.1, level 2, and
/// §3.3.1): the free bodies' blocks and the projection on the tree's coordinates, in names that
/// do not mention the coordinates chosen; `--emit equations --level scalar` writes them out.
pub fn vector_equations(mechanism: &Mechanism, topology: &Topology, options: Options) -> String {
    let table = notation_with(
        mechanism,
        topology,
        Options {
            level: Level::Vector,
            ..options
        },
    );
    let n = topology.body_count();
    let frames = FrameNames {
        thesis: options.thesis_indices,
        bodies: n,
    };
    let mut out = table;
    let _ = writeln!(out, "\n(* second member and efforts of the free bodies *)");
    for i in 1..=n {
        let g = frames.inertia(i);
        let _ = writeln!(out, "Omega_{i} = [q{i}[4](t), q{i}[5](t), q{i}[6](t)] ;");
        let _ = writeln!(
            out,
            "SSecMax_{i} = [- mu_{i} &s ~Omega_{i} &* ~Omega_{i} &* VOT_{i}_{g}, - ~Omega_{i} &* MOIo_{i} &* Omega_{i}] ;"
        );
        let _ = writeln!(out, "FForMax_{i} = [VOFE_{i}, VOCE_{i}] ;");
    }
    let all = |name: &str| {
        (1..=n)
            .map(|i| format!("{name}_{i}"))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let _ = writeln!(out, "SSecMax = [{}] ;", all("SSecMax"));
    let _ = writeln!(out, "FForMax = [{}] ;", all("FForMax"));
    let _ = writeln!(
        out,
        "\n(* free bodies: MMassMax &* qdot = SSecMax + FForMax *)"
    );
    let _ = writeln!(
        out,
        "[{}] = Psi(p) &* q ;",
        (1..=n)
            .map(|i| format!("q{i}[1..6](t)"))
            .collect::<Vec<_>>()
            .join(", ")
    );
    let _ = writeln!(
        out,
        "\n(* the tree's equations, Psi^T eliminating its reactions *)"
    );
    let _ = writeln!(out, "M(p) = &t(Psi(p)) &* MMassMax &* Psi(p) ;");
    let _ = writeln!(
        out,
        "S(p, q) = &t(Psi(p)) &* (SSecMax - MMassMax &* Psidot(p, q) &* q) ;"
    );
    let _ = writeln!(out, "F(p, q, t) = &t(Psi(p)) &* FForMax + FL(p, q, t) ;");
    let _ = writeln!(out, "M(p) &* q' = S(p, q) + F(p, q, t) ;");
    if !topology.complementary.is_empty() {
        let _ = writeln!(
            out,
            "\n(* loops: the complementary links' constraints, Psi^T eliminating the tree's reactions only *)"
        );
        let _ = writeln!(out, "Delta_V(p) = D_cmp(psi(p)) &* Psi(p) ;");
        let _ = writeln!(
            out,
            "M(p) &* q' = S(p, q) + F(p, q, t) + &t(Delta_V(p)) &* Lambda ;"
        );
        let _ = writeln!(out, "Delta_V(p) &* q = 0 ;");
    }
    out
}
