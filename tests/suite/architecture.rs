//! The phases depend one way: no import cycle between the files of `src/`, nor between the
//! folders (or files) inside any folder. A file depends on another when it names an item of it
//! by path (`crate::a::b`, `super::b`, `self::b`, or a child module declared with `mod b;`);
//! `#[cfg(test)]` modules are left out, since tests may use anything.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

type Module = Vec<String>;

/// Every `.rs` file under `dir` with its module path (`src/a/b.rs` and `src/a/b/mod.rs` are
/// `a::b`; `lib.rs` is the crate root).
fn modules(dir: &Path, prefix: &Module, into: &mut BTreeMap<Module, String>) {
    for entry in std::fs::read_dir(dir).expect("src/ is readable") {
        let path = entry.expect("a directory entry").path();
        let name = path.file_stem().unwrap().to_string_lossy().to_string();
        if path.is_dir() {
            let mut module = prefix.clone();
            module.push(name);
            modules(&path, &module, into);
        } else if path.extension().is_some_and(|e| e == "rs") {
            let mut module = prefix.clone();
            match name.as_str() {
                "mod" | "lib" => {}
                "main" if prefix.is_empty() => continue,
                _ => module.push(name),
            }
            into.insert(module, std::fs::read_to_string(&path).unwrap());
        }
    }
}

/// The text without comments, string and character literals, and `#[cfg(test)]` items (test
/// modules come last in a file).
fn code(text: &str) -> String {
    let text = match text.find("#[cfg(test)]") {
        Some(at) => &text[..at],
        None => text,
    };
    let chars: Vec<char> = text.chars().collect();
    let mut out = String::new();
    let mut i = 0;
    while i < chars.len() {
        let at = |k: usize| chars.get(k).copied().unwrap_or(' ');
        match (chars[i], at(i + 1)) {
            ('/', '/') => {
                while i < chars.len() && chars[i] != '\n' {
                    i += 1;
                }
            }
            ('/', '*') => {
                let mut depth = 0;
                while i < chars.len() {
                    if chars[i] == '/' && at(i + 1) == '*' {
                        depth += 1;
                        i += 1;
                    } else if chars[i] == '*' && at(i + 1) == '/' {
                        depth -= 1;
                        i += 1;
                        if depth == 0 {
                            break;
                        }
                    }
                    i += 1;
                }
                i += 1;
            }
            ('r', '"' | '#') if raw_string_at(&chars, i) => {
                let hashes = chars[i + 1..].iter().take_while(|&&c| c == '#').count();
                i += 2 + hashes;
                while i < chars.len() {
                    let closes = chars[i] == '"'
                        && chars[i + 1..]
                            .iter()
                            .take(hashes)
                            .filter(|&&c| c == '#')
                            .count()
                            == hashes;
                    i += 1;
                    if closes {
                        i += hashes;
                        break;
                    }
                }
                out.push_str("\"\"");
            }
            ('"', _) => {
                i += 1;
                while i < chars.len() && chars[i] != '"' {
                    i += if chars[i] == '\\' { 2 } else { 1 };
                }
                i += 1;
                out.push_str("\"\"");
            }
            ('\'', '\\') => {
                i += 2;
                while i < chars.len() && chars[i] != '\'' {
                    i += 1;
                }
                i += 1;
            }
            ('\'', _) if at(i + 2) == '\'' => i += 3,
            (c, _) => {
                out.push(c);
                i += 1;
            }
        }
    }
    out
}

/// `r"…"` or `r#"…"#` starts at `i` (not an identifier ending in `r`, nor a raw identifier).
fn raw_string_at(chars: &[char], i: usize) -> bool {
    let after_name = i > 0 && (chars[i - 1].is_alphanumeric() || chars[i - 1] == '_');
    let hashes = chars[i + 1..].iter().take_while(|&&c| c == '#').count();
    !after_name && chars.get(i + 1 + hashes) == Some(&'"')
}

/// Identifiers and punctuation, `::` as one token.
fn tokens(code: &str) -> Vec<String> {
    let mut tokens = Vec::new();
    let chars: Vec<char> = code.chars().collect();
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        if c.is_alphanumeric() || c == '_' {
            let start = i;
            while i < chars.len() && (chars[i].is_alphanumeric() || chars[i] == '_') {
                i += 1;
            }
            tokens.push(chars[start..i].iter().collect());
        } else if c == ':' && chars.get(i + 1) == Some(&':') {
            tokens.push("::".to_string());
            i += 2;
        } else {
            if !c.is_whitespace() {
                tokens.push(c.to_string());
            }
            i += 1;
        }
    }
    tokens
}

