//! Reading a URDF file as an LSD program: `lsdc import-urdf`, and `.urdf` files given to any
//! command (the loader imports them with the default options).
//!
//! The translation (documented for users in `docs/commands.md`):
//!
//! - each URDF link is a body whose reference frame is the link frame. Its `iframe` is the
//!   inertial origin turned onto the principal axes of the inertia tensor, `inertia` the
//!   principal moments. A link without mass and inertia is a massless body;
//! - each URDF joint is `join ORIGIN @ PARENT and CHILD with J as NAME`: URDF puts the child link
//!   frame at parent · origin · motion(q), which is LSD's dof chain from a join's first frame to
//!   its second;
//! - the root link is welded to earth, or joined to it by `free` for a floating base; gravity is
//!   the standard library's `weight` on every link with mass.
//!
//! Nothing is dropped silently: what LSD does not express (limits, mimic, damping, geometry,
//! transmissions...) is a warning at the URDF element, and so is every name that had to change.
//! urdf-rs reads the values but keeps no positions, so the text is also scanned here, to point
//! each diagnostic at its element and to report malformed XML where it is. The checks apply to
//! the elements urdf-rs reads ([`READ`]): an element it does not read, such as Pinocchio's
//! `<collision_checking>` in a link, is a warning, and what is inside it is not checked. A
//! `<texture>` without `filename`, which urdf-rs rejects, is blanked out of the text it reads:
//! materials are not imported.

use std::borrow::Cow;
use std::collections::HashSet;
use std::sync::OnceLock;

use nalgebra::{Matrix3, Rotation3, SymmetricEigen, UnitQuaternion, Vector3};
use urdf_rs::{Inertial, JointType, Pose, Robot};

use super::stdlib;
use crate::diag::{suggest, Diagnostic};
use crate::source::{FileId, Span};
use crate::syntax::ast::DeclKind;
use crate::syntax::lexer::{lex, Tok};
use crate::syntax::names::BUILTIN_NAMES;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ImportOptions {
    /// Join the root link to earth by `free` instead of welding it.
    pub floating_base: bool,
    /// Apply the standard library's `weight` (g along -z) to every link with mass.
    pub gravity: bool,
}

impl Default for ImportOptions {
    fn default() -> Self {
        ImportOptions {
            floating_base: false,
            gravity: true,
        }
    }
}

#[derive(Clone, Debug)]
pub struct Imported {
    /// The LSD program.
    pub text: String,
    /// What the program leaves out of the URDF and the names it changed, in the order of the
    /// URDF text.
    pub warnings: Vec<Diagnostic>,
}

/// Imports a URDF text. `name` is the file name shown in the program's header. The
/// diagnostics' spans are in `FileId(0)`: render them against a `SourceMap` whose first file is
/// `xml` (use [`import_urdf_at`] for another file).
pub fn import_urdf(name: &str, xml: &str, options: &ImportOptions) -> Result<Imported, Diagnostic> {
    import_urdf_at(FileId(0), name, xml, options)
}

/// Imports a URDF text whose diagnostics point into `file`, the id `xml` has in the caller's
/// `SourceMap`.
pub fn import_urdf_at(
    file: FileId,
    name: &str,
    xml: &str,
    options: &ImportOptions,
) -> Result<Imported, Diagnostic> {
    let source = Source::scan(file, xml)?;
    source.check_structure()?;
    let robot = urdf_rs::read_from_string(&source.urdf_text())
        .map_err(|e| source.rejected(&e.to_string()))?;
    let tree = Tree::build(&robot, &source)?;
    let mut importer = Importer {
        robot: &robot,
        source: &source,
        tree: &tree,
        options,
        names: Names::default(),
        warnings: Vec::new(),
    };
    let text = importer.program(name)?;
    let mut warnings = importer.warnings;
    warnings.sort_by_key(|d| d.primary_span().map(|s| s.start));
    Ok(Imported { text, warnings })
}

/// The LSD identifier a URDF link or joint name becomes, when no other link or joint took it
/// first. A valid LSD identifier stays as it is unless it is a keyword or a name the program
/// needs (a builtin such as `pi` or `earth`, a standard library module or one of its names such
/// as `revolute`, `weld` or `g`). Otherwise every character that cannot be part of an
/// identifier becomes `_`, a leading digit gets a `_` before it, and `_` is appended while the
/// result is a keyword or such a name. The importer then appends `_` while the name is taken by
/// an earlier link or joint (links first, then joints, in the order of the file).
pub fn lsd_name(urdf_name: &str) -> String {
    let mut name: String = urdf_name
        .chars()
        .map(|c| if continues_identifier(c) { c } else { '_' })
        .collect();
    if !name.chars().next().is_some_and(starts_identifier) {
        name.insert(0, '_');
    }
    while !is_identifier(&name) || reserved().contains(&name) {
        name.push('_');
    }
    name
}

/// Whether `text` is exactly one LSD identifier token (a keyword lexes as its own token).
fn is_identifier(text: &str) -> bool {
    let (tokens, errors) = lex(FileId(0), text);
    errors.is_empty()
        && matches!(tokens.as_slice(), [(0, Tok::Ident(_), end)] if *end == text.len())
}

fn starts_identifier(c: char) -> bool {
    c == '_' || is_identifier(c.encode_utf8(&mut [0; 4]))
}

fn continues_identifier(c: char) -> bool {
    is_identifier(&format!("_{c}"))
}

/// Names a link or joint cannot take: the builtins and the standard library's modules and
/// declarations, which the generated program uses and a declaration would shadow. The same set
/// whatever the options, so that a link's name does not depend on them.
fn reserved() -> &'static HashSet<String> {
    static RESERVED: OnceLock<HashSet<String>> = OnceLock::new();
    RESERVED.get_or_init(|| {
        let mut names: HashSet<String> = BUILTIN_NAMES.iter().map(|s| s.to_string()).collect();
        for module in stdlib::names() {
            names.insert(module.to_string());
            let Some((_, text)) = stdlib::find(module) else {
                continue;
            };
            let (program, _) = crate::syntax::parser::parse(FileId(0), text);
            for decl in &program.decls {
                match &decl.kind {
                    DeclKind::Let(bindings) => {
                        names.extend(bindings.iter().map(|b| b.name.name.to_string()))
                    }
                    DeclKind::Define { name, .. } => {
                        names.insert(name.name.to_string());
                    }
                    _ => {}
                }
            }
        }
        names
    })
}

// ---------------------------------------------------------------------------------------------
// The URDF text: elements and their positions
// ---------------------------------------------------------------------------------------------

/// A start tag of the URDF text.
struct Element {
    tag: String,
    /// Byte range of the start tag, `<` to `>`.
    range: (usize, usize),
    /// Byte offset after the element: after its end tag, or after the start tag of an empty
    /// element (`<tag ... />`).
    end: usize,
    attributes: Vec<Attribute>,
    parent: Option<usize>,
}

struct Attribute {
    name: String,
    value: String,
    /// Byte range of `name="value"`.
    range: (usize, usize),
}

impl Element {
    fn attribute(&self, name: &str) -> Option<&Attribute> {
        self.attributes.iter().find(|a| a.name == name)
    }
}

/// Where the text stops being well-formed XML.
struct XmlError {
    message: String,
    range: (usize, usize),
    label: &'static str,
}

