//! Code actions: the fixes the diagnostics' help suggests, a did-you-mean replacement or a
//! missing `import`.

use std::collections::HashMap;

use lsp_types::{CodeAction, CodeActionKind, Range, TextEdit, WorkspaceEdit};

use crate::diag::Diagnostic;
use crate::ide::analysis::Analysis;
use crate::ide::convert;
use crate::syntax::ast::DeclKind;

/// The fixes for the diagnostics whose range meets `range`.
pub fn code_actions(analysis: &Analysis, range: Range) -> Vec<CodeAction> {
    let mut actions = Vec::new();
    for diagnostic in &analysis.compilation.diagnostics {
        let converted = convert::diagnostic(analysis, diagnostic);
        let meets = converted.range.start <= range.end && range.start <= converted.range.end;
        if !meets {
            continue;
        }
        let Some(help) = &diagnostic.help else {
            continue;
        };
        let fix = quoted_after(help, "did you mean ")
            .and_then(|name| replacement(analysis, diagnostic, name))
            .or_else(|| quoted_after(help, "add ").map(|import| import_edit(analysis, import)));
        if let Some((title, edit)) = fix {
            let uri = convert::file_uri(analysis, analysis.root);
            actions.push(CodeAction {
                title,
                kind: Some(CodeActionKind::QUICKFIX),
                diagnostics: Some(vec![converted]),
                edit: Some(WorkspaceEdit::new(HashMap::from([(uri, vec![edit])]))),
                is_preferred: Some(true),
                ..Default::default()
            });
        }
    }
    actions
}

/// The text in backquotes right after `marker` in a help message: "did you mean `x`?".
fn quoted_after<'h>(help: &'h str, marker: &str) -> Option<&'h str> {
    let rest = &help[help.find(marker)? + marker.len()..];
    let rest = rest.strip_prefix('`')?;
    Some(&rest[..rest.find('`')?])
}

/// Replaces the diagnostic's primary span (in the edited file) with the suggested name.
fn replacement(
    analysis: &Analysis,
    diagnostic: &Diagnostic,
    name: &str,
) -> Option<(String, TextEdit)> {
    let span = diagnostic
        .primary_span()
        .filter(|s| s.file == analysis.root)?;
    let replaced = &analysis.text(analysis.root)[span.range()];
    if replaced.contains(char::is_whitespace) {
        return None;
    }
    let edit = TextEdit::new(convert::span_range(analysis, span), name.to_string());
    Some((format!("replace `{replaced}` with `{name}`"), edit))
}

/// Inserts an `import` after the file's last import, or before its first declaration.
fn import_edit(analysis: &Analysis, import: &str) -> (String, TextEdit) {
    let workspace = &analysis.compilation.workspace;
    let decls = &workspace.module(workspace.roots[0]).program.decls;
    let text = analysis.text(analysis.root);
    let last_import = decls
        .iter()
        .rfind(|d| matches!(d.kind, DeclKind::Import(_)));
    let (offset, new_text) = match (last_import, decls.first()) {
        (Some(decl), _) => {
            let end = text[decl.span.end as usize..]
                .find('\n')
                .map_or(text.len(), |i| decl.span.end as usize + i);
            (end, format!("\n{import}"))
        }
        (None, Some(first)) => (first.span.start as usize, format!("{import}\n")),
        (None, None) => (text.len(), format!("{import}\n")),
    };
    let position = convert::position(text, offset);
    let edit = TextEdit::new(Range::new(position, position), new_text);
    (format!("add `{import}`"), edit)
}
