//! What urdf-rs requires of a URDF text, checked before it reads it, so that the error says
//! where it is: urdf-rs's own errors have no position. Also stricter than urdf-rs about
//! numbers: it skips the words of a vector that are not numbers (`xyz="1 x 2 3"` would be
//! `1 2 3`) and reads `inf` and `NaN`, which no mechanism has.
//!
//! The checks apply to the elements urdf-rs reads ([`READ`]): an element it does not read,
//! such as Pinocchio's `<collision_checking>` in a link, is a warning, and what is inside it is
//! not checked.

use super::document::{child, children, parent, tag_of, Element, Source};
use crate::diag::{suggest, Diagnostic};
use crate::source::Span;

/// The elements urdf-rs reads, by the element they are in, from `<robot>` down. Any other
/// element, and everything inside it, is skipped by urdf-rs: an extension such as Pinocchio's
/// `<collision_checking>` in a link, whose `<capsule name="..."/>` is not a shape.
pub(super) const READ: &[(&str, &[&str])] = &[
    ("robot", &["link", "joint", "material"]),
    ("link", &["inertial", "visual", "collision"]),
    ("inertial", &["origin", "mass", "inertia"]),
    ("visual", &["origin", "geometry", "material"]),
    ("collision", &["origin", "geometry"]),
    (
        "geometry",
        &["box", "cylinder", "capsule", "sphere", "mesh"],
    ),
    ("material", &["color", "texture"]),
    (
        "joint",
        &[
            "origin",
            "parent",
            "child",
            "axis",
            "calibration",
            "dynamics",
            "limit",
            "mimic",
            "safety_controller",
        ],
    ),
];

/// Whether urdf-rs reads a `<tag>` inside a `<parent>`.
pub(super) fn reads(parent: &str, tag: &str) -> bool {
    READ.iter()
        .any(|(outer, inner)| *outer == parent && inner.contains(&tag))
}

/// URDF's joint types (urdf-rs also reads `spherical`).
const JOINT_TYPES: &[&str] = &[
    "revolute",
    "continuous",
    "prismatic",
    "fixed",
    "floating",
    "planar",
    "spherical",
];

/// The numbers urdf-rs reads inside links and joints: element, attribute, how many numbers,
/// whether the attribute is required.
const NUMBERS: &[(&str, &str, usize, bool)] = &[
    ("origin", "xyz", 3, false),
    ("origin", "rpy", 3, false),
    ("mass", "value", 1, true),
    ("inertia", "ixx", 1, true),
    ("inertia", "ixy", 1, true),
    ("inertia", "ixz", 1, true),
    ("inertia", "iyy", 1, true),
    ("inertia", "iyz", 1, true),
    ("inertia", "izz", 1, true),
    ("axis", "xyz", 3, true),
    ("limit", "lower", 1, false),
    ("limit", "upper", 1, false),
    ("limit", "effort", 1, false),
    ("limit", "velocity", 1, true),
    ("mimic", "multiplier", 1, false),
    ("mimic", "offset", 1, false),
    ("dynamics", "damping", 1, false),
    ("dynamics", "friction", 1, false),
    ("safety_controller", "soft_lower_limit", 1, false),
    ("safety_controller", "soft_upper_limit", 1, false),
    ("safety_controller", "k_position", 1, false),
    ("safety_controller", "k_velocity", 1, true),
    ("calibration", "rising", 1, false),
    ("calibration", "falling", 1, false),
    ("box", "size", 3, true),
    ("cylinder", "radius", 1, true),
    ("cylinder", "length", 1, true),
    ("capsule", "radius", 1, true),
    ("capsule", "length", 1, true),
    ("sphere", "radius", 1, true),
    ("mesh", "scale", 3, false),
    ("color", "rgba", 4, true),
];

/// Whether urdf-rs reads this element: the root `<robot>`, and below it each element that
/// urdf-rs reads inside an element it reads.
fn is_read(element: Element) -> bool {
    match parent(element) {
        Some(outer) => is_read(outer) && reads(&tag_of(outer), &tag_of(element)),
        None => tag_of(element) == "robot",
    }
}

fn invalid(span: Span, message: impl Into<String>, label: impl Into<String>) -> Diagnostic {
    Diagnostic::error("E1002", message).primary(span, label)
}

/// urdf-rs rejected a text that passed the checks below; its message has no position.
pub(super) fn rejected(source: &Source, reason: &str) -> Diagnostic {
    invalid(
        source.span(source.root()),
        format!("not a valid URDF file: {reason}"),
        "in this robot",
    )
    .help("the URDF format is described at http://wiki.ros.org/urdf/XML")
}