/// Constructs skipped by the scanner: how they open, how they close, what they are.
const SKIPPED: &[(&str, &str, &str)] = &[
    ("<!--", "-->", "comment"),
    ("<![CDATA[", "]]>", "CDATA section"),
    ("<?", "?>", "processing instruction"),
    ("<!", ">", "declaration"),
];

/// The start tags of an XML text in document order (so the root comes first, and every parent
/// before its children), checking that elements nest.
fn scan(xml: &str) -> Result<Vec<Element>, XmlError> {
    let mut elements: Vec<Element> = Vec::new();
    let mut open: Vec<usize> = Vec::new();
    let mut at = 0;
    while let Some(offset) = xml[at..].find('<') {
        let start = at + offset;
        let rest = &xml[start..];
        at = if let Some((_, close, what)) = SKIPPED
            .iter()
            .find(|(opening, ..)| rest.starts_with(opening))
        {
            past(xml, start, close, what)?
        } else if rest.starts_with("</") {
            let end = past(xml, start, ">", "end tag")?;
            let closed = close_element(
                &elements,
                &mut open,
                xml[start + 2..end - 1].trim(),
                (start, end),
            )?;
            elements[closed].end = end;
            end
        } else {
            let (element, end, empty) = start_tag(xml, start, open.last().copied())?;
            if element.parent.is_none() && !elements.is_empty() {
                let message = format!("a second root element `<{}>`", element.tag);
                return Err(XmlError {
                    message,
                    range: element.range,
                    label: "after the end of the root element",
                });
            }
            elements.push(element);
            if !empty {
                open.push(elements.len() - 1);
            }
            end
        };
    }
    if let Some(&index) = open.last() {
        let message = format!("`<{}>` is never closed", elements[index].tag);
        return Err(XmlError {
            message,
            range: elements[index].range,
            label: "opened here",
        });
    }
    if elements.is_empty() {
        return Err(XmlError {
            message: "no element".into(),
            range: (0, 0),
            label: "expected `<robot>`",
        });
    }
    Ok(elements)
}

/// The offset after `close`, searched from `start`.
fn past(xml: &str, start: usize, close: &str, what: &str) -> Result<usize, XmlError> {
    match xml[start + 1..].find(close) {
        Some(offset) => Ok(start + 1 + offset + close.len()),
        None => Err(XmlError {
            message: format!("unterminated {what}"),
            range: one_char(xml, start),
            label: "never closed",
        }),
    }
}

/// Closes the innermost open element, which must be `tag`: its index.
fn close_element(
    elements: &[Element],
    open: &mut Vec<usize>,
    tag: &str,
    range: (usize, usize),
) -> Result<usize, XmlError> {
    match open.pop() {
        Some(index) if elements[index].tag == tag => Ok(index),
        Some(index) => {
            let message = format!("`</{tag}>` closes `<{}>`", elements[index].tag);
            Err(XmlError {
                message,
                range,
                label: "mismatched end tag",
            })
        }
        None => Err(XmlError {
            message: format!("`</{tag}>` closes no element"),
            range,
            label: "unexpected end tag",
        }),
    }
}

/// Reads the start tag at `start`: the element, the offset after it, and whether it is empty
/// (`<tag ... />`).
fn start_tag(
    xml: &str,
    start: usize,
    parent: Option<usize>,
) -> Result<(Element, usize, bool), XmlError> {
    let bytes = xml.as_bytes();
    let unterminated = || XmlError {
        message: "unterminated start tag".into(),
        range: one_char(xml, start),
        label: "no `>` closes this tag",
    };
    let name_end = find_byte(bytes, start + 1, |b| {
        b.is_ascii_whitespace() || b == b'/' || b == b'>'
    })
    .ok_or_else(unterminated)?;
    if name_end == start + 1 {
        return Err(XmlError {
            message: "a `<` without an element name".into(),
            range: one_char(xml, start),
            label: "expected a name after `<`",
        });
    }
    let mut attributes = Vec::new();
    let mut at = name_end;
    loop {
        at = find_byte(bytes, at, |b| !b.is_ascii_whitespace()).ok_or_else(unterminated)?;
        let (end, empty) = match (bytes[at], bytes.get(at + 1)) {
            (b'>', _) => (at + 1, false),
            (b'/', Some(b'>')) => (at + 2, true),
            _ => {
                let (attribute, end) = attribute(xml, at)?;
                attributes.push(attribute);
                at = end;
                continue;
            }
        };
        let element = Element {
            tag: xml[start + 1..name_end].to_string(),
            range: (start, end),
            end,
            attributes,
            parent,
        };
        return Ok((element, end, empty));
    }
}

/// Reads `name="value"` at `start`: the attribute and the offset after it.
fn attribute(xml: &str, start: usize) -> Result<(Attribute, usize), XmlError> {
    let bytes = xml.as_bytes();
    let name_end = find_byte(bytes, start, |b| {
        b == b'=' || b == b'>' || b == b'/' || b.is_ascii_whitespace()
    })
    .unwrap_or(bytes.len());
    let error = |message: String, label| XmlError {
        message,
        range: (start, name_end.max(one_char(xml, start).1)),
        label,
    };
    if name_end == start {
        return Err(error(
            "an unexpected character in a tag".into(),
            "expected an attribute or `>`",
        ));
    }
    let name = &xml[start..name_end];
    let equals =
        find_byte(bytes, name_end, |b| !b.is_ascii_whitespace()).filter(|&i| bytes[i] == b'=');
    let quote = equals
        .and_then(|e| find_byte(bytes, e + 1, |b| !b.is_ascii_whitespace()))
        .filter(|&i| matches!(bytes[i], b'"' | b'\''));
    let Some(quote) = quote else {
        return Err(error(
            format!("attribute `{name}` has no quoted value"),
            "expected `=\"...\"` after it",
        ));
    };
    let Some(close) = find_byte(bytes, quote + 1, |b| b == bytes[quote]) else {
        return Err(error(
            format!("the value of attribute `{name}` is never closed"),
            "unterminated value",
        ));
    };
    let attribute = Attribute {
        name: name.to_string(),
        value: unescape(&xml[quote + 1..close]),
        range: (start, close + 1),
    };
    Ok((attribute, close + 1))
}

fn find_byte(bytes: &[u8], from: usize, found: impl Fn(u8) -> bool) -> Option<usize> {
    bytes
        .get(from..)?
        .iter()
        .position(|&b| found(b))
        .map(|i| from + i)
}

/// The range of the character at `at` (empty at the end of the text).
fn one_char(xml: &str, at: usize) -> (usize, usize) {
    (at, at + xml[at..].chars().next().map_or(0, char::len_utf8))
}

/// An attribute value with its character and entity references replaced.
fn unescape(raw: &str) -> String {
    let mut out = String::with_capacity(raw.len());
    let mut rest = raw;
    while let Some(amp) = rest.find('&') {
        out.push_str(&rest[..amp]);
        rest = &rest[amp..];
        match rest
            .find(';')
            .and_then(|semi| Some((entity(&rest[1..semi])?, semi)))
        {
            Some((c, semi)) => {
                out.push(c);
                rest = &rest[semi + 1..];
            }
            None => {
                out.push('&');
                rest = &rest[1..];
            }
        }
    }
    out.push_str(rest);
    out
}

