//! `lsdc fmt`: on every example and standard library module, and on mutated programs, formatting
//! keeps every token and comment, gives the same equations of motion, and is idempotent.

use std::path::{Path, PathBuf};

use lsdc::ide::format::{format, lsd_files};
use lsdc::load::LoadOptions;
use lsdc::source::FileId;
use lsdc::syntax::lexer::{comments_in_gap, lex};
use proptest::prelude::*;

/// The tokens' texts and the comments of a program, in order: what formatting must keep.
fn tokens_and_comments(text: &str) -> Vec<String> {
    let (tokens, errors) = lex(FileId(0), text);
    assert!(errors.is_empty());
    let mut pieces = Vec::new();
    let mut end = 0;
    for (start, _, token_end) in tokens {
        let gap = &text[end..start];
        pieces.extend(comments_in_gap(gap).into_iter().map(|c| gap[c].to_string()));
        pieces.push(text[start..token_end].to_string());
        end = token_end;
    }
    let gap = &text[end..];
    pieces.extend(comments_in_gap(gap).into_iter().map(|c| gap[c].to_string()));
    pieces
}

/// What `lsdc compile --emit equations` prints for a program (`None` if it has none: a
/// library, or a program with errors, whose diagnostics are compared instead).
fn equations(text: &str, dir: &Path) -> String {
    let program =
        lsdc::api::Program::from_text("program.lsd", text, Some(dir), &LoadOptions::default());
    let Ok(mechanism) = program.mechanism() else {
        let messages: Vec<String> = program
            .diagnostics()
            .iter()
            .map(|d| d.to_string())
            .collect();
        return messages.join("\n");
    };
    let generated = lsdc::topology::build(mechanism)
        .map_err(|d| format!("{d:?}"))
        .and_then(|topology| {
            lsdc::symbolic::generate(mechanism, &topology).map_err(|d| format!("{d:?}"))
        });
    match generated {
        Ok(equations) => lsdc::symbolic::emit::text(&equations, "program.lsd"),
        Err(error) => error,
    }
}

/// Formats and checks the properties; returns the formatted text.
fn check_formatting(text: &str, dir: &Path) -> String {
    let formatted = format(FileId(0), text).expect("the program parses");
    assert_eq!(tokens_and_comments(&formatted), tokens_and_comments(text));
    assert_eq!(
        format(FileId(0), &formatted).expect("parses"),
        formatted,
        "not idempotent"
    );
    assert_eq!(equations(&formatted, dir), equations(text, dir));
    formatted
}

fn repository_files() -> Vec<PathBuf> {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    lsd_files(&[root.join("examples"), root.join("stdlib")]).expect("readable")
}

#[test]
fn examples_keep_their_tokens_comments_and_equations() {
    let files = repository_files();
    assert!(files.len() > 30);
    for file in files {
        let text = std::fs::read_to_string(&file).expect("readable");
        check_formatting(&text, file.parent().expect("a directory"));
    }
}

#[test]
fn the_repository_is_formatted() {
    for file in repository_files() {
        let text = std::fs::read_to_string(&file).expect("readable");
        assert_eq!(
            format(FileId(0), &text).expect("parses"),
            text,
            "{}",
            file.display()
        );
    }
}

#[test]
fn layout_follows_the_documented_style() {
    let text = "let b = body mass = 2*x, inertia = [1,1,1] end; let f(a:vector) = -a ;\n\n\n\
                join earth and b.frame with link(q)\ndof = q||[0,0,1] end as j;(* done *)";
    let expected = "let b = body mass = 2 * x, inertia = [1, 1, 1] end ;\n\
                    let f(a : vector) = -a ;\n\n\
                    join earth and b.frame with link(q)\n  dof = q || [0, 0, 1] end as j ; (* done *)\n";
    assert_eq!(format(FileId(0), text).expect("parses"), expected);
}

#[test]
fn a_program_that_does_not_parse_is_refused() {
    let diagnostics = format(FileId(0), "let a = ;").expect_err("a syntax error");
    assert_eq!(diagnostics[0].code, "E0201");
}

/// Where a mutation goes: after the token of this index (modulo their number).
#[derive(Clone, Debug)]
enum Mutation {
    Space(usize, &'static str),
    Comment(usize),
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        (
            any::<usize>(),
            prop::sample::select(vec!["", " ", "\n", "\n\n\n", "\t  "])
        )
            .prop_map(|(at, s)| Mutation::Space(at, s)),
        any::<usize>().prop_map(Mutation::Comment),
    ]
}

/// The program with its whitespace after some tokens replaced, and comments inserted.
fn mutate(text: &str, mutations: &[Mutation]) -> String {
    let (tokens, _) = lex(FileId(0), text);
    let mut edits: Vec<(usize, usize, String)> = Vec::new();
    for mutation in mutations {
        let (index, replacement) = match mutation {
            Mutation::Space(at, s) => (at % tokens.len(), s.to_string()),
            Mutation::Comment(at) => (at % tokens.len(), format!(" (* note {at} *)\n")),
        };
        let end = tokens[index].2;
        let next = tokens.get(index + 1).map_or(text.len(), |t| t.0);
        let gap = &text[end..next];
        // Keep the comments already there; an empty gap stays only where tokens stay apart.
        if comments_in_gap(gap).is_empty() && !edits.iter().any(|e| e.0 == end) {
            let spaced = if replacement.is_empty() {
                " ".to_string()
            } else {
                replacement
            };
            edits.push((end, next, spaced));
        }
    }
    edits.sort();
    let mut out = String::new();
    let mut position = 0;
    for (start, end, replacement) in edits {
        out.push_str(&text[position..start]);
        out.push_str(&replacement);
        position = end;
    }
    out.push_str(&text[position..]);
    out
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]
    #[test]
    fn mutated_programs_keep_their_meaning(
        example in prop::sample::select(vec!["pendulum.lsd", "satellite.lsd", "four_bar.lsd", "link_forms.lsd", "governor.lsd"]),
        mutations in prop::collection::vec(mutation(), 1..12),
    ) {
        let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("examples");
        let text = std::fs::read_to_string(dir.join(example)).expect("readable");
        let mutated = mutate(&text, &mutations);
        assert_eq!(equations(&mutated, &dir), equations(&text, &dir));
        check_formatting(&mutated, &dir);
    }
}
