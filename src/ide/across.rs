//! Find references and rename across files: a name defined in a library is used by every file
//! that imports it, and each file's analysis indexes only the file and what it imports. The
//! definition is therefore identified by its file and place (a [`Target`]), looked up in the
//! analysis of every open file and of every readable `.lsd` file beside them that imports it,
//! and its occurrences gathered from all of them.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use lsp_types::{Location, TextEdit, Uri, WorkspaceEdit};

use crate::ide::analysis::{Analysis, DefinitionKind, Reference};
use crate::ide::convert;
use crate::load::LoadOptions;
use crate::source::{FileId, Span};
use crate::syntax::lexer::{lex, Tok};

/// The prefix of the names the standard library's modules have in a compilation.
const STDLIB: &str = "<stdlib>/";

/// A definition, identified whichever file's analysis it is seen from.
pub struct Target {
    /// Its file: the canonical path, or `<stdlib>/module.lsd`.
    file: String,
    start: u32,
    end: u32,
    pub name: String,
    kind: DefinitionKind,
}

impl Target {
    /// The definition of the name at `offset` in the analysis's own file.
    pub fn at(analysis: &Analysis, offset: usize) -> Option<Target> {
        let occurrence = analysis.index.occurrence_at(analysis.root, offset)?;
        let Reference::Definition(id) = occurrence.reference else {
            return None;
        };
        let definition = &analysis.index.definitions[id];
        Some(Target {
            file: file_key(analysis, definition.span.file()),
            start: definition.span.start(),
            end: definition.span.end(),
            name: definition.name.to_string(),
            kind: definition.kind.clone(),
        })
    }

    fn in_stdlib(&self) -> bool {
        self.file.starts_with(STDLIB)
    }

    /// The directory of the file that defines it (none for the standard library).
    pub fn directory(&self) -> Option<PathBuf> {
        (!self.in_stdlib()).then(|| Path::new(&self.file).parent().map(Path::to_path_buf))?
    }

    /// The name a file must import to see the target: its file's stem.
    pub fn module(&self) -> &str {
        let name = self.file.rsplit('/').next().unwrap_or(&self.file);
        name.strip_suffix(".lsd").unwrap_or(name)
    }

    /// The same definition in another analysis.
    fn find(&self, analysis: &Analysis) -> Option<usize> {
        analysis.index.definitions.iter().position(|d| {
            d.span.start() == self.start
                && d.span.end() == self.end
                && *d.name == *self.name
                && file_key(analysis, d.span.file()) == self.file
        })
    }
}

/// A file's identity across analyses: its canonical path (so that `lib.lsd` and `./lib.lsd`
/// are one file), or its name in the standard library.
fn file_key(analysis: &Analysis, file: FileId) -> String {
    let name = &analysis.compilation.workspace.sources.file(file).name;
    if name.starts_with(STDLIB) {
        return name.clone();
    }
    std::fs::canonicalize(name).map_or_else(|_| name.clone(), |p| p.display().to_string())
}

/// Every occurrence of the target, each once: from the analysis whose own file it is when that
/// file is open (its text is the editor's), else from any analysis that imports it.
fn occurrences<'a>(analyses: &[&'a Analysis], target: &Target) -> Vec<(&'a Analysis, Span)> {
    let open: BTreeSet<String> = analyses.iter().map(|a| file_key(a, a.root)).collect();
    let mut seen = BTreeSet::new();
    let mut found = Vec::new();
    for &analysis in analyses {
        let Some(id) = target.find(analysis) else {
            continue;
        };
        for occurrence in analysis.index.references(id) {
            let file = file_key(analysis, occurrence.span.file());
            let own_or_closed = occurrence.span.file() == analysis.root || !open.contains(&file);
            let key = (file, occurrence.span.start(), occurrence.span.end());
            if own_or_closed && seen.insert(key) {
                found.push((analysis, occurrence.span));
            }
        }
    }
    found
}

/// Every use of the target in the analysed files; with `declaration`, its definition too.
pub fn references(analyses: &[&Analysis], target: &Target, declaration: bool) -> Vec<Location> {
    occurrences(analyses, target)
        .into_iter()
        .filter(|(analysis, span)| {
            declaration
                || !(span.start() == target.start && file_key(analysis, span.file()) == target.file)
        })
        .map(|(analysis, span)| convert::location(analysis, span))
        .collect()
}

/// Renames the target in every analysed file. The standard library's names and a library's
/// own name (its file's) are not renamed.
pub fn rename(
    analyses: &[&Analysis],
    target: &Target,
    new_name: &str,
) -> Result<WorkspaceEdit, String> {
    if target.in_stdlib() {
        return Err(format!(
            "`{}` is defined in the standard library (`{}`), which cannot be renamed",
            target.name,
            target.module()
        ));
    }
    if matches!(target.kind, DefinitionKind::Module(_)) {
        return Err(format!(
            "`{}` is a library, named by its file: rename the file",
            target.name
        ));
    }
    let (tokens, errors) = lex(FileId(0), new_name);
    if !errors.is_empty()
        || !matches!(tokens.as_slice(), [(0, Tok::Ident(_), end)] if *end == new_name.len())
    {
        return Err(format!(
            "`{new_name}` is not a name (a keyword, or not an identifier)"
        ));
    }
    // Grouped by file in a list: a map keyed by `Uri` (which caches its parts in cells) is
    // only built at the end.
    let mut changes: Vec<(Uri, Vec<TextEdit>)> = Vec::new();
    for (analysis, span) in occurrences(analyses, target) {
        let uri = convert::file_uri(analysis, span.file());
        let edit = TextEdit::new(convert::span_range(analysis, span), new_name.to_string());
        match changes.iter_mut().find(|(u, _)| *u == uri) {
            Some((_, edits)) => edits.push(edit),
            None => changes.push((uri, vec![edit])),
        }
    }
    Ok(WorkspaceEdit::new(changes.into_iter().collect()))
}

/// The `.lsd` files of `directories` that are not open and import the target's module,
/// analysed from disk: the files a reference or a rename must also reach.
pub fn readable_importers(
    directories: &BTreeSet<PathBuf>,
    open: &BTreeSet<PathBuf>,
    target: &Target,
    options: &LoadOptions,
) -> Vec<Analysis> {
    let module = target.module();
    let mut analyses = Vec::new();
    for directory in directories {
        let Ok(entries) = std::fs::read_dir(directory) else {
            continue;
        };
        let mut paths: Vec<PathBuf> = entries.filter_map(|e| Some(e.ok()?.path())).collect();
        paths.sort();
        for path in paths {
            if path.extension().is_none_or(|e| e != "lsd") {
                continue;
            }
            let canonical = std::fs::canonicalize(&path).unwrap_or_else(|_| path.clone());
            if open.contains(&canonical) {
                continue;
            }
            let Ok(text) = std::fs::read_to_string(&path) else {
                continue;
            };
            // Only a file that names the module can import it: the others are not compiled.
            let defines_it = target.file == canonical.display().to_string();
            if defines_it || (text.contains("import") && text.contains(module)) {
                analyses.push(Analysis::new(&canonical, &text, options));
            }
        }
    }
    analyses
}