fn entity(name: &str) -> Option<char> {
    match name {
        "lt" => Some('<'),
        "gt" => Some('>'),
        "amp" => Some('&'),
        "quot" => Some('"'),
        "apos" => Some('\''),
        _ => {
            let code = match name.strip_prefix("#x") {
                Some(hex) => u32::from_str_radix(hex, 16).ok()?,
                None => name.strip_prefix('#')?.parse().ok()?,
            };
            char::from_u32(code)
        }
    }
}

/// The URDF text's elements, for checking what urdf-rs would reject with no position, and for
/// locating diagnostics.
struct Source<'a> {
    file: FileId,
    xml: &'a str,
    elements: Vec<Element>,
    children: Vec<Vec<usize>>,
    /// Whether urdf-rs reads each element (see [`READ`]).
    read: Vec<bool>,
}

/// The elements urdf-rs reads, by the element they are in, from `<robot>` down. Any other
/// element, and everything inside it, is skipped by urdf-rs: an extension such as Pinocchio's
/// `<collision_checking>` in a link, whose `<capsule name="..."/>` is not a shape.
const READ: &[(&str, &[&str])] = &[
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
fn reads(parent: &str, tag: &str) -> bool {
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

impl<'a> Source<'a> {
    fn scan(file: FileId, xml: &'a str) -> Result<Source<'a>, Diagnostic> {
        let elements = scan(xml).map_err(|e| {
            Diagnostic::error("E1001", format!("malformed XML: {}", e.message))
                .primary(Span::new(file, e.range.0, e.range.1), e.label)
                .help("a URDF file is an XML document whose root element is `<robot>`")
        })?;
        let mut children = vec![Vec::new(); elements.len()];
        // Parents come before their children, so `read[parent]` is known when it is needed.
        let mut read = Vec::with_capacity(elements.len());
        for (index, element) in elements.iter().enumerate() {
            read.push(match element.parent {
                Some(parent) => read[parent] && reads(&elements[parent].tag, &element.tag),
                None => element.tag == "robot",
            });
            if let Some(parent) = element.parent {
                children[parent].push(index);
            }
        }
        Ok(Source {
            file,
            xml,
            elements,
            children,
            read,
        })
    }

    /// The text handed to urdf-rs: the URDF with the elements that urdf-rs would reject but
    /// the import does not use blanked out, byte for byte and keeping the line breaks, so that
    /// offsets and lines stay those of the file. These are the `<texture>` elements without a
    /// `filename` (`<texture />` in the materials of some robots): urdf-rs requires the
    /// attribute, and materials are not imported (W1007).
    fn urdf_text(&self) -> Cow<'a, str> {
        let xml = self.xml;
        let mut blanked = self
            .elements
            .iter()
            .filter(|e| e.tag == "texture" && e.attribute("filename").is_none())
            .peekable();
        if blanked.peek().is_none() {
            return Cow::Borrowed(xml);
        }
        let mut text = String::with_capacity(xml.len());
        let mut at = 0;
        for element in blanked {
            let (start, end) = (element.range.0, element.end);
            if start < at {
                continue; // inside an element already blanked
            }
            text.push_str(&xml[at..start]);
            for c in xml[start..end].chars() {
                match c {
                    '\n' | '\r' => text.push(c),
                    _ => text.extend(std::iter::repeat_n(' ', c.len_utf8())),
                }
            }
            at = end;
        }
        text.push_str(&xml[at..]);
        Cow::Owned(text)
    }

    fn span(&self, index: usize) -> Span {
        let (start, end) = self.elements[index].range;
        Span::new(self.file, start, end)
    }

    /// The span of an attribute, or of its element when it has no such attribute.
    fn attribute_span(&self, index: usize, name: &str) -> Span {
        match self.elements[index].attribute(name) {
            Some(a) => Span::new(self.file, a.range.0, a.range.1),
            None => self.span(index),
        }
    }

    fn attribute(&self, index: usize, name: &str) -> Option<&str> {
        self.elements[index]
            .attribute(name)
            .map(|a| a.value.as_str())
    }

    fn child(&self, parent: usize, tag: &str) -> Option<usize> {
        self.children[parent]
            .iter()
            .copied()
            .find(|&c| self.elements[c].tag == tag)
    }

    /// The elements of the robot (children of the root) with this tag.
    fn top_level<'s>(&'s self, tag: &'s str) -> impl Iterator<Item = usize> + 's {
        self.children[0]
            .iter()
            .copied()
            .filter(move |&c| self.elements[c].tag == tag)
    }

    /// The link or joint elements called `name`, in document order.
    fn named<'s>(&'s self, tag: &'s str, name: &'s str) -> impl Iterator<Item = usize> + 's {
        self.top_level(tag)
            .filter(move |&c| self.attribute(c, "name") == Some(name))
    }

    /// The first link or joint element called `name` (the root if there is none, so that a
    /// diagnostic always has a place).
    fn element(&self, tag: &str, name: &str) -> usize {
        self.named(tag, name).next().unwrap_or(0)
    }

    fn line(&self, index: usize) -> usize {
        self.xml[..self.elements[index].range.0]
            .matches('\n')
            .count()
            + 1
    }

    fn invalid(
        &self,
        span: Span,
        message: impl Into<String>,
        label: impl Into<String>,
    ) -> Diagnostic {
        Diagnostic::error("E1002", message).primary(span, label)
    }

    /// urdf-rs rejected a text that passed the checks below; its message has no position.
    fn rejected(&self, reason: &str) -> Diagnostic {
        self.invalid(
            self.span(0),
            format!("not a valid URDF file: {reason}"),
            "in this robot",
        )
        .help("the URDF format is described at http://wiki.ros.org/urdf/XML")
    }

    /// What urdf-rs requires, checked first so that the error says where it is.
    fn check_structure(&self) -> Result<(), Diagnostic> {
        let root = &self.elements[0];
        if root.tag != "robot" {
            return Err(self
                .invalid(self.span(0), format!("the root element is `<{}>`, not `<robot>`", root.tag), "expected `<robot>`")
                .help("a URDF file describes one robot: `<robot name=\"...\"> <link .../> <joint .../> </robot>`"));
        }
        for &top in &self.children[0] {
            match self.elements[top].tag.as_str() {
                "link" => self.check_link(top)?,
                "joint" => self.check_joint(top)?,
                _ => {}
            }
        }
        Ok(())
    }

    fn check_link(&self, link: usize) -> Result<(), Diagnostic> {
        self.required_attribute(link, "name")?;
        if let Some(inertial) = self.child(link, "inertial") {
            self.required_child(inertial, "mass")?;
            self.required_child(inertial, "inertia")?;
        }
        for &shape in &self.children[link] {
            if matches!(self.elements[shape].tag.as_str(), "visual" | "collision") {
                self.required_child(shape, "geometry")?;
            }
        }
        self.check_numbers_below(link)
    }

    fn check_joint(&self, joint: usize) -> Result<(), Diagnostic> {
        self.required_attribute(joint, "name")?;
        let kind = self.required_attribute(joint, "type")?;
        if !JOINT_TYPES.contains(&kind) {
            let diagnostic = self.invalid(
                self.attribute_span(joint, "type"),
                format!("unknown joint type `{kind}`"),
                "not a URDF joint type",
            );
            return Err(
                match suggest::did_you_mean(kind, JOINT_TYPES.iter().copied()) {
                    Some(known) => diagnostic.help(format!("did you mean `{known}`?")),
                    None => {
                        diagnostic.help(format!("the joint types are {}", JOINT_TYPES.join(", ")))
                    }
                },
            );
        }
        for tag in ["parent", "child"] {
            let element = self.required_child(joint, tag)?;
            self.required_attribute(element, "link")?;
        }
        self.check_numbers_below(joint)
    }

    fn required_attribute(&self, index: usize, name: &str) -> Result<&str, Diagnostic> {
        self.attribute(index, name).ok_or_else(|| {
            let tag = &self.elements[index].tag;
            self.invalid(
                self.span(index),
                format!("`<{tag}>` has no `{name}` attribute"),
                format!("`{name}` is required"),
            )
        })
    }

    fn required_child(&self, parent: usize, tag: &str) -> Result<usize, Diagnostic> {
        self.child(parent, tag).ok_or_else(|| {
            let outer = &self.elements[parent].tag;
            self.invalid(
                self.span(parent),
                format!("`<{outer}>` has no `<{tag}>` element"),
                format!("`<{tag}>` is required here"),
            )
        })
    }

    /// Checks the numbers of `top` (a link or joint) and of every element inside it: the
    /// elements that follow it in document order up to the first one whose parent comes before it.
    fn check_numbers_below(&self, top: usize) -> Result<(), Diagnostic> {
        let end = (top + 1..self.elements.len())
            .find(|&i| self.elements[i].parent.is_none_or(|p| p < top))
            .unwrap_or(self.elements.len());
        (top..end).try_for_each(|index| self.check_numbers(index))
    }

    /// Checks the numbers of an element urdf-rs reads: the same tag elsewhere is not read
    /// (`<capsule name="test"/>` in Pinocchio's `<collision_checking>` is not a shape).
    fn check_numbers(&self, index: usize) -> Result<(), Diagnostic> {
        if !self.read[index] {
            return Ok(());
        }
        let element = &self.elements[index];
        for &(tag, name, count, required) in NUMBERS.iter().filter(|(tag, ..)| *tag == element.tag)
        {
            let Some(attribute) = element.attribute(name) else {
                if required {
                    self.required_attribute(index, name)?;
                }
                continue;
            };
            let numbers: Vec<Option<f64>> = attribute
                .value
                .split_whitespace()
                .map(|t| t.parse::<f64>().ok().filter(|x| x.is_finite()))
                .collect();
            if numbers.len() != count || numbers.contains(&None) {
                let expected = if count == 1 {
                    "a finite number".to_string()
                } else {
                    format!("{count} finite numbers")
                };
                let message = format!(
                    "`{name}` of `<{tag}>` must be {expected}, not `{}`",
                    attribute.value
                );
                return Err(self.invalid(
                    self.attribute_span(index, name),
                    message,
                    format!("expected {expected}"),
                ));
            }
        }
        Ok(())
    }
}

