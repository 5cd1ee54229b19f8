//! Rendering diagnostics: as text with source snippets (codespan-reporting), or as JSON for
//! editors and CI. Both forms carry the same information.

use std::ops::Range;

use codespan_reporting::diagnostic as cs;
use codespan_reporting::files::{Error as FilesError, Files};
use codespan_reporting::term;
use serde::Serialize;

use crate::diag::{Diagnostic, Severity};
use crate::source::SourceMap;
use crate::source::{FileId, Span};

impl<'a> Files<'a> for SourceMap {
    type FileId = FileId;
    type Name = &'a str;
    type Source = &'a str;

    fn name(&'a self, id: FileId) -> Result<&'a str, FilesError> {
        Ok(&self.file(id).name)
    }

    fn source(&'a self, id: FileId) -> Result<&'a str, FilesError> {
        Ok(&self.file(id).text)
    }

    fn line_index(&'a self, id: FileId, byte_index: usize) -> Result<usize, FilesError> {
        Ok(self.file(id).line_column(byte_index).0 - 1)
    }

    fn line_range(&'a self, id: FileId, line_index: usize) -> Result<Range<usize>, FilesError> {
        let file = self.file(id);
        let start = file
            .line_start(line_index)
            .ok_or(FilesError::LineTooLarge {
                given: line_index,
                max: 0,
            })?;
        let end = file.line_start(line_index + 1).unwrap_or(file.text.len());
        Ok(start..end)
    }
}

/// Renders diagnostics as plain text, as a terminal shows them.
pub fn to_text(sources: &SourceMap, diagnostics: &[Diagnostic]) -> String {
    let config = term::Config::default();
    let mut out = String::new();
    for diagnostic in diagnostics {
        let mut rendered = to_codespan(diagnostic);
        rendered
            .notes
            .extend(diagnostic.fix.iter().map(|fix| describe_fix(sources, fix)));
        if term::emit_to_string(&mut out, &config, sources, &rendered).is_err() {
            out.push_str(&format!(
                "{}: {}\n",
                severity_word(diagnostic.severity),
                diagnostic.message
            ));
        }
    }
    out
}

/// A fix in words (the command line's note, the title of an editor's quick fix): "fix: replace `.5` by `0.5`", "fix: insert `,` at 2:17".
pub fn describe_fix(sources: &SourceMap, fix: &crate::diag::Fix) -> String {
    let file = sources.file(fix.span.file());
    let replaced = file.text.get(fix.span.range()).unwrap_or_default();
    let replacement = fix.replacement.trim_end_matches('\n');
    let (line, column) = file.line_column(fix.span.start() as usize);
    match (replaced.is_empty(), replacement.is_empty()) {
        (true, _) if fix.replacement.ends_with('\n') && column == 1 => {
            format!("fix: insert the line `{replacement}` before line {line}")
        }
        (true, _) => format!("fix: insert `{replacement}` at {line}:{column}"),
        (false, true) => format!("fix: remove `{replaced}`"),
        (false, false) => format!("fix: replace `{replaced}` by `{replacement}`"),
    }
}

fn severity_word(severity: Severity) -> &'static str {
    match severity {
        Severity::Error => "error",
        Severity::Warning => "warning",
    }
}

fn to_codespan(diagnostic: &Diagnostic) -> cs::Diagnostic<FileId> {
    let severity = match diagnostic.severity {
        Severity::Error => cs::Severity::Error,
        Severity::Warning => cs::Severity::Warning,
    };
    let labels = diagnostic
        .labels
        .iter()
        .map(|label| {
            let style = if label.primary {
                cs::LabelStyle::Primary
            } else {
                cs::LabelStyle::Secondary
            };
            cs::Label::new(style, label.span.file(), label.span.range())
                .with_message(label.message.clone())
        })
        .collect();
    let mut notes = diagnostic
        .notes
        .iter()
        .map(|n| format!("note: {n}"))
        .collect::<Vec<_>>();
    if let Some(help) = &diagnostic.help {
        notes.push(format!("help: {help}"));
    }
    cs::Diagnostic::new(severity)
        .with_code(diagnostic.code)
        .with_message(diagnostic.message.clone())
        .with_labels(labels)
        .with_notes(notes)
}

#[derive(Serialize)]
struct JsonPosition {
    file: String,
    line: usize,
    column: usize,
    end_line: usize,
    end_column: usize,
}

#[derive(Serialize)]
struct JsonLabel {
    #[serde(flatten)]
    position: JsonPosition,
    message: String,
    primary: bool,
}

#[derive(Serialize)]
struct JsonDiagnostic {
    severity: &'static str,
    code: &'static str,
    message: String,
    /// Position of the primary label (absent only for diagnostics about no particular place).
    #[serde(flatten)]
    position: Option<JsonPosition>,
    labels: Vec<JsonLabel>,
    notes: Vec<String>,
    help: Option<String>,
    /// Edits that fix the problem (none or one): replace the text from the position to the end
    /// position by `replacement` (an insertion when they are equal).
    fixes: Vec<JsonFix>,
}

#[derive(Serialize)]
struct JsonFix {
    #[serde(flatten)]
    position: JsonPosition,
    replacement: String,
}

fn position(sources: &SourceMap, span: Span) -> JsonPosition {
    let file = sources.file(span.file());
    let (line, column) = file.line_column(span.start() as usize);
    let (end_line, end_column) = file.line_column(span.end() as usize);
    JsonPosition {
        file: file.name.clone(),
        line,
        column,
        end_line,
        end_column,
    }
}

/// The JSON form of diagnostics: one object per diagnostic, with one-based lines and columns.
pub fn to_json_value(sources: &SourceMap, diagnostics: &[Diagnostic]) -> serde_json::Value {
    let list: Vec<JsonDiagnostic> = diagnostics
        .iter()
        .map(|d| JsonDiagnostic {
            severity: severity_word(d.severity),
            code: d.code,
            message: d.message.clone(),
            position: d.primary_span().map(|s| position(sources, s)),
            labels: d
                .labels
                .iter()
                .map(|l| JsonLabel {
                    position: position(sources, l.span),
                    message: l.message.clone(),
                    primary: l.primary,
                })
                .collect(),
            notes: d.notes.clone(),
            help: d.help.clone(),
            fixes: d
                .fix
                .iter()
                .map(|f| JsonFix {
                    position: position(sources, f.span),
                    replacement: f.replacement.clone(),
                })
                .collect(),
        })
        .collect();
    serde_json::to_value(list).unwrap_or(serde_json::Value::Null)
}
