//! The links and joints as a tree, with the errors that keep them from being one.

use std::collections::HashSet;

use urdf_rs::Robot;

use super::document::{child, Source};
use crate::diag::{suggest, Diagnostic};

/// The links and joints as a tree: URDF requires one, and LSD's join of the root to earth
/// assumes it.
pub(super) struct Tree {
    /// Parent and child link of each joint.
    pub(super) joint_links: Vec<(usize, usize)>,
    pub(super) root: usize,
}

impl Tree {
    pub(super) fn build(robot: &Robot, source: &Source) -> Result<Tree, Diagnostic> {
        let link_names: Vec<&str> = robot.links.iter().map(|l| l.name.as_str()).collect();
        unique(&link_names, "link", source)?;
        unique(
            &robot
                .joints
                .iter()
                .map(|j| j.name.as_str())
                .collect::<Vec<_>>(),
            "joint",
            source,
        )?;
        let mut joint_links = Vec::new();
        let mut parent_joint: Vec<Option<usize>> = vec![None; link_names.len()];
        for (index, joint) in robot.joints.iter().enumerate() {
            let parent = link_of(
                &link_names,
                &joint.name,
                "parent",
                &joint.parent.link,
                source,
            )?;
            let child = link_of(&link_names, &joint.name, "child", &joint.child.link, source)?;
            if let Some(first) = parent_joint[child] {
                return Err(two_parents(robot, source, first, index));
            }
            parent_joint[child] = Some(index);
            joint_links.push((parent, child));
        }
        let parent_link: Vec<Option<usize>> = parent_joint
            .iter()
            .map(|j| j.map(|j| joint_links[j].0))
            .collect();
        if let Some(cycle) = find_cycle(&parent_link) {
            return Err(cycle_error(robot, source, &cycle, &parent_joint));
        }
        let roots: Vec<usize> = (0..link_names.len())
            .filter(|&l| parent_joint[l].is_none())
            .collect();
        match roots.as_slice() {
            [root] => Ok(Tree {
                joint_links,
                root: *root,
            }),
            [] => Err(Diagnostic::error("E1007", "the robot has no link")
                .primary(source.span(source.root()), "no `<link>` in this robot")
                .help("declare the robot's links: `<link name=\"base\"/>`")),
            [first, second, ..] => {
                let names: Vec<String> = roots
                    .iter()
                    .map(|&l| format!("`{}`", link_names[l]))
                    .collect();
                Err(Diagnostic::error("E1007", format!("the robot has {} root links: {}", roots.len(), names.join(", ")))
                    .primary(source.span(source.element("link", link_names[*second])), "the child of no joint")
                    .secondary(source.span(source.element("link", link_names[*first])), "another root")
                    .help("a URDF robot is one tree: join the other root links to it (a `fixed` joint welds them)"))
            }
        }
    }
}

/// Two links or two joints with the same name are an error: joints name their links, and LSD
/// names must be unique.
fn unique(names: &[&str], tag: &str, source: &Source) -> Result<(), Diagnostic> {
    let mut seen = HashSet::new();
    for name in names {
        if !seen.insert(*name) {
            let mut elements = source.named(tag, name);
            let mut next = || elements.next().unwrap_or_else(|| source.root());
            let (first, second) = (next(), next());
            return Err(
                Diagnostic::error("E1004", format!("two {tag}s are called `{name}`"))
                    .primary(source.attribute_span(second, "name"), "this name")
                    .secondary(source.attribute_span(first, "name"), "was given here first")
                    .help(format!("rename one of the {tag}s")),
            );
        }
    }
    Ok(())
}

/// The link a joint's `<parent>` or `<child>` names.
fn link_of(
    links: &[&str],
    joint: &str,
    role: &str,
    name: &str,
    source: &Source,
) -> Result<usize, Diagnostic> {
    if let Some(index) = links.iter().position(|l| *l == name) {
        return Ok(index);
    }
    let element = source.element("joint", joint);
    let at = child(element, role).unwrap_or(element);
    let diagnostic = Diagnostic::error(
        "E1003",
        format!("joint `{joint}` names the {role} link `{name}`, which does not exist"),
    )
    .primary(source.attribute_span(at, "link"), "no link has this name");
    Err(match suggest::did_you_mean(name, links.iter().copied()) {
        Some(known) => diagnostic.help(format!("did you mean `{known}`?")),
        None => diagnostic.help(format!(
            "declare it with `<link name=\"{name}\"/>`, or name one of the robot's links"
        )),
    })
}

fn two_parents(robot: &Robot, source: &Source, first: usize, second: usize) -> Diagnostic {
    let link = &robot.joints[second].child.link;
    let at = |joint: usize| {
        let element = source.element("joint", &robot.joints[joint].name);
        source.span(child(element, "child").unwrap_or(element))
    };
    let (first_name, second_name) = (&robot.joints[first].name, &robot.joints[second].name);
    Diagnostic::error("E1005", format!("link `{link}` is the child of two joints, `{first_name}` and `{second_name}`"))
        .primary(at(second), "its second parent joint")
        .secondary(at(first), "its first parent joint")
        .help("a URDF robot is a tree: each link has at most one parent joint (closed loops are not URDF)")
}

/// A cycle of links, each the parent of the one before it, if the parent relation has one.
fn find_cycle(parent_link: &[Option<usize>]) -> Option<Vec<usize>> {
    const UNSEEN: u8 = 0;
    const ON_PATH: u8 = 1;
    const DONE: u8 = 2;
    let mut state = vec![UNSEEN; parent_link.len()];
    for start in 0..parent_link.len() {
        let mut path = Vec::new();
        let mut link = Some(start);
        while let Some(l) = link {
            match state[l] {
                DONE => break,
                ON_PATH => {
                    return Some(path[path.iter().position(|&p| p == l).unwrap_or(0)..].to_vec())
                }
                _ => {}
            }
            state[l] = ON_PATH;
            path.push(l);
            link = parent_link[l];
        }
        for l in path {
            state[l] = DONE;
        }
    }
    None
}

fn cycle_error(
    robot: &Robot,
    source: &Source,
    cycle: &[usize],
    parent_joint: &[Option<usize>],
) -> Diagnostic {
    let mut names: Vec<&str> = cycle
        .iter()
        .rev()
        .map(|&l| robot.links[l].name.as_str())
        .collect();
    names.push(names[0]);
    let mut joints: Vec<usize> = cycle.iter().filter_map(|&l| parent_joint[l]).collect();
    joints.sort_unstable();
    let at = |joint: usize| source.span(source.element("joint", &robot.joints[joint].name));
    let mut diagnostic = Diagnostic::error("E1006", "the joints form a cycle")
        .primary(at(joints[0]), "this joint is part of the cycle")
        .note(format!("the cycle, from parent to child: {}", names.join(" → ")))
        .help("a URDF robot is a tree: the root link is the child of no joint (closed loops are not URDF)");
    for &joint in &joints[1..] {
        diagnostic = diagnostic.secondary(at(joint), "also part of it");
    }
    diagnostic
}