// ---------------------------------------------------------------------------------------------
// The tree of links
// ---------------------------------------------------------------------------------------------

/// The links and joints as a tree: URDF requires one, and LSD's join of the root to earth
/// assumes it.
struct Tree {
    /// Parent and child link of each joint.
    joint_links: Vec<(usize, usize)>,
    root: usize,
}

impl Tree {
    fn build(robot: &Robot, source: &Source) -> Result<Tree, Diagnostic> {
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
                .primary(source.span(0), "no `<link>` in this robot")
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
            let (first, second) = (elements.next().unwrap_or(0), elements.next().unwrap_or(0));
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
    let at = source.child(element, role).unwrap_or(element);
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
    let child = &robot.joints[second].child.link;
    let at = |joint: usize| {
        let element = source.element("joint", &robot.joints[joint].name);
        source.span(source.child(element, "child").unwrap_or(element))
    };
    let (first_name, second_name) = (&robot.joints[first].name, &robot.joints[second].name);
    Diagnostic::error("E1005", format!("link `{child}` is the child of two joints, `{first_name}` and `{second_name}`"))
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

// ---------------------------------------------------------------------------------------------
// The LSD program
// ---------------------------------------------------------------------------------------------

#[derive(Default)]
struct Names {
    links: Vec<String>,
    joints: Vec<String>,
    /// The join of the root link to earth.
    base: String,
}

struct Importer<'a> {
    robot: &'a Robot,
    source: &'a Source<'a>,
    tree: &'a Tree,
    options: &'a ImportOptions,
    names: Names,
    warnings: Vec<Diagnostic>,
}

impl Importer<'_> {
    fn program(&mut self, file_name: &str) -> Result<String, Diagnostic> {
        self.assign_names();
        let mut out = self.header(file_name);
        out += "import joints ;\n";
        if self.options.gravity {
            out += "import gravity ;\n";
        }
        out += "\n(* Links *)\n";
        for index in 0..self.robot.links.len() {
            out += &self.link(index);
        }
        out += "\n(* Joints *)\n";
        out += &self.base_joint();
        for index in 0..self.robot.joints.len() {
            out += &self.joint(index)?;
            self.joint_warnings(index);
        }
        out += &self.gravity();
        self.geometry_warning();
        self.unsupported_warnings();
        Ok(out)
    }

    fn header(&self, file_name: &str) -> String {
        let root = &self.names.links[self.tree.root];
        let base = if self.options.floating_base {
            format!(
                "is free, a floating base joined to earth by `{}`",
                self.names.base
            )
        } else {
            "is welded to earth".to_string()
        };
        let gravity = if self.options.gravity {
            "Standard gravity pulls every link with mass along -z."
        } else {
            "No gravity."
        };
        let robot = if self.robot.name.is_empty() {
            "Robot".to_string()
        } else {
            format!("Robot `{}`", self.robot.name)
        };
        let text = format!(
            "{robot}, imported from the URDF file `{file_name}`.\n   \
             Units are URDF's: m, rad, kg, kg m². Each link is a body whose reference frame is the link\n   \
             frame, with `iframe` at its centre of mass along its principal axes of inertia. Each joint\n   \
             joins its origin on the parent link to the child link's frame.\n   \
             The root link `{root}` {base}.\n   \
             {gravity}"
        );
        comment(&text) + "\n\n"
    }

    /// Gives every link and joint its LSD name: first the names that can stay as they are, in the
    /// order of the file, links first; then the others, renamed by [`lsd_name`] and made unique.
    fn assign_names(&mut self) {
        let robot = self.robot;
        let requests: Vec<(&str, &str)> = robot
            .links
            .iter()
            .map(|l| ("link", l.name.as_str()))
            .chain(robot.joints.iter().map(|j| ("joint", j.name.as_str())))
            .collect();
        let mut used = HashSet::new();
        let mut assigned: Vec<Option<String>> = requests
            .iter()
            .map(|(_, name)| {
                (lsd_name(name) == *name && used.insert(name.to_string())).then(|| name.to_string())
            })
            .collect();
        for (slot, &(tag, name)) in assigned.iter_mut().zip(&requests) {
            if slot.is_none() {
                let mut candidate = lsd_name(name);
                while !used.insert(candidate.clone()) {
                    candidate.push('_');
                }
                self.warnings
                    .push(self.rename_warning(tag, name, &candidate));
                *slot = Some(candidate);
            }
        }
        let mut names = assigned.into_iter().flatten();
        self.names.links = names.by_ref().take(robot.links.len()).collect();
        self.names.joints = names.collect();
        let mut base = if self.options.floating_base {
            "root_joint"
        } else {
            "world_joint"
        }
        .to_string();
        while used.contains(&base) {
            base.push('_');
        }
        self.names.base = base;
    }

