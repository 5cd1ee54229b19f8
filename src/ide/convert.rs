//! Between the compiler's terms and the protocol's: byte offsets and UTF-16 positions, file
//! names and `file:` URIs, diagnostics.

use std::path::{Path, PathBuf};
use std::str::FromStr;

use lsp_types::{
    DiagnosticRelatedInformation, DiagnosticSeverity, Location, NumberOrString, Position, Range,
    Uri,
};

use crate::diag::{Diagnostic, Severity};
use crate::ide::analysis::Analysis;
use crate::load::stdlib;
use crate::source::{FileId, Span};

/// The UTF-16 position of a byte offset (the protocol counts columns in UTF-16 code units).
pub fn position(text: &str, offset: usize) -> Position {
    LineStarts::new(text).position(text, offset)
}

/// Where the lines of a text start, to convert many offsets.
pub struct LineStarts(Vec<usize>);

impl LineStarts {
    pub fn new(text: &str) -> LineStarts {
        let starts = std::iter::once(0).chain(text.match_indices('\n').map(|(i, _)| i + 1));
        LineStarts(starts.collect())
    }

    pub fn position(&self, text: &str, offset: usize) -> Position {
        let offset = floor_char_boundary(text, offset.min(text.len()));
        let line = self.0.partition_point(|&start| start <= offset) - 1;
        let line_start = self.0[line];
        let character: usize = text[line_start..offset].chars().map(char::len_utf16).sum();
        Position::new(line as u32, character as u32)
    }
}

/// The byte offset of a UTF-16 position; past the end of a line, the end of the line.
pub fn offset(text: &str, position: Position) -> usize {
    let mut line_start = 0;
    for _ in 0..position.line {
        match text[line_start..].find('\n') {
            Some(i) => line_start += i + 1,
            None => return text.len(),
        }
    }
    let line_end = text[line_start..]
        .find('\n')
        .map_or(text.len(), |i| line_start + i);
    let mut units = 0;
    for (i, c) in text[line_start..line_end].char_indices() {
        if units >= position.character as usize {
            return line_start + i;
        }
        units += c.len_utf16();
    }
    line_end
}

fn floor_char_boundary(text: &str, mut offset: usize) -> usize {
    while !text.is_char_boundary(offset) {
        offset -= 1;
    }
    offset
}

pub fn range(text: &str, start: usize, end: usize) -> Range {
    Range::new(position(text, start), position(text, end))
}

/// The range of a span in its file.
pub fn span_range(analysis: &Analysis, span: Span) -> Range {
    range(
        analysis.text(span.file()),
        span.start() as usize,
        span.end() as usize,
    )
}

/// The `file:` URI of a path (absolute, or made absolute against the working directory).
pub fn path_to_uri(path: &Path) -> Uri {
    let absolute = std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf());
    let mut uri = String::from("file://");
    for byte in absolute.to_string_lossy().bytes() {
        if byte.is_ascii_alphanumeric() || b"/-._~".contains(&byte) {
            uri.push(byte as char);
        } else {
            uri.push_str(&format!("%{byte:02X}"));
        }
    }
    Uri::from_str(&uri).unwrap_or_else(|_| Uri::from_str("file:///").expect("a valid URI"))
}

/// The path of a `file:` URI.
pub fn uri_to_path(uri: &Uri) -> Option<PathBuf> {
    let path = uri.as_str().strip_prefix("file://")?;
    let bytes = path.as_bytes();
    let mut decoded = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        let escaped = (bytes[i] == b'%')
            .then(|| std::str::from_utf8(bytes.get(i + 1..i + 3)?).ok())
            .flatten()
            .and_then(|hex| u8::from_str_radix(hex, 16).ok());
        match escaped {
            Some(byte) => {
                decoded.push(byte);
                i += 3;
            }
            None => {
                decoded.push(bytes[i]);
                i += 1;
            }
        }
    }
    String::from_utf8(decoded).ok().map(PathBuf::from)
}

/// The URI of a file of the compilation. A file of the standard library (embedded in the
/// binary) is written to a directory of its own in the temporary directory, so that an editor
/// can open it.
pub fn file_uri(analysis: &Analysis, file: FileId) -> Uri {
    let name = &analysis.compilation.workspace.sources.file(file).name;
    match name
        .strip_prefix("<stdlib>/")
        .and_then(|n| n.strip_suffix(".lsd"))
    {
        Some(module) => path_to_uri(&stdlib_copy(module).unwrap_or_else(|| PathBuf::from(name))),
        None => path_to_uri(Path::new(name)),
    }
}

/// A copy of a standard library module on disk, for editors to show.
fn stdlib_copy(module: &str) -> Option<PathBuf> {
    let (name, text) = stdlib::find(module)?;
    let dir = std::env::temp_dir().join(format!("lsdc-{}-stdlib", env!("CARGO_PKG_VERSION")));
    let path = dir.join(format!("{name}.lsd"));
    if std::fs::read_to_string(&path).ok().as_deref() != Some(text) {
        std::fs::create_dir_all(&dir).ok()?;
        std::fs::write(&path, text).ok()?;
    }
    Some(path)
}

pub fn location(analysis: &Analysis, span: Span) -> Location {
    Location::new(file_uri(analysis, span.file()), span_range(analysis, span))
}

/// A diagnostic of the compilation as the protocol has it, for the root file: located at its
/// primary label when that is in the root file, else at its first label there (the import that
/// brought a library in); the other labels are related locations, and the help and notes
/// follow the message.
pub fn diagnostic(analysis: &Analysis, diagnostic: &Diagnostic) -> lsp_types::Diagnostic {
    let in_root = |span: &Span| span.file() == analysis.root;
    let primary = diagnostic.primary_span();
    let anchor = primary
        .filter(in_root)
        .or_else(|| diagnostic.labels.iter().map(|l| l.span).find(in_root))
        .unwrap_or(Span::new(analysis.root, 0, 0));
    let related = diagnostic
        .labels
        .iter()
        .filter(|label| label.span != anchor)
        .map(|label| DiagnosticRelatedInformation {
            location: location(analysis, label.span),
            message: if label.message.is_empty() {
                diagnostic.message.clone()
            } else {
                label.message.clone()
            },
        })
        .collect();
    let mut message = diagnostic.message.clone();
    for note in &diagnostic.notes {
        message.push_str(&format!("\nnote: {note}"));
    }
    if let Some(help) = &diagnostic.help {
        message.push_str(&format!("\nhelp: {help}"));
    }
    lsp_types::Diagnostic {
        range: span_range(analysis, anchor),
        severity: Some(match diagnostic.severity {
            Severity::Error => DiagnosticSeverity::ERROR,
            Severity::Warning => DiagnosticSeverity::WARNING,
        }),
        code: Some(NumberOrString::String(diagnostic.code.to_string())),
        source: Some("lsdc".to_string()),
        message,
        related_information: Some(related),
        ..Default::default()
    }
}
