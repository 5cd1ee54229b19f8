//! The URDF text as an XML document whose elements know where they are in the file.
//!
//! urdf-rs reads the values but keeps no positions, so the text is also parsed with roxmltree:
//! its nodes carry byte ranges, which become the spans of the import's diagnostics, and its
//! errors say where the text stops being well-formed XML.

use std::borrow::Cow;
use std::cell::OnceCell;
use std::collections::HashMap;
use std::ops::Range;

use roxmltree::{Document, Node, NodeId, ParsingOptions};

use crate::diag::Diagnostic;
use crate::source::{FileId, Span};

/// The deepest nesting of elements a URDF file may have, the root `<robot>` being level 1. A
/// URDF needs about five levels (`robot`, `link`, `visual`, `geometry`, `mesh`), a few more in
/// the extensions of tools; the limit is far above that, and keeps the reading of urdf-rs, whose
/// time grows with the square of the depth (100,000 levels took minutes), short.
pub const MAX_ELEMENT_NESTING: usize = 100;

/// An element of the URDF document.
pub type Element<'s, 'a> = Node<'s, 'a>;

/// The parsed URDF text, for checking what urdf-rs would reject with no position, and for
/// locating diagnostics.
pub struct Source<'a> {
    file: FileId,
    xml: &'a str,
    document: Document<'a>,
    /// The first top-level element of each tag and name, indexed at the first lookup
    /// (`element`): a scan of the document per lookup made the import of a chain of n links
    /// take time in n² (4,000 links: 0.9 s of the 1.5 s `lsdc simulate` took, by a profile).
    first_named: OnceCell<HashMap<(String, String), NodeId>>,
}