    fn rename_warning(&self, tag: &str, name: &str, lsd: &str) -> Diagnostic {
        let reason = if lsd_name(name) == name {
            "another link or joint has this name (links and joints share one name space in LSD)"
                .to_string()
        } else if reserved().contains(name) {
            format!("`{name}` is a builtin or standard library name that the program uses")
        } else if is_identifier(&format!("{name}_")) && !is_identifier(name) {
            format!("`{name}` is an LSD keyword")
        } else {
            "an LSD name is letters, digits and `_`, and does not start with a digit".to_string()
        };
        let element = self.source.named(tag, name).next().unwrap_or(0);
        Diagnostic::warning("W1001", format!("{tag} `{name}` is called `{lsd}` in LSD"))
            .primary(self.source.attribute_span(element, "name"), "renamed")
            .note(reason)
    }

    /// The program's comment after a renamed link or joint: its URDF name.
    fn original(&self, tag: &str, name: &str, lsd: &str) -> String {
        if name == lsd {
            String::new()
        } else {
            format!(" {}", comment(&format!("URDF {tag} \"{name}\"")))
        }
    }

    fn link(&mut self, index: usize) -> String {
        let link = &self.robot.links[index];
        let inertial = &link.inertial;
        let body = if is_massless(inertial) {
            "body mass = 0, inertia = 0 end".to_string()
        } else {
            let principal = principal(&tensor(inertial));
            self.check_inertia(index, &principal.moments);
            let mut rotation = rpy_factors(&inertial.origin.rpy);
            rotation.extend(
                principal
                    .axes
                    .as_ref()
                    .and_then(axis_angle)
                    .map(|(angle, axis)| factor(angle, axis)),
            );
            format!(
                "body mass = {}, iframe = {}, inertia = {} end",
                number(inertial.mass.value),
                displacement(inertial.origin.xyz.0, &rotation),
                vector(principal.moments.into())
            )
        };
        let name = &self.names.links[index];
        format!(
            "let {name} = {body} ;{}\n",
            self.original("link", &link.name, name)
        )
    }

    /// A warning when the link's mass and inertia are not those of a rigid body.
    fn check_inertia(&mut self, index: usize, moments: &Vector3<f64>) {
        let link = &self.robot.links[index];
        let mass = link.inertial.mass.value;
        let tolerance = 1e-12 * moments.amax();
        let mut problems = Vec::new();
        if mass < 0.0 {
            problems.push(format!("its mass {} is negative", number(mass)));
        } else if mass == 0.0 {
            problems.push("it has inertia but no mass".to_string());
        }
        if moments.min() < -tolerance {
            problems.push(
                "its inertia tensor is not positive definite (a negative principal moment)"
                    .to_string(),
            );
        } else if moments.min() <= tolerance {
            problems.push("its inertia tensor is not positive definite (a zero principal moment, as of a point mass or a thin rod)".to_string());
        }
        let mut sorted = [moments.x, moments.y, moments.z];
        sorted.sort_by(f64::total_cmp);
        if sorted[0] + sorted[1] < sorted[2] - tolerance {
            problems.push("its principal moments violate the triangle inequality".to_string());
        }
        if problems.is_empty() {
            return;
        }
        let element = self.source.element("link", &link.name);
        let inertial = self.source.child(element, "inertial");
        let at = inertial
            .and_then(|i| self.source.child(i, "inertia"))
            .or(inertial)
            .unwrap_or(element);
        self.warnings.push(
            Diagnostic::warning("W1010", format!("the inertia of link `{}` is not physically consistent: {}", link.name, problems.join("; ")))
                .primary(self.source.span(at), "imported as written")
                .note(format!("mass {}, principal moments {}, {}, {}", number(mass), number(moments.x), number(moments.y), number(moments.z)))
                .note("a rigid body has a positive mass and principal moments with I1 + I2 ≥ I3 for any two of them and the third")
                .help("the moments are about the centre of mass, in kg m²: check the URDF's `<inertia>` and `<mass>`"),
        );
    }

    fn base_joint(&self) -> String {
        let link = if self.options.floating_base {
            "free"
        } else {
            "weld"
        };
        format!(
            "join earth and {} with {link} as {} ;\n",
            self.names.links[self.tree.root], self.names.base
        )
    }

    fn joint(&mut self, index: usize) -> Result<String, Diagnostic> {
        let joint = &self.robot.joints[index];
        let (parent, child) = self.tree.joint_links[index];
        let first = frame(&joint.origin, &self.names.links[parent]);
        let link = self.joint_link(index)?;
        let name = &self.names.joints[index];
        Ok(format!(
            "join {first} and {} with {link} as {name} ;{}\n",
            self.names.links[child],
            self.original("joint", &joint.name, name)
        ))
    }

    /// The LSD link of a URDF joint type.
    fn joint_link(&mut self, index: usize) -> Result<String, Diagnostic> {
        Ok(match self.robot.joints[index].joint_type {
            JointType::Revolute => format!("revolute({})", vector(self.axis(index)?.into())),
            JointType::Continuous => format!("continuous({})", vector(self.axis(index)?.into())),
            JointType::Prismatic => format!("prismatic({})", vector(self.axis(index)?.into())),
            JointType::Planar => planar(&self.axis(index)?),
            JointType::Fixed => "weld".to_string(),
            JointType::Floating => "free".to_string(),
            JointType::Spherical => "spherical".to_string(),
        })
    }

    /// The joint's axis as a unit vector; a warning when the URDF's was not one.
    fn axis(&mut self, index: usize) -> Result<Vector3<f64>, Diagnostic> {
        let joint = &self.robot.joints[index];
        let axis = Vector3::from(joint.axis.xyz.0);
        let element = self.source.element("joint", &joint.name);
        let at = self
            .source
            .child(element, "axis")
            .map_or(self.source.span(element), |a| {
                self.source.attribute_span(a, "xyz")
            });
        if axis == Vector3::zeros() {
            return Err(Diagnostic::error(
                "E1008",
                format!("the axis of joint `{}` is zero", joint.name),
            )
            .primary(at, "no direction")
            .help("give the direction of the motion, e.g. `<axis xyz=\"0 0 1\"/>`"));
        }
        let length = axis.norm();
        if (length - 1.0).abs() <= 4.0 * f64::EPSILON {
            return Ok(axis);
        }
        // Scaled first so that huge or tiny components neither overflow nor underflow.
        let unit = (axis / axis.amax()).normalize();
        if (length - 1.0).abs() > 1e-9 {
            self.warnings.push(
                Diagnostic::warning(
                    "W1009",
                    format!("the axis of joint `{}` is not a unit vector", joint.name),
                )
                .primary(at, format!("its length is {}", number(length)))
                .note(format!("it is imported as {}", vector(unit.into()))),
            );
        }
        Ok(unit)
    }

