//! Completion: fields after `.`, a package's names after `:`, libraries after `import`, the
//! parameters of the definition being called, and the names in scope.

use lsp_types::{CompletionItem, CompletionItemKind};

use crate::check::types::{builtin_constant, field_names, Ty};
use crate::ide::analysis::{Analysis, Definition, DefinitionKind};
use crate::load::stdlib;
use crate::syntax::names::BUILTIN_NAMES;

const KEYWORDS: &[&str] = &[
    "and", "apply", "as", "between", "body", "end", "force", "given", "import", "fixed", "guess",
    "in", "initial", "join", "let", "link", "local", "on", "output", "package", "simulate",
    "torque", "with",
];

/// The completions at a byte offset of the root file of `edited`. The names come from `names`:
/// the same analysis, or the latest one whose declarations could be read when the file being
/// typed no longer parses (a parser that reaches the end of the file inside a declaration keeps
/// none of them).
pub fn completions(edited: &Analysis, names: &Analysis, offset: usize) -> Vec<CompletionItem> {
    let analysis = names;
    let text = edited.text(edited.root);
    let offset = offset.min(text.len());
    let word_start = text[..offset]
        .char_indices()
        .rev()
        .take_while(|(_, c)| c.is_alphanumeric() || *c == '_')
        .last()
        .map_or(offset, |(i, _)| i);
    let before = &text[..word_start];
    let line = &before[before.rfind('\n').map_or(0, |i| i + 1)..];
    if line.trim() == "import" {
        return libraries(analysis);
    }
    match before.chars().last() {
        Some('.') => fields(analysis, name_before(&before[..before.len() - 1])),
        Some(':') => package_members(analysis, name_before(&before[..before.len() - 1])),
        _ => {
            let mut items = parameters_of_call(analysis, before);
            items.extend(names_in_scope(
                analysis,
                offset.min(analysis.text(analysis.root).len()),
            ));
            items
        }
    }
}

/// The identifier that ends at the end of `text`.
fn name_before(text: &str) -> &str {
    let start = text
        .char_indices()
        .rev()
        .take_while(|(_, c)| c.is_alphanumeric() || *c == '_')
        .last()
        .map_or(text.len(), |(i, _)| i);
    &text[start..]
}

fn item(label: &str, kind: CompletionItemKind, detail: Option<String>) -> CompletionItem {
    CompletionItem {
        label: label.to_string(),
        kind: Some(kind),
        detail,
        ..Default::default()
    }
}

/// The standard library's modules and the `.lsd` files beside the edited file.
fn libraries(analysis: &Analysis) -> Vec<CompletionItem> {
    let mut items: Vec<CompletionItem> = stdlib::names()
        .map(|name| {
            item(
                name,
                CompletionItemKind::MODULE,
                Some("standard library".into()),
            )
        })
        .collect();
    let root = &analysis
        .compilation
        .workspace
        .sources
        .file(analysis.root)
        .name;
    let dir = std::path::Path::new(root).parent();
    let entries = dir
        .and_then(|d| std::fs::read_dir(d).ok())
        .into_iter()
        .flatten();
    for path in entries.flatten().map(|e| e.path()) {
        let is_library = path.extension().is_some_and(|e| e == "lsd") && path != *root;
        if let (true, Some(stem)) = (is_library, path.file_stem()) {
            items.push(item(
                &stem.to_string_lossy(),
                CompletionItemKind::FILE,
                None,
            ));
        }
    }
    items
}

/// The fields of the named value: a body's, a frame's, an effort's, a join's coordinates.
fn fields(analysis: &Analysis, target: &str) -> Vec<CompletionItem> {
    let Some(definition) = analysis.index.visible_named(target) else {
        return Vec::new();
    };
    let names = match definition.ty {
        Some(Ty::Join) => join_coordinates(analysis, definition),
        Some(ty) => field_names(ty),
        None => Vec::new(),
    };
    names
        .iter()
        .map(|name| item(name, CompletionItemKind::FIELD, None))
        .collect()
}

