//! Property tests: the front end never panics, whatever it is fed — random token sequences and
//! random mutations of the bundled examples — and every error it reports points inside a file.

use proptest::prelude::*;

use lsdc::diag::render;
use lsdc::driver::compile_text;
use lsdc::load::LoadOptions;

/// Token texts of LSD, including the ones only errors use.
const TOKENS: &[&str] = &[
    "let",
    "join",
    "and",
    "with",
    "apply",
    "on",
    "package",
    "import",
    "as",
    "local",
    "in",
    "end",
    "body",
    "link",
    "force",
    "torque",
    "=",
    ";",
    ",",
    ":",
    ".",
    "(",
    ")",
    "[",
    "]",
    "+",
    "-",
    "*",
    "/",
    "^",
    "++",
    "||",
    "@",
    "'",
    "0",
    "1",
    "2.5",
    "1e3",
    "x",
    "y",
    "axe",
    "rotoïde",
    "earth",
    "pi",
    "sin",
    "?s",
    "?fs",
    "?v",
    "mass",
    "frame",
    "iframe",
    "inertia",
    "dof",
    "dof1",
    "dof2",
    "value",
    "joints",
    "revolute",
    "\"lib.lsd\"",
    "(*",
    "*)",
    "?",
    "|",
    "#",
];

fn examples() -> Vec<String> {
    [
        "examples/satellite.lsd",
        "examples/satellite_library.lsd",
        "examples/link_forms.lsd",
        "stdlib/joints.lsd",
    ]
    .iter()
    .map(|p| std::fs::read_to_string(p).expect("example readable"))
    .collect()
}

fn run_front_end(text: &str) {
    let options = LoadOptions {
        library_dirs: Vec::new(),
        use_environment: false,
        scene: None,
    };
    let compilation = compile_text(
        "random.lsd",
        text,
        Some(std::path::Path::new("examples")),
        &options,
    );
    for diagnostic in &compilation.diagnostics {
        for label in &diagnostic.labels {
            let file = compilation.workspace.sources.file(label.span.file());
            assert!(
                label.span.start() <= label.span.end()
                    && label.span.end() as usize <= file.text.len()
            );
        }
    }
    let text = render::to_text(&compilation.workspace.sources, &compilation.diagnostics);
    assert_eq!(text.is_empty(), compilation.diagnostics.is_empty());
    render::to_json_value(&compilation.workspace.sources, &compilation.diagnostics);
    if let Some(mechanism) = compilation.mechanism {
        mechanism.summary();
        mechanism.dump();
    }
}

#[derive(Debug, Clone)]
enum Mutation {
    Delete { at: usize, len: usize },
    Insert { at: usize, token: usize },
    Duplicate { at: usize, len: usize },
    Swap { a: usize, b: usize },
}

fn apply(text: &str, mutation: &Mutation) -> String {
    let chars: Vec<char> = text.chars().collect();
    let n = chars.len().max(1);
    let mut out = chars.clone();
    match *mutation {
        Mutation::Delete { at, len } => {
            let start = at % n;
            let end = (start + len).min(chars.len());
            out.drain(start.min(chars.len())..end);
        }
        Mutation::Insert { at, token } => {
            let at = (at % n).min(chars.len());
            let inserted: Vec<char> = format!(" {} ", TOKENS[token % TOKENS.len()])
                .chars()
                .collect();
            out.splice(at..at, inserted);
        }
        Mutation::Duplicate { at, len } => {
            let start = (at % n).min(chars.len());
            let end = (start + len).min(chars.len());
            let copy: Vec<char> = chars[start..end].to_vec();
            out.splice(end..end, copy);
        }
        Mutation::Swap { a, b } => {
            if !chars.is_empty() {
                out.swap(a % chars.len(), b % chars.len());
            }
        }
    }
    out.into_iter().collect()
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        (any::<usize>(), 1usize..40).prop_map(|(at, len)| Mutation::Delete { at, len }),
        (any::<usize>(), any::<usize>()).prop_map(|(at, token)| Mutation::Insert { at, token }),
        (any::<usize>(), 1usize..80).prop_map(|(at, len)| Mutation::Duplicate { at, len }),
        (any::<usize>(), any::<usize>()).prop_map(|(a, b)| Mutation::Swap { a, b }),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 400, ..ProptestConfig::default() })]

    #[test]
    fn random_token_sequences_never_panic(tokens in prop::collection::vec(0..TOKENS.len(), 0..60)) {
        let text: Vec<&str> = tokens.iter().map(|&i| TOKENS[i]).collect();
        run_front_end(&text.join(" "));
    }

    #[test]
    fn mutated_examples_never_panic(example in 0usize..4, mutations in prop::collection::vec(mutation(), 1..6)) {
        let mut text = examples()[example].clone();
        for m in &mutations {
            text = apply(&text, m);
        }
        run_front_end(&text);
    }

    #[test]
    fn arbitrary_text_never_panics(text in "\\PC{0,200}") {
        run_front_end(&text);
    }
}