    /// What each joint's elements say that LSD does not model.
    fn joint_warnings(&mut self, index: usize) {
        let joint = &self.robot.joints[index];
        let element = self.source.element("joint", &joint.name);
        let child = |tag: &str| self.source.child(element, tag);
        let mut found = Vec::new();
        if let Some(limit) = child("limit") {
            found.push(self.joint_warning(limit, "W1002", format!("the limits of joint `{}` are not modelled", joint.name))
                .help("the imported joint moves without limits; a stop can be written as a link effort"));
        }
        if let (Some(mimic), Some(element)) = (&joint.mimic, child("mimic")) {
            let (multiplier, offset) =
                (mimic.multiplier.unwrap_or(1.0), mimic.offset.unwrap_or(0.0));
            let message = format!(
                "joint `{}` mimics joint `{}` but is imported as an independent joint",
                joint.name, mimic.joint
            );
            found.push(Diagnostic::warning("W1003", message)
                .primary(self.source.span(element), "not imported")
                .note(format!("in URDF its position is {} × `{}` + {}", number(multiplier), mimic.joint, number(offset)))
                .help("it gets its own coordinate: give it `initial` values consistent with the joint it mimics"));
        }
        if let (Some(dynamics), Some(element)) = (&joint.dynamics, child("dynamics")) {
            if dynamics.damping != 0.0 || dynamics.friction != 0.0 {
                let effort = if joint.joint_type == JointType::Prismatic {
                    "force"
                } else {
                    "torque"
                };
                found.push(self.joint_warning(element, "W1004", format!("the damping and friction of joint `{}` are not modelled", joint.name))
                    .help(format!("viscous damping can be written as a link effort: `{effort} = (-{} * q') * axis`", number(dynamics.damping))));
            }
        }
        if let Some(controller) = child("safety_controller") {
            found.push(
                self.joint_warning(
                    controller,
                    "W1005",
                    format!(
                        "the safety controller of joint `{}` is not modelled",
                        joint.name
                    ),
                )
                .help("soft limits and controller gains are not part of the mechanism"),
            );
        }
        if let Some(calibration) = child("calibration") {
            found.push(
                self.joint_warning(
                    calibration,
                    "W1006",
                    format!("the calibration of joint `{}` is not imported", joint.name),
                )
                .help("reference positions of sensors are not part of the mechanism"),
            );
        }
        self.warnings.extend(found);
    }

    /// A warning at a joint's child element, with its attributes as the URDF gives them.
    fn joint_warning(&self, element: usize, code: &'static str, message: String) -> Diagnostic {
        let given: Vec<String> = self.source.elements[element]
            .attributes
            .iter()
            .map(|a| format!("{} = {}", a.name, a.value))
            .collect();
        let diagnostic =
            Diagnostic::warning(code, message).primary(self.source.span(element), "not imported");
        if given.is_empty() {
            diagnostic
        } else {
            diagnostic.note(format!("the URDF gives {}", given.join(", ")))
        }
    }

    fn gravity(&self) -> String {
        if !self.options.gravity {
            return String::new();
        }
        let mut out = String::from(
            "\n(* Gravity: the weight of every link with mass, at its centre of mass *)\n",
        );
        for (link, name) in self.robot.links.iter().zip(&self.names.links) {
            if link.inertial.mass.value != 0.0 {
                out += &format!("apply weight({name}) on {name}.iframe ;\n");
            }
        }
        out
    }

    /// One warning for all the shapes and materials, which LSD has no place for.
    fn geometry_warning(&mut self) {
        let source = self.source;
        let is_top_link = |index: usize| {
            source.elements[index].tag == "link" && source.elements[index].parent == Some(0)
        };
        let is_shape = |index: usize| match source.elements[index].tag.as_str() {
            "visual" | "collision" => source.elements[index].parent.is_some_and(is_top_link),
            "material" => source.elements[index].parent == Some(0),
            _ => false,
        };
        let Some(first) = (0..source.elements.len()).find(|&i| is_shape(i)) else {
            return;
        };
        let links = &self.robot.links;
        let shaped = links
            .iter()
            .filter(|l| !l.visual.is_empty() || !l.collision.is_empty())
            .count();
        let visual = links.iter().filter(|l| !l.visual.is_empty()).count();
        let collision = links.iter().filter(|l| !l.collision.is_empty()).count();
        let materials = source.top_level("material").count();
        let message = match shaped {
            0 => "the robot's materials are not imported".to_string(),
            n => format!(
                "the visual and collision geometry of {} is not imported",
                count(n, "link")
            ),
        };
        let mut diagnostic =
            Diagnostic::warning("W1007", message).primary(source.span(first), "the first of them");
        if shaped > 0 {
            let links = count(links.len(), "link");
            diagnostic = diagnostic.note(format!("of the robot's {links}, {visual} with `<visual>` and {collision} with `<collision>` elements"));
        }
        if materials > 0 {
            diagnostic = diagnostic.note(format!(
                "the robot defines {}",
                count(materials, "material")
            ));
        }
        let help = "LSD describes bodies, joints and efforts, not shapes: the bodies' mass properties come from `<inertial>`";
        self.warnings.push(diagnostic.help(help));
    }

    /// A warning for each kind of element that urdf-rs does not read: in the robot, any element
    /// but a link, joint or material; in a link or a joint, any element urdf-rs does not read
    /// there (see [`READ`]), such as Pinocchio's `<collision_checking>`.
    fn unsupported_warnings(&mut self) {
        let source = self.source;
        // (the link or joint the elements are in, or `None` for the robot; their tag; them)
        let mut groups: Vec<(Option<&str>, &str, Vec<usize>)> = Vec::new();
        for &top in &source.children[0] {
            let top_tag = source.elements[top].tag.as_str();
            let found: Vec<(Option<&str>, usize)> = match top_tag {
                "link" | "joint" => source.children[top]
                    .iter()
                    .filter(|&&c| !reads(top_tag, &source.elements[c].tag))
                    .map(|&c| (Some(top_tag), c))
                    .collect(),
                "material" => Vec::new(),
                _ => vec![(None, top)],
            };
            for (owner, element) in found {
                let tag = source.elements[element].tag.as_str();
                match groups.iter_mut().find(|(o, t, _)| *o == owner && *t == tag) {
                    Some((_, _, all)) => all.push(element),
                    None => groups.push((owner, tag, vec![element])),
                }
            }
        }
        for (owner, tag, all) in groups {
            let place = match owner {
                None => String::new(),
                Some(owner) => {
                    let mut names: Vec<&str> = all
                        .iter()
                        .filter_map(|&e| source.elements[e].parent)
                        .map(|p| source.attribute(p, "name").unwrap_or(""))
                        .collect();
                    names.dedup();
                    match names.as_slice() {
                        [name] => format!(" of {owner} `{name}`"),
                        _ => format!(" of {} {owner}s", names.len()),
                    }
                }
            };
            let message = match all.len() {
                1 => format!("`<{tag}>`{place} is not imported"),
                n => format!("{n} `<{tag}>` elements{place} are not imported"),
            };
            let mut diagnostic =
                Diagnostic::warning("W1008", message).primary(source.span(all[0]), "not imported");
            if all.len() > 1 {
                let lines: Vec<String> = all[1..]
                    .iter()
                    .map(|&e| source.line(e).to_string())
                    .collect();
                let others = if lines.len() == 1 {
                    "the other is at line"
                } else {
                    "the others are at lines"
                };
                diagnostic = diagnostic.note(format!("{others} {}", lines.join(", ")));
            }
            let help = match (owner, tag) {
                (None, "transmission") => {
                    "transmissions (actuators, gear ratios) are outside the mechanism: apply the actuators' efforts with `apply` or link efforts"
                }
                (None, "gazebo") => "settings for the Gazebo simulator have no meaning in LSD",
                (None, _) => "LSD imports a robot's links and joints",
                (Some(_), "collision_checking") => "Pinocchio's collision-checking settings are about shapes, which LSD does not describe",
                (Some("link"), _) => "LSD imports a link's mass properties, its `<inertial>`",
                (Some(_), _) => "LSD imports a joint's `type`, `<origin>`, `<parent>`, `<child>` and `<axis>`",
            };
            self.warnings.push(diagnostic.help(help));
        }
    }
}