fn join_coordinates(analysis: &Analysis, join: &Definition) -> Vec<String> {
    let Some(mechanism) = analysis.mechanism() else {
        return Vec::new();
    };
    mechanism
        .joins
        .iter()
        .find(|j| j.name.as_ref() == Some(&join.name))
        .map(|j| {
            let link = &mechanism.links[j.link.0 as usize];
            link.coordinates.iter().map(|c| c.to_string()).collect()
        })
        .unwrap_or_default()
}

fn package_members(analysis: &Analysis, package: &str) -> Vec<CompletionItem> {
    let scope = analysis
        .index
        .definitions
        .iter()
        .filter(|d| &*d.name == package)
        .find_map(|d| match d.kind {
            DefinitionKind::Package(scope) | DefinitionKind::Module(scope) => scope,
            _ => None,
        });
    let members = scope.and_then(|s| analysis.index.scope_members.get(&s));
    members
        .into_iter()
        .flatten()
        .map(|&id| definition_item(&analysis.index.definitions[id]))
        .collect()
}

/// Inside `f(...)` where `f` is a parameterised definition: its parameters, as `name = `.
fn parameters_of_call(analysis: &Analysis, before: &str) -> Vec<CompletionItem> {
    let mut depth = 0i32;
    for (i, c) in before.char_indices().rev() {
        match c {
            ')' | ']' => depth += 1,
            '[' if depth > 0 => depth -= 1,
            '(' if depth > 0 => depth -= 1,
            '(' => return parameters_of(analysis, name_before(&before[..i])),
            ';' | '[' => break,
            _ => {}
        }
    }
    Vec::new()
}

fn parameters_of(analysis: &Analysis, callee: &str) -> Vec<CompletionItem> {
    let Some(definition) = analysis.index.visible_named(callee) else {
        return Vec::new();
    };
    let DefinitionKind::Function { parameters } = &definition.kind else {
        return Vec::new();
    };
    parameters
        .iter()
        .map(|&p| {
            let name = &analysis.index.definitions[p].name;
            CompletionItem {
                insert_text: Some(format!("{name} = ")),
                ..item(
                    &format!("{name} ="),
                    CompletionItemKind::VARIABLE,
                    Some(format!("parameter of `{callee}`")),
                )
            }
        })
        .collect()
}

/// The locals around the offset, the names the file sees, the built-in names and the keywords.
fn names_in_scope(analysis: &Analysis, offset: usize) -> Vec<CompletionItem> {
    let index = &analysis.index;
    let locals = index.definitions.iter().filter(|d| {
        d.is_local()
            && d.declaration.file() == analysis.root
            && d.declaration.start() as usize <= offset
            && offset <= d.declaration.end() as usize
    });
    let globals = index.visible.iter().map(|&id| &index.definitions[id]);
    let mut items: Vec<CompletionItem> = locals.chain(globals).map(definition_item).collect();
    items.extend(BUILTIN_NAMES.iter().map(|name| {
        let kind = if builtin_constant(name).is_some() {
            CompletionItemKind::CONSTANT
        } else {
            CompletionItemKind::FUNCTION
        };
        item(name, kind, Some("built-in".into()))
    }));
    items.extend(
        KEYWORDS
            .iter()
            .map(|k| item(k, CompletionItemKind::KEYWORD, None)),
    );
    items
}

fn definition_item(definition: &Definition) -> CompletionItem {
    let kind = match definition.kind {
        DefinitionKind::Function { .. } => CompletionItemKind::FUNCTION,
        DefinitionKind::Package(_) | DefinitionKind::Module(_) => CompletionItemKind::MODULE,
        DefinitionKind::Parameter | DefinitionKind::Coordinate | DefinitionKind::Local => {
            CompletionItemKind::VARIABLE
        }
        DefinitionKind::Value | DefinitionKind::Join => CompletionItemKind::VALUE,
    };
    let detail = definition
        .ty
        .filter(|ty| *ty != Ty::Error)
        .map(|ty| ty.to_string());
    item(&definition.name, kind, detail)
}
