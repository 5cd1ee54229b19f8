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

pub fn notation(mechanism: &Mechanism, topology: &Topology) -> String {
    notation_and_names(mechanism, topology).0
}

/// The names the notation table gives the written unknowns (`v4T_4_G_z`, `cL2_x`, `u1`, …):
/// the names `--set` accepts for unknowns the program did not name.
pub fn unknown_names(mechanism: &Mechanism, topology: &Topology) -> HashMap<UnknownId, String> {
    notation_and_names(mechanism, topology).1
}

fn notation_and_names(
    mechanism: &Mechanism,
    topology: &Topology,
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
    for (k, &id) in topology.bodies.iter().enumerate() {
        let i = k + 1;
        let body = mechanism.body(id);
        if let Quantity::Declared(d) = &body.iframe {
            displacement_lines(&mut names, i, "G", d, &mut declared);
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
            deduced.push(format!("VOT_{i}_G = 0"));
        }
        if massless && no_inertia {
            deduced.push(format!("MOIo_{i} := 0"));
            continue;
        }
        if centred {
            relations.push(format!("MOIo_{i} = MOIg_{i}"));
        } else {
            relations.push(format!("VOT_{i}_G = MOR_0_{i} &* V{i}T_{i}_G"));
            let central = if no_inertia {
                String::new()
            } else {
                format!("MOIg_{i} ")
            };
            relations.push(format!(
                "MOIo_{i} = {central}- mu_{i} &* ~VOT_{i}_G &* ~VOT_{i}_G"
            ));
        }
        if !no_inertia {
            relations.push(format!(
                "MOIg_{i} = MOR_0_{i} &* M{i}R_{i}_G &* MIg_{i} &* &t(MOR_0_{i} &* M{i}R_{i}_G)"
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
        for frame in [&join.first, &join.second] {
            if let BodyRef::Body(id) = frame.body {
                let i = topology.number_of[&id];
                displacement_lines(
                    &mut names,
                    i,
                    &number.to_string(),
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