fn count(n: usize, noun: &str) -> String {
    format!("{n} {noun}{}", if n == 1 { "" } else { "s" })
}

/// A program comment around `text`, in which `(*` or `*)` would open or close a comment.
fn comment(text: &str) -> String {
    format!("(* {} *)", text.replace("(*", "( *").replace("*)", "* )"))
}

// ---------------------------------------------------------------------------------------------
// Mass properties
// ---------------------------------------------------------------------------------------------

fn is_massless(inertial: &Inertial) -> bool {
    let i = &inertial.inertia;
    inertial.mass.value == 0.0 && [i.ixx, i.ixy, i.ixz, i.iyy, i.iyz, i.izz] == [0.0; 6]
}

/// The inertia tensor about the centre of mass, in the inertial origin's frame.
fn tensor(inertial: &Inertial) -> Matrix3<f64> {
    let i = &inertial.inertia;
    Matrix3::new(
        i.ixx, i.ixy, i.ixz, i.ixy, i.iyy, i.iyz, i.ixz, i.iyz, i.izz,
    )
}

/// Principal moments, and the rotation from the tensor's frame to the principal axes (its
/// columns), `None` when the tensor is already diagonal.
struct Principal {
    moments: Vector3<f64>,
    axes: Option<Rotation3<f64>>,
}

fn principal(tensor: &Matrix3<f64>) -> Principal {
    let off_diagonal = [tensor[(0, 1)], tensor[(0, 2)], tensor[(1, 2)]];
    if off_diagonal == [0.0; 3] {
        return Principal {
            moments: tensor.diagonal(),
            axes: None,
        };
    }
    let eigen = SymmetricEigen::new(*tensor);
    let (axes, moments) = closest_frame(&eigen.eigenvectors, &eigen.eigenvalues);
    Principal {
        moments,
        axes: Some(axes),
    }
}

/// Among the orders and directions of the eigenvectors that make a proper rotation, the one
/// closest to the identity (largest trace): each principal axis goes with the nearest axis of the
/// tensor's frame, so a nearly diagonal tensor gets a small rotation and its moments keep their
/// order.
fn closest_frame(vectors: &Matrix3<f64>, values: &Vector3<f64>) -> (Rotation3<f64>, Vector3<f64>) {
    const ORDERS: [[usize; 3]; 6] = [
        [0, 1, 2],
        [0, 2, 1],
        [1, 0, 2],
        [1, 2, 0],
        [2, 0, 1],
        [2, 1, 0],
    ];
    let candidates = ORDERS.iter().flat_map(|order| {
        (0..8).map(move |signs: usize| {
            let mut frame = Matrix3::zeros();
            for (k, &column) in order.iter().enumerate() {
                let sign = if signs >> k & 1 == 1 { -1.0 } else { 1.0 };
                frame.set_column(k, &(vectors.column(column) * sign));
            }
            (
                frame,
                Vector3::new(values[order[0]], values[order[1]], values[order[2]]),
            )
        })
    });
    let best = candidates
        .filter(|(frame, _)| frame.determinant() > 0.0)
        .max_by(|a, b| a.0.trace().total_cmp(&b.0.trace()));
    let (frame, moments) = best.unwrap_or((Matrix3::identity(), *values));
    (Rotation3::from_matrix_unchecked(frame), moments)
}

/// `angle || axis` of a rotation, through its quaternion: `atan2` keeps every digit of the angle,
/// small or near a half turn (the `acos` of the trace would lose half of them).
fn axis_angle(rotation: &Rotation3<f64>) -> Option<(f64, Vector3<f64>)> {
    let q = UnitQuaternion::from_rotation_matrix(rotation).into_inner();
    let (w, v) = if q.w < 0.0 {
        (-q.w, -q.imag())
    } else {
        (q.w, q.imag())
    };
    let s = v.norm();
    (s > 0.0).then(|| (2.0 * s.atan2(w), v / s))
}

// ---------------------------------------------------------------------------------------------
// Writing LSD
// ---------------------------------------------------------------------------------------------

/// A number as LSD reads it back exactly: Rust's shortest round-trip digits, positional for usual
/// magnitudes and with an exponent for very small or large ones (`{}` alone writes 1e-300 with
/// 300 zeros). The sign is LSD's unary minus, and `-0` is `0`.
fn number(x: f64) -> String {
    if x == 0.0 {
        return "0".to_string();
    }
    let magnitude = x.abs();
    let digits = if (1e-5..1e16).contains(&magnitude) {
        format!("{magnitude}")
    } else {
        format!("{magnitude:e}")
    };
    if x < 0.0 {
        format!("-{digits}")
    } else {
        digits
    }
}

fn vector(v: [f64; 3]) -> String {
    format!("[{}, {}, {}]", number(v[0]), number(v[1]), number(v[2]))
}

/// `(angle || axis)`, in parentheses as `||` binds more loosely than `++`, `@` and `*`.
fn factor(angle: f64, axis: Vector3<f64>) -> String {
    format!("({} || {})", number(angle), vector(axis.into()))
}

/// URDF's roll, pitch, yaw, fixed axes x, y, z: the rotation Rz(yaw) · Ry(pitch) · Rx(roll), as
/// LSD factors, leaving out zero angles.
fn rpy_factors(rpy: &[f64; 3]) -> Vec<String> {
    [
        (rpy[2], Vector3::z()),
        (rpy[1], Vector3::y()),
        (rpy[0], Vector3::x()),
    ]
    .into_iter()
    .filter(|(angle, _)| *angle != 0.0)
    .map(|(angle, axis)| factor(angle, axis))
    .collect()
}

/// `[x, y, z] ++ R`, with `R` the product of the factors (`1` for none).
fn displacement(xyz: [f64; 3], rotation: &[String]) -> String {
    let rotation = if rotation.is_empty() {
        "1".to_string()
    } else {
        rotation.join(" * ")
    };
    format!("{} ++ {rotation}", vector(xyz))
}

/// A frame at `origin` on `body`: the body itself when the origin is the identity.
fn frame(origin: &Pose, body: &str) -> String {
    let rotation = rpy_factors(&origin.rpy);
    if origin.xyz.0 == [0.0; 3] && rotation.is_empty() {
        body.to_string()
    } else {
        format!("{} @ {body}", displacement(origin.xyz.0, &rotation))
    }
}