/// What urdf-rs requires, checked first so that the error says where it is.
pub(super) fn check_structure(source: &Source) -> Result<(), Diagnostic> {
    let root = source.root();
    let tag = tag_of(root);
    if tag != "robot" {
        return Err(invalid(source.span(root), format!("the root element is `<{tag}>`, not `<robot>`"), "expected `<robot>`")
            .help("a URDF file describes one robot: `<robot name=\"...\"> <link .../> <joint .../> </robot>`"));
    }
    for top in children(root) {
        match tag_of(top).as_ref() {
            "link" => check_link(source, top)?,
            "joint" => check_joint(source, top)?,
            _ => {}
        }
    }
    Ok(())
}

fn check_link(source: &Source, link: Element) -> Result<(), Diagnostic> {
    required_attribute(source, link, "name")?;
    if let Some(inertial) = child(link, "inertial") {
        required_child(source, inertial, "mass")?;
        required_child(source, inertial, "inertia")?;
    }
    for shape in children(link) {
        if matches!(tag_of(shape).as_ref(), "visual" | "collision") {
            required_child(source, shape, "geometry")?;
        }
    }
    check_numbers_below(source, link)
}

fn check_joint(source: &Source, joint: Element) -> Result<(), Diagnostic> {
    required_attribute(source, joint, "name")?;
    let kind = required_attribute(source, joint, "type")?;
    if !JOINT_TYPES.contains(&kind) {
        let diagnostic = invalid(
            source.attribute_span(joint, "type"),
            format!("unknown joint type `{kind}`"),
            "not a URDF joint type",
        );
        return Err(
            match suggest::did_you_mean(kind, JOINT_TYPES.iter().copied()) {
                Some(known) => diagnostic.help(format!("did you mean `{known}`?")),
                None => diagnostic.help(format!("the joint types are {}", JOINT_TYPES.join(", "))),
            },
        );
    }
    for tag in ["parent", "child"] {
        let element = required_child(source, joint, tag)?;
        required_attribute(source, element, "link")?;
    }
    check_numbers_below(source, joint)
}

fn required_attribute<'s>(
    source: &Source,
    element: Element<'s, '_>,
    name: &str,
) -> Result<&'s str, Diagnostic> {
    element.attribute(name).ok_or_else(|| {
        let tag = tag_of(element);
        invalid(
            source.span(element),
            format!("`<{tag}>` has no `{name}` attribute"),
            format!("`{name}` is required"),
        )
    })
}

fn required_child<'s, 'a>(
    source: &Source,
    outer: Element<'s, 'a>,
    tag: &str,
) -> Result<Element<'s, 'a>, Diagnostic> {
    child(outer, tag).ok_or_else(|| {
        let outer_tag = tag_of(outer);
        invalid(
            source.span(outer),
            format!("`<{outer_tag}>` has no `<{tag}>` element"),
            format!("`<{tag}>` is required here"),
        )
    })
}

/// Checks the numbers of `top` (a link or joint) and of every element inside it.
fn check_numbers_below(source: &Source, top: Element) -> Result<(), Diagnostic> {
    top.descendants()
        .filter(|e| e.is_element())
        .try_for_each(|e| check_numbers(source, e))
}

/// Checks the numbers of an element urdf-rs reads: the same tag elsewhere is not read
/// (`<capsule name="test"/>` in Pinocchio's `<collision_checking>` is not a shape).
fn check_numbers(source: &Source, element: Element) -> Result<(), Diagnostic> {
    if !is_read(element) {
        return Ok(());
    }
    let tag = tag_of(element);
    for &(_, name, count, required) in NUMBERS.iter().filter(|(t, ..)| *t == tag) {
        let Some(value) = element.attribute(name) else {
            if required {
                required_attribute(source, element, name)?;
            }
            continue;
        };
        let numbers: Vec<Option<f64>> = value
            .split_whitespace()
            .map(|t| t.parse::<f64>().ok().filter(|x| x.is_finite()))
            .collect();
        if numbers.len() != count || numbers.contains(&None) {
            let expected = if count == 1 {
                "a finite number".to_string()
            } else {
                format!("{count} finite numbers")
            };
            let message = format!("`{name}` of `<{tag}>` must be {expected}, not `{value}`");
            return Err(invalid(
                source.attribute_span(element, name),
                message,
                format!("expected {expected}"),
            ));
        }
    }
    Ok(())
}