/// The paths a file names: every `a::b::c` (use-groups `a::{b, c::d}` expanded one level per
/// item), each as its segments.
fn paths(tokens: &[String]) -> Vec<Vec<String>> {
    let mut found = Vec::new();
    let mut i = 0;
    while i < tokens.len() {
        let is_name = |t: &str| t.chars().all(|c| c.is_alphanumeric() || c == '_');
        let preceded_by_path = i > 0 && tokens[i - 1] == "::";
        if !is_name(&tokens[i]) || preceded_by_path {
            i += 1;
            continue;
        }
        let mut path = vec![tokens[i].clone()];
        let mut j = i + 1;
        while j + 1 < tokens.len() && tokens[j] == "::" && is_name(&tokens[j + 1]) {
            path.push(tokens[j + 1].clone());
            j += 2;
        }
        if j + 1 < tokens.len() && tokens[j] == "::" && tokens[j + 1] == "{" {
            let mut depth = 0;
            let mut item: Vec<&str> = Vec::new();
            let mut flush = |item: &mut Vec<&str>| {
                let mut full = path.clone();
                full.extend(
                    item.iter()
                        .take_while(|t| **t == "::" || is_name(t))
                        .filter(|t| **t != "::" && **t != "self")
                        .take(2)
                        .map(|t| t.to_string()),
                );
                found.push(full);
                item.clear();
            };
            j += 1;
            while j < tokens.len() {
                match tokens[j].as_str() {
                    "{" => depth += 1,
                    "}" if depth == 1 => {
                        flush(&mut item);
                        break;
                    }
                    "}" => depth -= 1,
                    "," if depth == 1 => flush(&mut item),
                    token if depth == 1 => item.push(token),
                    _ => {}
                }
                j += 1;
            }
        }
        found.push(path);
        i = j;
    }
    found
}

/// The module files each file depends on.
fn dependencies(files: &BTreeMap<Module, String>) -> BTreeMap<Module, BTreeSet<Module>> {
    let resolve = |path: &[String]| -> Module {
        (0..=path.len())
            .rev()
            .map(|n| path[..n].to_vec())
            .find(|m| files.contains_key(m))
            .unwrap_or_default()
    };
    let mut graph = BTreeMap::new();
    for (module, text) in files {
        let tokens = tokens(&code(text));
        let children: BTreeSet<&str> = tokens
            .windows(3)
            .filter(|w| w[0] == "mod" && w[2] == ";")
            .map(|w| w[1].as_str())
            .collect();
        let mut deps = BTreeSet::new();
        // A lone `super`, `self` or `crate` is a visibility or a receiver, not a path.
        for path in paths(&tokens).into_iter().filter(|p| p.len() > 1) {
            let mut base: Module = match path[0].as_str() {
                "crate" => Vec::new(),
                "self" => module.clone(),
                "super" => module[..module.len().saturating_sub(1)].to_vec(),
                child if children.contains(child) => {
                    let mut m = module.clone();
                    m.push(child.to_string());
                    m
                }
                _ => continue,
            };
            let mut rest = &path[1..];
            while rest.first().is_some_and(|s| s == "super") {
                base.pop();
                rest = &rest[1..];
            }
            base.extend(rest.iter().cloned());
            let target = resolve(&base);
            if &target != module {
                deps.insert(target);
            }
        }
        graph.insert(module.clone(), deps);
    }
    graph
}

/// The strongly connected components with more than one node (Tarjan).
fn cycles(
    nodes: &BTreeSet<Module>,
    edges: &BTreeMap<Module, BTreeSet<Module>>,
) -> Vec<Vec<Module>> {
    struct State<'a> {
        edges: &'a BTreeMap<Module, BTreeSet<Module>>,
        index: BTreeMap<Module, usize>,
        low: BTreeMap<Module, usize>,
        stack: Vec<Module>,
        found: Vec<Vec<Module>>,
    }
    fn visit(state: &mut State, v: &Module) {
        let n = state.index.len();
        state.index.insert(v.clone(), n);
        state.low.insert(v.clone(), n);
        state.stack.push(v.clone());
        for w in state.edges.get(v).into_iter().flatten() {
            if !state.index.contains_key(w) {
                visit(state, w);
                let low = state.low[v].min(state.low[w]);
                state.low.insert(v.clone(), low);
            } else if state.stack.contains(w) {
                let low = state.low[v].min(state.index[w]);
                state.low.insert(v.clone(), low);
            }
        }
        if state.low[v] == state.index[v] {
            let at = state.stack.iter().position(|m| m == v).unwrap();
            let component = state.stack.split_off(at);
            if component.len() > 1 {
                state.found.push(component);
            }
        }
    }
    let mut state = State {
        edges,
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        stack: Vec::new(),
        found: Vec::new(),
    };
    for v in nodes {
        if !state.index.contains_key(v) {
            visit(&mut state, v);
        }
    }
    state.found
}