/// URDF's planar joint moves in the plane normal to its axis. The standard `planar` is normal to
/// z; for another normal the same motion is written as an inline link: translations x and y along
/// two unit vectors u and w of the plane (u × w = normal), then the rotation q about the normal.
fn planar(normal: &Vector3<f64>) -> String {
    if *normal == Vector3::z() {
        return "planar".to_string();
    }
    // u: the coordinate axis after the normal's largest component, projected onto the plane, so
    // a normal along x, y or z gets the next two coordinate axes in cyclic order.
    let next = Vector3::ith((normal.iamax() + 1) % 3, 1.0);
    let u = (next - normal * normal.dot(&next)).normalize();
    let w = normal.cross(&u);
    format!(
        "link(x, y, q) dof1 = x * {} + y * {}, dof2 = q || {} end",
        vector(u.into()),
        vector(w.into()),
        vector((*normal).into())
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn import(xml: &str) -> Imported {
        import_urdf("test.urdf", xml, &ImportOptions::default()).unwrap_or_else(|d| panic!("{d:?}"))
    }

    #[test]
    fn numbers_read_back_exactly_and_lex_as_numbers() {
        for x in [
            0.1,
            1e-7,
            1e21,
            -0.5,
            2.5e-5,
            1e16,
            123456789.125,
            f64::MAX,
            f64::MIN_POSITIVE,
            5e-324,
            -3.0,
        ] {
            let text = number(x);
            let magnitude = text.trim_start_matches('-');
            let (tokens, errors) = lex(FileId(0), magnitude);
            assert!(errors.is_empty() && tokens.len() == 1, "{text}");
            assert!(matches!(tokens[0].1, Tok::Int(_) | Tok::Float(_)), "{text}");
            assert_eq!(
                magnitude.parse::<f64>().unwrap_or(f64::NAN),
                x.abs(),
                "{text}"
            );
        }
        assert_eq!(number(-0.0), "0");
        assert_eq!(number(1e-7), "1e-7");
        assert_eq!(number(0.25), "0.25");
    }

    #[test]
    fn names_follow_the_documented_rule() {
        assert_eq!(lsd_name("base_link"), "base_link");
        assert_eq!(lsd_name("base-link"), "base_link");
        assert_eq!(lsd_name("1st"), "_1st");
        assert_eq!(lsd_name("with"), "with_");
        assert_eq!(lsd_name("earth"), "earth_");
        assert_eq!(lsd_name("revolute"), "revolute_");
        assert_eq!(lsd_name("g"), "g_");
        assert_eq!(lsd_name("joints"), "joints_");
        assert_eq!(lsd_name("continuous"), "continuous_");
        assert_eq!(lsd_name("sin"), "sin_");
        assert_eq!(lsd_name("bras_rotoïde"), "bras_rotoïde");
        assert_eq!(lsd_name(""), "_");
        assert_eq!(lsd_name("a b/c"), "a_b_c");
    }

    #[test]
    fn a_nearly_diagonal_tensor_gets_a_small_rotation() {
        let tensor = Matrix3::new(3.0, 1e-3, 0.0, 1e-3, 2.0, 0.0, 0.0, 0.0, 1.0);
        let principal = principal(&tensor);
        let axes = principal.axes.expect("not diagonal");
        assert!(axes.angle() < 1e-2, "{}", axes.angle());
        assert!((principal.moments - Vector3::new(3.0, 2.0, 1.0)).amax() < 1e-5);
        let rebuilt =
            axes.matrix() * Matrix3::from_diagonal(&principal.moments) * axes.matrix().transpose();
        assert!((rebuilt - tensor).amax() < 1e-15);
    }

    #[test]
    fn axis_angle_is_exact_for_small_and_half_turns() {
        let turns = [
            (1e-9, Vector3::new(0.0, 0.6, 0.8)),
            (std::f64::consts::PI - 1e-12, Vector3::x()),
            (2.0, Vector3::new(1.0, 2.0, 3.0)),
        ];
        for (angle, axis) in turns {
            let rotation = Rotation3::from_axis_angle(&nalgebra::Unit::new_normalize(axis), angle);
            let (found, found_axis) = axis_angle(&rotation).expect("not the identity");
            let back =
                Rotation3::from_axis_angle(&nalgebra::Unit::new_normalize(found_axis), found);
            assert!(
                (back.matrix() - rotation.matrix()).amax() < 1e-15,
                "{angle}"
            );
        }
        assert!(axis_angle(&Rotation3::identity()).is_none());
    }

    #[test]
    fn malformed_xml_is_located() {
        let xml = "<robot name=\"r\">\n  <link name=\"a\">\n</robot>\n";
        let error = import_urdf("t.urdf", xml, &ImportOptions::default()).expect_err("malformed");
        assert_eq!(error.code, "E1001");
        let span = error.primary_span().expect("located");
        assert_eq!(&xml[span.range()], "</robot>");
        for xml in [
            "",
            "<robot",
            "<robot name=\"r>",
            "<robot><!-- </robot>",
            "<robot></link>",
            "text",
            "<a/><b/>",
        ] {
            let error = import_urdf("t.urdf", xml, &ImportOptions::default()).expect_err(xml);
            assert_eq!(error.code, "E1001", "{xml}");
        }
    }

    #[test]
    fn scanner_reads_attributes_and_entities() {
        let elements = scan("<?xml version=\"1.0\"?><!-- c --><robot name='a&amp;b&#x41;'><link name = \"l\" /></robot>").ok().expect("scans");
        assert_eq!(elements.len(), 2);
        assert_eq!(
            elements[0].attribute("name").map(|a| a.value.as_str()),
            Some("a&bA")
        );
        assert_eq!(elements[1].parent, Some(0));
        assert_eq!(
            elements[1].attribute("name").map(|a| a.value.as_str()),
            Some("l")
        );
    }

    #[test]
    fn textures_without_file_are_blanked_for_urdf_rs() {
        let xml = "<robot name=\"r\"><material name=\"m\"><texture a=\"é\">\n</texture><texture filename=\"t.png\"/></material><link name=\"a\"/></robot>";
        let source = Source::scan(FileId(0), xml).expect("scans");
        let text = source.urdf_text();
        assert_eq!(text.len(), xml.len());
        assert_eq!(text.matches('\n').count(), 1);
        assert!(
            !text.contains("<texture a=") && !text.contains("</texture>"),
            "{text}"
        );
        assert!(text.contains("<texture filename=\"t.png\"/>"), "{text}");
        assert!(urdf_rs::read_from_string(&text).is_ok());
        assert!(matches!(
            Source::scan(FileId(0), "<robot/>")
                .expect("scans")
                .urdf_text(),
            Cow::Borrowed(_)
        ));
    }

    #[test]
    fn planar_axes_span_the_plane() {
        assert_eq!(planar(&Vector3::z()), "planar");
        assert_eq!(
            planar(&Vector3::x()),
            "link(x, y, q) dof1 = x * [0, 1, 0] + y * [0, 0, 1], dof2 = q || [1, 0, 0] end"
        );
        assert_eq!(
            planar(&Vector3::y()),
            "link(x, y, q) dof1 = x * [0, 0, 1] + y * [1, 0, 0], dof2 = q || [0, 1, 0] end"
        );
    }

    #[test]
    fn materials_alone_are_reported_once() {
        let imported = import("<robot name=\"r\"><material name=\"m\"/><material name=\"n\"/><link name=\"a\"/></robot>");
        let messages: Vec<&str> = imported
            .warnings
            .iter()
            .map(|d| d.message.as_str())
            .collect();
        assert_eq!(messages, ["the robot's materials are not imported"]);
        assert_eq!(
            imported.warnings[0].notes,
            ["the robot defines 2 materials"]
        );
    }

    #[test]
    fn comments_cannot_be_closed_by_names() {
        let imported = import("<robot name=\"a*)b(*c\"><link name=\"x*)\"/></robot>");
        let (tokens, errors) = lex(FileId(0), &imported.text);
        assert!(errors.is_empty(), "{}", imported.text);
        assert!(matches!(tokens[0].1, Tok::Import), "{}", imported.text);
        assert!(
            imported
                .text
                .contains("let x__ = body mass = 0, inertia = 0 end ; (* URDF link \"x* )\" *)"),
            "{}",
            imported.text
        );
    }
}
