//! Code actions: the quick fixes the diagnostics carry (`Diagnostic::fix`): a did-you-mean
//! replacement, a missing `import`, a `//` comment rewritten, a number's leading digit, …

use std::collections::HashMap;

use lsp_types::{CodeAction, CodeActionKind, Range, TextEdit, WorkspaceEdit};

use crate::diag::render::describe_fix;
use crate::ide::analysis::Analysis;
use crate::ide::convert;

/// The fixes of the diagnostics whose range meets `range`.
pub fn code_actions(analysis: &Analysis, range: Range) -> Vec<CodeAction> {
    let sources = &analysis.compilation.workspace.sources;
    let mut actions = Vec::new();
    for diagnostic in &analysis.compilation.diagnostics {
        let Some(fix) = &diagnostic.fix else {
            continue;
        };
        let converted = convert::diagnostic(analysis, diagnostic);
        let meets = converted.range.start <= range.end && range.start <= converted.range.end;
        if !meets {
            continue;
        }
        let described = describe_fix(sources, fix);
        let title = described.strip_prefix("fix: ").unwrap_or(&described);
        let edit = TextEdit::new(
            convert::span_range(analysis, fix.span),
            fix.replacement.clone(),
        );
        let uri = convert::file_uri(analysis, fix.span.file());
        actions.push(CodeAction {
            title: title.to_string(),
            kind: Some(CodeActionKind::QUICKFIX),
            diagnostics: Some(vec![converted]),
            edit: Some(WorkspaceEdit::new(HashMap::from([(uri, vec![edit])]))),
            is_preferred: Some(true),
            ..Default::default()
        });
    }
    actions
}