fn name(m: &[String]) -> String {
    if m.is_empty() {
        "crate".to_string()
    } else {
        m.join("::")
    }
}

fn describe(component: &[Module], edges: &BTreeMap<Module, BTreeSet<Module>>) -> String {
    let mut lines = Vec::new();
    for a in component {
        for b in edges
            .get(a)
            .into_iter()
            .flatten()
            .filter(|b| component.contains(b))
        {
            lines.push(format!("  {} -> {}", name(a), name(b)));
        }
    }
    lines.join("\n")
}

/// The graph between the entries of `folder`: its subfolders and files, each standing for
/// everything under it.
fn folder_graph(
    folder: &[String],
    files: &BTreeMap<Module, BTreeSet<Module>>,
) -> (BTreeSet<Module>, BTreeMap<Module, BTreeSet<Module>>) {
    let entry = |m: &Module| -> Option<Module> {
        (m.len() > folder.len() && m.starts_with(folder)).then(|| m[..=folder.len()].to_vec())
    };
    let mut nodes = BTreeSet::new();
    let mut edges: BTreeMap<Module, BTreeSet<Module>> = BTreeMap::new();
    for (a, deps) in files {
        let Some(ea) = entry(a) else { continue };
        nodes.insert(ea.clone());
        for eb in deps.iter().filter_map(entry).filter(|eb| *eb != ea) {
            edges.entry(ea.clone()).or_default().insert(eb);
        }
    }
    (nodes, edges)
}

#[test]
fn no_import_cycle_between_files_or_folders() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = BTreeMap::new();
    modules(&src, &Vec::new(), &mut files);
    let graph = dependencies(&files);
    let mut problems = Vec::new();
    let nodes: BTreeSet<Module> = files.keys().cloned().collect();
    for component in cycles(&nodes, &graph) {
        problems.push(format!(
            "files depend on each other:\n{}",
            describe(&component, &graph)
        ));
    }
    let folders: BTreeSet<Module> = files
        .keys()
        .flat_map(|m| (0..m.len()).map(|n| m[..n].to_vec()))
        .collect();
    for folder in &folders {
        let (nodes, edges) = folder_graph(folder, &graph);
        for component in cycles(&nodes, &edges) {
            problems.push(format!(
                "inside `{}`:\n{}",
                name(folder),
                describe(&component, &edges)
            ));
        }
    }
    assert!(
        problems.is_empty(),
        "import cycles in src/:\n{}",
        problems.join("\n")
    );
}

#[test]
fn the_checker_sees_a_cycle() {
    let mut files = BTreeMap::new();
    files.insert(vec![], "pub mod a;\npub mod b;".to_string());
    files.insert(
        vec!["a".to_string()],
        "use crate::b::{self, Thing};\n// crate::c\n".to_string(),
    );
    files.insert(
        vec!["b".to_string()],
        "fn f() { super::a::g(\"crate::x\") }".to_string(),
    );
    let graph = dependencies(&files);
    let nodes: BTreeSet<Module> = files.keys().cloned().collect();
    assert_eq!(cycles(&nodes, &graph).len(), 1);
    let (folder_nodes, edges) = folder_graph(&[], &graph);
    assert_eq!(cycles(&folder_nodes, &edges).len(), 1);
    files.insert(
        vec!["b".to_string()],
        "fn f() { let s = \"super::a\"; }".to_string(),
    );
    let graph = dependencies(&files);
    assert!(cycles(&nodes, &graph).is_empty());
}

/// nalgebra's SVD iterates until it converges, which a matrix with a NaN or an infinite entry
/// never does: every decomposition goes through `linalg::svd`, which refuses such a matrix and
/// bounds the iterations. A call of nalgebra's own (`.svd(`, `SVD::new`) elsewhere is a run that
/// can hang.
#[test]
fn every_svd_goes_through_the_wrapper_that_ends() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = BTreeMap::new();
    modules(&src, &Vec::new(), &mut files);
    let mut found = Vec::new();
    for (module, text) in &files {
        // `linalg` is the wrapper; `dynamics::angles` decomposes a 6 × 6 matrix on the stack
        // (the wrapper takes heap matrices, and that solve must not allocate), checking first,
        // as the wrapper does, that every entry is finite.
        let allowed = [vec!["linalg"], vec!["dynamics", "angles"]];
        if allowed.iter().any(|m| m.iter().eq(module.iter())) {
            continue;
        }
        let code = code(text);
        for needle in [
            ".svd(",
            "SVD::new(",
            ".svd_unordered(",
            "SVD::new_unordered(",
        ] {
            if code.contains(needle) {
                found.push(format!("{}: {needle}", name(module)));
            }
        }
    }
    assert!(
        found.is_empty(),
        "SVDs outside `linalg::svd`:\n{}",
        found.join("\n")
    );
}