impl<'a> Source<'a> {
    /// Parses `xml`; malformed XML is an error at the place roxmltree reports.
    pub fn parse(file: FileId, xml: &'a str) -> Result<Source<'a>, Diagnostic> {
        // URDF files written by tools may carry a DOCTYPE: accept it, as urdf-rs does.
        let options = ParsingOptions {
            allow_dtd: true,
            ..ParsingOptions::default()
        };
        let document = Document::parse_with_options(xml, options)
            .map_err(|error| malformed(file, xml, &error))?;
        let source = Source {
            file,
            xml,
            document,
            first_named: OnceCell::new(),
        };
        source.limit_nesting()?;
        Ok(source)
    }

    /// E0209 at the first element nested deeper than [`MAX_ELEMENT_NESTING`]. The depths are
    /// counted in one pass over the document, each element's from its parent's, without
    /// recursion.
    fn limit_nesting(&self) -> Result<(), Diagnostic> {
        let mut depths = vec![0; self.document.descendants().count()];
        for element in self.document.descendants().filter(Node::is_element) {
            let depth = element.parent().map_or(0, |p| depths[p.id().get_usize()]) + 1;
            if depth > MAX_ELEMENT_NESTING {
                return Err(Diagnostic::error(
                    "E0209",
                    format!("the elements are nested more than {MAX_ELEMENT_NESTING} levels deep"),
                )
                .primary(
                    self.span(element),
                    format!("level {} starts here", MAX_ELEMENT_NESTING + 1),
                )
                .help("the elements of a URDF robot are a few levels deep (`<robot>`, `<link>`, `<visual>`, `<geometry>`, `<mesh>`)"));
            }
            depths[element.id().get_usize()] = depth;
        }
        Ok(())
    }

    /// The root element (`<robot>` in a URDF file).
    pub fn root(&self) -> Element<'_, 'a> {
        self.document.root_element()
    }

    /// The span of an element's start tag, `<` to `>`: pointing at the whole element would
    /// underline every line of a link.
    pub fn span(&self, element: Element) -> Span {
        let range = self.start_tag(element);
        Span::new(self.file, range.start, range.end)
    }

    /// The span of `name="value"`, or of the element's start tag when it has no such attribute.
    pub fn attribute_span(&self, element: Element, name: &str) -> Span {
        match element.attribute_node(name) {
            Some(attribute) => {
                let range = attribute.range();
                Span::new(self.file, range.start, range.end)
            }
            None => self.span(element),
        }
    }

    /// One-based line of an element's start tag.
    pub(super) fn line(&self, element: Element) -> usize {
        self.document.text_pos_at(element.range().start).row as usize
    }

    /// The first link or joint element called `name` (the root if there is none, so that a
    /// diagnostic always has a place).
    pub(super) fn element(&self, tag: &str, name: &str) -> Element<'_, 'a> {
        let index = self.first_named.get_or_init(|| {
            let mut index = HashMap::new();
            for element in children(self.root()) {
                if let Some(name) = element.attribute("name") {
                    let key = (tag_of(element).into_owned(), name.to_string());
                    index.entry(key).or_insert(element.id());
                }
            }
            index
        });
        (index.get(&(tag.to_string(), name.to_string())))
            .and_then(|&id| self.document.get_node(id))
            .unwrap_or_else(|| self.root())
    }

    /// The link or joint elements called `name`, in document order.
    pub(super) fn named<'s, 'q>(
        &'s self,
        tag: &'q str,
        name: &'q str,
    ) -> impl Iterator<Item = Element<'s, 'a>> + 'q
    where
        's: 'q,
    {
        self.top_level(tag)
            .filter(move |e| e.attribute("name") == Some(name))
    }

    /// The elements of the robot (children of the root) with this tag.
    pub(super) fn top_level<'s, 'q>(
        &'s self,
        tag: &'q str,
    ) -> impl Iterator<Item = Element<'s, 'a>> + 'q
    where
        's: 'q,
    {
        children(self.root()).filter(move |&e| tag_of(e) == tag)
    }

    /// Byte range of an element's start tag. roxmltree gives the range of the whole element
    /// and of each attribute; the tag ends at the first `>` after its name and attributes, as
    /// only spaces and `/` may come between them and the `>`. (Namespace declarations have no
    /// range, but a `>` in their URI would be very unusual.)
    fn start_tag(&self, element: Element) -> Range<usize> {
        let start = element.range().start;
        let after = element
            .attributes()
            .map(|a| a.range().end)
            .max()
            .unwrap_or(start);
        let end = self.xml[after..]
            .find('>')
            .map_or(element.range().end, |i| after + i + 1);
        start..end
    }

    /// The text handed to urdf-rs: the URDF with the elements that urdf-rs would reject but
    /// the import does not use blanked out, byte for byte and keeping the line breaks, so that
    /// offsets and lines stay those of the file. These are the `<texture>` elements without a
    /// `filename` (`<texture />` in the materials of some robots): urdf-rs requires the
    /// attribute, and materials are not imported (W1007).
    pub fn urdf_text(&self) -> Cow<'a, str> {
        let xml = self.xml;
        let mut blanked = self
            .root()
            .descendants()
            .filter(|&e| tag_of(e) == "texture" && e.attribute("filename").is_none())
            .peekable();
        if blanked.peek().is_none() {
            return Cow::Borrowed(xml);
        }
        let mut text = String::with_capacity(xml.len());
        let mut at = 0;
        for element in blanked {
            let Range { start, end } = element.range();
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
}

/// The child elements of an element (not its text or comments).
pub(super) fn children<'s, 'a>(element: Element<'s, 'a>) -> impl Iterator<Item = Element<'s, 'a>> {
    element.children().filter(Node::is_element)
}

/// The first child element with this tag.
pub fn child<'s, 'a>(element: Element<'s, 'a>, tag: &str) -> Option<Element<'s, 'a>> {
    children(element).find(|&c| tag_of(c) == tag)
}

/// The parent element, `None` for the root.
pub fn parent<'s, 'a>(element: Element<'s, 'a>) -> Option<Element<'s, 'a>> {
    element.parent().filter(Node::is_element)
}

/// An element's tag as written, with its namespace prefix if it has one (`xacro:macro`).
pub(super) fn tag_of<'a>(element: Element<'_, 'a>) -> Cow<'a, str> {
    let name = element.tag_name();
    qualified(element, name.namespace(), name.name())
}

/// An element's attributes as `(name, value)`, names as written.
pub(super) fn attributes<'s, 'a>(
    element: Element<'s, 'a>,
) -> impl Iterator<Item = (Cow<'a, str>, &'s str)> {
    element
        .attributes()
        .map(move |a| (qualified(element, a.namespace(), a.name()), a.value()))
}

/// `prefix:name` when `namespace` was declared with a prefix in scope of `element`.
fn qualified<'a>(element: Element<'_, 'a>, namespace: Option<&str>, name: &'a str) -> Cow<'a, str> {
    match namespace.and_then(|uri| element.lookup_prefix(uri)) {
        Some(prefix) if !prefix.is_empty() => Cow::Owned(format!("{prefix}:{name}")),
        _ => Cow::Borrowed(name),
    }
}

