//! The LSD names of URDF links and joints.

use std::collections::HashSet;
use std::sync::OnceLock;

use crate::load::stdlib;
use crate::source::FileId;
use crate::syntax::ast::DeclKind;
use crate::syntax::lexer::{lex, Tok};
use crate::syntax::names::BUILTIN_NAMES;

/// The LSD identifier a URDF link or joint name becomes, when no other link or joint took it
/// first. A valid LSD identifier stays as it is unless it is a keyword or a name the program
/// needs (a builtin such as `pi` or `earth`, a standard library module or one of its names such
/// as `revolute`, `weld` or `g`). Otherwise every character that cannot be part of an
/// identifier becomes `_`, a leading digit gets a `_` before it, and `_` is appended while the
/// result is a keyword or such a name. The importer then appends `_` while the name is taken by
/// an earlier link or joint (links first, then joints, in the order of the file).
pub fn lsd_name(urdf_name: &str) -> String {
    let mut name: String = urdf_name
        .chars()
        .map(|c| if continues_identifier(c) { c } else { '_' })
        .collect();
    if !name.chars().next().is_some_and(starts_identifier) {
        name.insert(0, '_');
    }
    while !is_identifier(&name) || reserved().contains(&name) {
        name.push('_');
    }
    name
}

/// Whether `text` is exactly one LSD identifier token (a keyword lexes as its own token).
pub(super) fn is_identifier(text: &str) -> bool {
    let (tokens, errors) = lex(FileId(0), text);
    errors.is_empty()
        && matches!(tokens.as_slice(), [(0, Tok::Ident(_), end)] if *end == text.len())
}

fn starts_identifier(c: char) -> bool {
    c == '_' || is_identifier(c.encode_utf8(&mut [0; 4]))
}

fn continues_identifier(c: char) -> bool {
    is_identifier(&format!("_{c}"))
}

/// Names a link or joint cannot take: the builtins and the standard library's modules and
/// declarations, which the generated program uses and a declaration would shadow. The same set
/// whatever the options, so that a link's name does not depend on them.
pub(super) fn reserved() -> &'static HashSet<String> {
    static RESERVED: OnceLock<HashSet<String>> = OnceLock::new();
    RESERVED.get_or_init(|| {
        let mut names: HashSet<String> = BUILTIN_NAMES.iter().map(|s| s.to_string()).collect();
        for module in stdlib::names() {
            names.insert(module.to_string());
            let Some((_, text)) = stdlib::find(module) else {
                continue;
            };
            let (program, _) = crate::syntax::parser::parse(FileId(0), text);
            for decl in &program.decls {
                match &decl.kind {
                    DeclKind::Let(bindings) => {
                        names.extend(bindings.iter().map(|b| b.name.name.to_string()))
                    }
                    DeclKind::Define(define) => {
                        names.insert(define.name.name.to_string());
                    }
                    _ => {}
                }
            }
        }
        names
    })
}
