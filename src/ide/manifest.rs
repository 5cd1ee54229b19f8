//! Completion in a test manifest (`lsdtest.toml`, docs/commands.md "Manifests"): the scene
//! names of a case's program in its `scene = "..."`, the one place outside the command line
//! where a scene name is written. The manifest is read line by line around the cursor, not
//! parsed: a file being typed is seldom valid TOML.

use std::path::Path;

use lsp_types::{CompletionItem, CompletionItemKind};

use crate::ide::analysis::Analysis;
use crate::load::LoadOptions;

/// Whether the server reads the file at `path` as a test manifest rather than as LSD.
pub fn is_manifest(path: &Path) -> bool {
    path.extension()
        .is_some_and(|extension| extension == "toml")
}

/// The completions at byte `offset` of the manifest `text` at `path`: inside the string of a
/// case's `scene = "`, the scenes its `program` declares (read by `program_text`, given the
/// program's path: the open file's text, or the file on disk); nothing elsewhere.
pub fn completions(
    path: &Path,
    text: &str,
    offset: usize,
    program_text: &dyn Fn(&Path) -> Option<String>,
    options: &LoadOptions,
) -> Vec<CompletionItem> {
    let offset = offset.min(text.len());
    let line_start = text[..offset].rfind('\n').map_or(0, |i| i + 1);
    if value_being_typed(&text[line_start..offset], "scene").is_none() {
        return Vec::new();
    }
    let Some(program) = case_program(text, line_start) else {
        return Vec::new();
    };
    let program = path.parent().unwrap_or(Path::new("")).join(program);
    let Some(program_text) = program_text(&program) else {
        return Vec::new();
    };
    let analysis = Analysis::new(&program, &program_text, options);
    let scenes = &analysis.compilation.workspace.scenes.names;
    (scenes.iter())
        .map(|name| CompletionItem {
            label: name.clone(),
            kind: Some(CompletionItemKind::ENUM_MEMBER),
            detail: Some(format!("scene of {}", program.display())),
            ..Default::default()
        })
        .collect()
}

/// The part of a string value typed so far when `before` (a line up to the cursor) is
/// `key = "...` with the string still open.
fn value_being_typed<'t>(before: &'t str, key: &str) -> Option<&'t str> {
    after_opening_quote(before, key).filter(|typed| !typed.contains('"'))
}

/// What follows the opening quote of `key = "...` on `line`.
fn after_opening_quote<'t>(line: &'t str, key: &str) -> Option<&'t str> {
    let rest = line.trim_start().strip_prefix(key)?;
    rest.trim_start()
        .strip_prefix('=')?
        .trim_start()
        .strip_prefix('"')
}

/// The `program` of the `[[case]]` table the line starting at `line_start` belongs to: the
/// table whose header is the last one before it, read to the next header.
fn case_program(text: &str, line_start: usize) -> Option<&str> {
    let is_header = |line: &str| line.trim_start().starts_with('[');
    let (index, header) = (text[..line_start].lines().enumerate())
        .filter(|(_, line)| is_header(line))
        .last()?;
    if header.trim() != "[[case]]" {
        return None;
    }
    let mut table = (text.lines().skip(index + 1)).take_while(|line| !is_header(line));
    table.find_map(|line| {
        let value = after_opening_quote(line, "program")?;
        // The string ends at its closing quote (a comment may follow).
        value.split('"').next()
    })
}