/// The diagnostic for a text that is not well-formed XML.
fn malformed(file: FileId, xml: &str, error: &roxmltree::Error) -> Diagnostic {
    let (message, label) = describe(xml, error);
    let range = error_range(xml, error);
    Diagnostic::error("E1001", format!("malformed XML: {message}"))
        .primary(Span::new(file, range.start, range.end), label)
        .help("a URDF file is an XML document whose root element is `<robot>`")
}

/// What went wrong, and the label at the place: roxmltree's own words for the rare errors,
/// without the position it appends (the span shows it).
fn describe(xml: &str, error: &roxmltree::Error) -> (String, &'static str) {
    use roxmltree::Error as E;
    match error {
        E::UnexpectedCloseTag(open, close, _) => (
            format!("`</{close}>` closes `<{open}>`"),
            "mismatched end tag",
        ),
        E::UnknownToken(pos) => unknown_token(&xml[error_range(xml, error)], *pos),
        // roxmltree also says this of a text whose only tag is never closed (`<robot`).
        E::NoRootNode if xml.trim().is_empty() => ("no element".into(), "expected `<robot>`"),
        E::NoRootNode => ("no complete element".into(), "expected `<robot>`"),
        E::UnclosedRootNode => (
            "the text ends before the root element is closed".into(),
            "the text ends here",
        ),
        E::UnexpectedEndOfStream => ("the text ends inside a tag".into(), "the text ends here"),
        E::InvalidString(close, pos) if offset(xml, *pos) == xml.len() => {
            (format!("the text ends before `{close}`"), "never closed")
        }
        _ => {
            let text = error.to_string();
            let suffix = format!(" at {}", error.pos());
            let message = text.strip_suffix(&suffix).unwrap_or(&text).to_string();
            (message, "here")
        }
    }
}

/// roxmltree's "unknown token": what is there says which.
fn unknown_token(token: &str, pos: roxmltree::TextPos) -> (String, &'static str) {
    if token.starts_with("</") {
        (format!("`{token}` closes no element"), "unexpected end tag")
    } else if token.starts_with('<') {
        (
            format!("`{token}` after the end of the root element"),
            "a second root element",
        )
    } else if pos.row == 1 && pos.col == 1 {
        (
            "text where the root element should be".into(),
            "expected `<robot>`",
        )
    } else {
        ("text outside the root element".into(), "unexpected text")
    }
}

/// The bytes to underline for an error: the tag at its position, or the character there.
fn error_range(xml: &str, error: &roxmltree::Error) -> Range<usize> {
    use roxmltree::Error as E;
    let at = match error {
        // Errors without a position: the end of the text, where it was found.
        E::UnclosedRootNode | E::UnexpectedEndOfStream => return xml.len()..xml.len(),
        E::NoRootNode => return 0..0,
        _ => offset(xml, error.pos()),
    };
    if at == xml.len() {
        if let E::InvalidString(close, _) = error {
            // A comment, CDATA section or processing instruction runs to the end of the text:
            // point at where it opens.
            if let Some(start) = opening(close).and_then(|open| xml.rfind(open)) {
                return start..start + 1;
            }
        }
        return at..at;
    }
    let tag = matches!(error, E::UnexpectedCloseTag(..) | E::UnknownToken(_));
    match xml[at..].find('>') {
        Some(end) if tag && xml[at..].starts_with('<') => at..at + end + 1,
        _ => at..at + xml[at..].chars().next().map_or(0, char::len_utf8),
    }
}

/// How the construct that `close` ends opens.
fn opening(close: &str) -> Option<&'static str> {
    match close {
        "-->" => Some("<!--"),
        "]]>" => Some("<![CDATA["),
        "?>" => Some("<?"),
        _ => None,
    }
}

/// The byte offset of roxmltree's one-based line and column (counted in characters).
fn offset(xml: &str, pos: roxmltree::TextPos) -> usize {
    let line_start: usize = xml
        .split_inclusive('\n')
        .take(pos.row as usize - 1)
        .map(str::len)
        .sum();
    let column: usize = xml[line_start..]
        .chars()
        .take(pos.col as usize - 1)
        .map(char::len_utf8)
        .sum();
    line_start + column
}
