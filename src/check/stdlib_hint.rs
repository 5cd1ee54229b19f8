//! The hint for a name the program did not import: "`revolute` is in the standard library: add
//! `import joints;`", with the import offered as a fix.

use crate::diag::Diagnostic;
use crate::load::{stdlib, Workspace};
use crate::source::{FileId, Span};

/// Adds the hint to an unknown-name error when a standard-library module declares the name, or
/// the name is a module's own (`joints:revolute` without `import joints;`).
pub(super) fn import_hint(
    diagnostic: &Diagnostic,
    name: &str,
    at: Span,
    workspace: &Workspace,
) -> Option<Diagnostic> {
    let module = stdlib::find(name)
        .map(|(module, _)| module)
        .or_else(|| stdlib::module_declaring(name))?;
    let what = if module == name {
        format!("`{name}` is a standard-library module")
    } else {
        format!("`{name}` is in the standard library")
    };
    let diagnostic = diagnostic
        .clone()
        .help(format!("{what}: add `import {module};`"));
    Some(match import_position(workspace, at.file()) {
        Some(position) => diagnostic.fix(position, format!("import {module} ;\n")),
        None => diagnostic,
    })
}

/// Where an import is inserted: at the start of the line of the file's first declaration, after
/// any heading comment.
fn import_position(workspace: &Workspace, file: FileId) -> Option<Span> {
    let module = workspace.modules.iter().find(|m| m.file == file)?;
    let first = module.program.decls.first()?.span;
    let text = &workspace.sources.file(file).text;
    let line_start = text[..first.start() as usize]
        .rfind('\n')
        .map_or(0, |i| i + 1);
    Some(Span::new(file, line_start, line_start))
}
