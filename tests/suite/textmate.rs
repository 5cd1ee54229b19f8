//! The TextMate grammar of `editors/vscode/` on every example and standard library module: at
//! each token the lexer finds, the grammar's first matching pattern covers exactly that token
//! and gives it the scope of its kind; every comment is a comment.

use std::path::PathBuf;

use lsdc::source::FileId;
use lsdc::syntax::lexer::{comments_in_gap, lex, Tok};
use regex::Regex;
use serde_json::Value;

struct Pattern {
    regex: Regex,
    scope: String,
}

/// The grammar's top-level patterns in order, with their includes resolved; a `begin`/`end`
/// rule is represented by its `begin`.
fn patterns() -> Vec<Pattern> {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("editors/vscode/syntaxes/lsd.tmLanguage.json");
    let grammar: Value =
        serde_json::from_str(&std::fs::read_to_string(path).expect("readable")).expect("JSON");
    let repository = &grammar["repository"];
    grammar["patterns"]
        .as_array()
        .expect("patterns")
        .iter()
        .map(|include| {
            let name = include["include"]
                .as_str()
                .expect("an include")
                .trim_start_matches('#');
            let rule = &repository[name];
            let source = rule["match"]
                .as_str()
                .or(rule["begin"].as_str())
                .expect("a pattern");
            Pattern {
                regex: Regex::new(&format!("^(?:{source})")).expect("a regular expression"),
                scope: rule["name"].as_str().expect("a scope").to_string(),
            }
        })
        .collect()
}

/// The scope a token of this kind must get.
fn expected_scope(token: Tok<'_>) -> &'static str {
    match token {
        Tok::Int(_) | Tok::Float(_) => "constant.numeric",
        Tok::Str(_) => "string",
        Tok::Unknown(_) => "variable.other.unknown",
        Tok::Ident(name) if lsdc::syntax::names::BUILTIN_NAMES.contains(&name) => {
            "support.function"
        }
        Tok::Ident(_) => "variable.other",
        token if token.text().chars().all(char::is_alphabetic) => "keyword.other",
        Tok::Parallel | Tok::PlusPlus | Tok::Plus | Tok::Minus | Tok::Star | Tok::Slash => {
            "keyword.operator"
        }
        Tok::Caret | Tok::At | Tok::Equal | Tok::Prime => "keyword.operator",
        _ => "punctuation",
    }
}

fn first_match<'p>(patterns: &'p [Pattern], rest: &str) -> Option<(&'p Pattern, usize)> {
    patterns
        .iter()
        .find_map(|p| p.regex.find(rest).map(|m| (p, m.end())))
}

#[test]
fn every_token_of_the_examples_is_classified() {
    let patterns = patterns();
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let files = lsdc::ide::format::lsd_files(&[root.join("examples"), root.join("stdlib")])
        .expect("readable");
    let mut tokens_seen = 0;
    for file in files {
        let text = std::fs::read_to_string(&file).expect("readable");
        let (tokens, errors) = lex(FileId(0), &text);
        assert!(errors.is_empty());
        let mut end = 0;
        for (start, token, token_end) in tokens {
            for comment in comments_in_gap(&text[end..start]) {
                let (pattern, _) =
                    first_match(&patterns, &text[end + comment.start..]).expect("a comment");
                assert_eq!(pattern.scope, "comment.block.lsd", "{}", file.display());
            }
            let (pattern, length) = first_match(&patterns, &text[start..])
                .unwrap_or_else(|| panic!("{}: nothing matches at {start}", file.display()));
            assert_eq!(
                length,
                token_end - start,
                "{}: {token} at {start}",
                file.display()
            );
            assert!(
                pattern.scope.starts_with(expected_scope(token)),
                "{}: {token} is {}",
                file.display(),
                pattern.scope
            );
            end = token_end;
            tokens_seen += 1;
        }
    }
    assert!(tokens_seen > 5000, "{tokens_seen}");
}
