//! Completion: fields after `.`, a package's names after `:`, libraries after `import`, the
//! parameters of the definition being called, and the names in scope.

use lsp_types::{CompletionItem, CompletionItemKind};

use crate::check::types::{builtin_constant, field_names, Ty};
use crate::ide::analysis::{Analysis, Definition, DefinitionKind};
use crate::load::stdlib;
use crate::syntax::names::BUILTIN_NAMES;

const KEYWORDS: &[&str] = &[
    "and", "apply", "as", "between", "body", "end", "force", "given", "import", "fixed", "guess",
    "in", "initial", "join", "let", "link", "local", "on", "output", "package", "scene",
    "simulate", "torque", "with",
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
        Some('.') => fields(analysis, path_before(&before[..before.len() - 1])),
        Some(':') => {
            let package = name_before(without_index(&before[..before.len() - 1]));
            package_members(analysis, package)
        }
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

/// `text` without the instance index that ends it: `leg[1]` is `leg`.
fn without_index(text: &str) -> &str {
    if !text.ends_with(']') {
        return text;
    }
    let mut depth = 0;
    for (i, c) in text.char_indices().rev() {
        match c {
            ']' => depth += 1,
            '[' if depth == 1 => return &text[..i],
            '[' => depth -= 1,
            _ => {}
        }
    }
    text
}

/// The qualified name that ends at the end of `text`, as written (`leg[1]:knee`, `Arm:sh`,
/// `rod`), and its plain names (`["leg", "knee"]`).
fn path_before(text: &str) -> (&str, Vec<&str>) {
    let mut names = Vec::new();
    let mut rest = text;
    loop {
        let name = name_before(rest);
        rest = &rest[..rest.len() - name.len()];
        names.push(name);
        match rest.strip_suffix(':') {
            Some(package) if !name.is_empty() => rest = without_index(package),
            _ => break,
        }
    }
    names.reverse();
    (&text[rest.len()..], names)
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

/// The fields of the named value: a body's, a frame's, an effort's, a join's coordinates. The
/// value may be a package's (`Arm:sh`, `leg[1]:knee`).
fn fields(analysis: &Analysis, (written, path): (&str, Vec<&str>)) -> Vec<CompletionItem> {
    let definition = match path.as_slice() {
        [name] => analysis.index.visible_named(name),
        [.., package, name] => member(analysis, package, name),
        [] => None,
    };
    let Some(definition) = definition else {
        return Vec::new();
    };
    let names = match definition.ty {
        Some(Ty::Join) => join_coordinates(analysis, definition, written),
        Some(ty) => field_names(ty),
        None => Vec::new(),
    };
    names
        .iter()
        .map(|name| item(name, CompletionItemKind::FIELD, None))
        .collect()
}

/// The coordinates of a join, found in the mechanism by the name as written (`leg[1]:knee`, how
/// the mechanism names a join of an instance) or its plain name.
fn join_coordinates(analysis: &Analysis, join: &Definition, written: &str) -> Vec<String> {
    let Some(mechanism) = analysis.mechanism() else {
        return Vec::new();
    };
    let named = |name: &str| {
        (mechanism.joins.iter()).find(|j| j.name.as_ref().is_some_and(|n| &**n == name))
    };
    named(written)
        .or_else(|| named(&join.name))
        .map(|j| {
            let link = &mechanism.links[j.link.0 as usize];
            link.coordinates.iter().map(|c| c.to_string()).collect()
        })
        .unwrap_or_default()
}

/// The definition `name` declared in `package`.
fn member<'a>(analysis: &'a Analysis, package: &str, name: &str) -> Option<&'a Definition> {
    let members = analysis
        .index
        .scope_members
        .get(&package_scope(analysis, package)?)?;
    let definitions = &analysis.index.definitions;
    members
        .iter()
        .map(|&id| &definitions[id])
        .find(|d| &*d.name == name)
}

fn package_members(analysis: &Analysis, package: &str) -> Vec<CompletionItem> {
    let members =
        package_scope(analysis, package).and_then(|s| analysis.index.scope_members.get(&s));
    members
        .into_iter()
        .flatten()
        .map(|&id| definition_item(&analysis.index.definitions[id]))
        .collect()
}

/// The scope of the package or module named `package`.
fn package_scope(analysis: &Analysis, package: &str) -> Option<crate::check::scope::ScopeId> {
    analysis
        .index
        .definitions
        .iter()
        .filter(|d| &*d.name == package)
        .find_map(|d| match d.kind {
            DefinitionKind::Package(scope) | DefinitionKind::Module(scope) => scope,
            _ => None,
        })
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
        DefinitionKind::Parameter
        | DefinitionKind::Coordinate
        | DefinitionKind::Local
        | DefinitionKind::Input => CompletionItemKind::VARIABLE,
        DefinitionKind::Value | DefinitionKind::Join => CompletionItemKind::VALUE,
    };
    let detail = definition
        .ty
        .filter(|ty| *ty != Ty::Error)
        .map(|ty| ty.to_string());
    item(&definition.name, kind, detail)
}
