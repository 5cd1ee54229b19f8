//! Glue between the lexer, the LALRPOP parser and diagnostics. One call parses a whole file and
//! reports every lexical and syntax error the parser can recover from.

use lalrpop_util::ParseError;

use crate::diag::Diagnostic;
use crate::source::{FileId, Span};
use crate::syntax::ast::{Names, Program};
use crate::syntax::lexer::{lex, LexError, Repair, Spanned, Tok, Tokens};
use crate::syntax::nesting::limit_nesting;
use crate::syntax::repair::{self, Slip};

/// The parser LALRPOP generated from `grammar/lsd.lalrpop`, checked in (see `build.rs`).
#[rustfmt::skip]
#[allow(clippy::all, unused_parens, unused_imports, unused_extern_crates)]
mod grammar {
    include!("generated/lsd.rs");
}

/// How many times a file is parsed again with its slips repaired (see `repair`); slips found
/// after the last pass are reported without a repair.
const MAX_REPAIR_PASSES: usize = 16;

/// Parses one file. The program is returned even when there are errors: declarations that could
/// not be read become `DeclKind::Error`. A recognised slip (a missing comma, …) is reported and
/// the file parsed again with it repaired, so that what follows it is still read.
pub fn parse(file: FileId, text: &str) -> (Program, Vec<Diagnostic>) {
    let mut repairs = Vec::new();
    let mut slips = Vec::new();
    let mut passes = 0;
    loop {
        let recognise = passes < MAX_REPAIR_PASSES;
        passes += 1;
        let (program, lexical, syntax, found) = parse_pass(file, text, &repairs, recognise);
        if found.is_empty() {
            slips.extend(syntax);
            slips.sort_by_key(|d: &Diagnostic| d.primary_span().map(|s| s.start()));
            return (program, lexical.into_iter().chain(slips).collect());
        }
        for slip in found {
            repairs.push((slip.offset, slip.repair));
            slips.push(slip.diagnostic);
        }
    }
}

/// One parse with `repairs` applied: the program, the lexical and syntax errors (those of the
/// nesting limit among them), and the new slips found (only when `recognise`). Declarations
/// past the nesting limit are taken apart here, so that a pass's program is dropped safely
/// when the file is parsed again.
fn parse_pass(
    file: FileId,
    text: &str,
    repairs: &[(usize, Repair)],
    recognise: bool,
) -> (Program, Vec<Diagnostic>, Vec<Diagnostic>, Vec<Slip>) {
    let mut tokens = Tokens::repaired(file, text, repairs.to_vec());
    let mut recovered = Vec::new();
    let mut names = Names::default();
    let parser = grammar::ProgramParser::new();
    let result = parser.parse(file, &mut recovered, &mut names, &mut tokens);
    let lexical = tokens.errors;
    let result = match result {
        Ok(mut program) if recovered.is_empty() => {
            let mut syntax = Vec::new();
            limit_nesting(&mut program, &mut syntax);
            return (program, lexical, syntax, Vec::new());
        }
        other => other,
    };
    // Describing a syntax error looks at the tokens before it: lexed again, only then.
    let (tokens, _) = lex(file, text);
    let context = ErrorContext {
        file,
        tokens: &tokens,
        text_len: text.len(),
    };
    let mut errors: Vec<_> = recovered.into_iter().map(|e| e.error).collect();
    let mut syntax = Vec::new();
    let program = match result {
        Ok(mut program) => {
            limit_nesting(&mut program, &mut syntax);
            program
        }
        Err(error) => {
            errors.push(error);
            Program { decls: Vec::new() }
        }
    };
    let mut slips = Vec::new();
    for error in errors {
        let slip = recognise
            .then(|| repair::recognise(file, &tokens, &error))
            .flatten()
            .filter(|slip| !repairs.iter().any(|(offset, _)| *offset == slip.offset));
        match slip {
            Some(slip) => slips.push(slip),
            None => syntax.push(context.describe(error)),
        }
    }
    (program, lexical, syntax, slips)
}

struct ErrorContext<'a, 'input> {
    file: FileId,
    tokens: &'a [Spanned<'input>],
    text_len: usize,
}

impl ErrorContext<'_, '_> {
    fn describe(&self, error: ParseError<usize, Tok<'_>, LexError>) -> Diagnostic {
        match error {
            ParseError::UnrecognizedToken {
                token: (start, token, end),
                expected,
            } => self.unexpected_token(Span::new(self.file, start, end), start, token, &expected),
            ParseError::ExtraToken {
                token: (start, token, end),
            } => Diagnostic::error("E0201", format!("unexpected {token}"))
                .primary(Span::new(self.file, start, end), "nothing can follow here"),
            ParseError::UnrecognizedEof { location, expected } => {
                let at = location.min(self.text_len);
                Diagnostic::error(
                    "E0202",
                    format!(
                        "unexpected end of file, expected {}",
                        expected_list(&expected)
                    ),
                )
                .primary(Span::new(self.file, at, at), "the file ends here")
                .with_help(missing_terminator_help(&expected))
            }
            ParseError::InvalidToken { location } => Diagnostic::error("E0101", "invalid token")
                .primary(
                    Span::new(self.file, location, location + 1),
                    "not part of any LSD token",
                ),
            ParseError::User { error } => Diagnostic::error("E0101", format!("{error:?}")),
        }
    }

    fn unexpected_token(
        &self,
        span: Span,
        start: usize,
        token: Tok<'_>,
        expected: &[String],
    ) -> Diagnostic {
        let message = format!("expected {}, found {token}", expected_list(expected));
        let diagnostic = Diagnostic::error("E0201", message);
        if let Some(opening) = self.unmatched_closing(start, token) {
            return diagnostic
                .primary(
                    span,
                    format!("this `{}` closes no `{opening}`", token.text()),
                )
                .help(format!("remove the extra `{}`", token.text()));
        }
        if expected.len() == 1 && expected[0] == "\"=\"" {
            let field = self
                .previous_token(start)
                .map(|t| t.to_string())
                .unwrap_or_default();
            return diagnostic.primary(span, "expected `=` here").help(format!(
                "a field is written `name = value`: insert `=` after {field}"
            ));
        }
        let label = if token == Tok::Semicolon {
            "unexpected `;`".to_string()
        } else {
            format!("unexpected {token}")
        };
        diagnostic
            .primary(span, label)
            .with_help(missing_terminator_help(expected))
    }

    /// For `]` or `)`: the matching opening bracket's text when this one closes nothing.
    fn unmatched_closing(&self, start: usize, token: Tok<'_>) -> Option<&'static str> {
        let (open, close) = match token {
            Tok::RBracket => (Tok::LBracket, Tok::RBracket),
            Tok::RParen => (Tok::LParen, Tok::RParen),
            _ => return None,
        };
        let mut depth = 0i64;
        for (position, t, _) in self.tokens.iter() {
            if *position >= start {
                break;
            }
            if *t == open {
                depth += 1;
            } else if *t == close {
                depth -= 1;
            } else if *t == Tok::Semicolon {
                depth = 0;
            }
        }
        (depth <= 0).then_some(open.text())
    }

    fn previous_token(&self, start: usize) -> Option<Tok<'_>> {
        let index = self.tokens.partition_point(|(s, _, _)| *s < start);
        index.checked_sub(1).map(|i| self.tokens[i].1)
    }
}

/// `"\"=\""` and `Identifier` as the parser names them, for people.
fn describe_expected(token: &str) -> String {
    match token {
        "Identifier" => "a name".to_string(),
        "Int" | "Float" => "a number".to_string(),
        "UnknownName" => "an unknown".to_string(),
        "Str" => "a string".to_string(),
        quoted => format!("`{}`", quoted.trim_matches('"')),
    }
}

/// The tokens that would go on with the expression just read (its operators, `.field`, `x'`,
/// a call's `(`, an index's `[`, `P:x`), as the parser names them.
const CONTINUING: [&str; 13] = [
    "\"+\"", "\"-\"", "\"*\"", "\"/\"", "\"^\"", "\"||\"", "\"++\"", "\"@\"", "\".\"", "\"'\"",
    "\"(\"", "\"[\"", "\":\"",
];

/// The tokens the parser could have taken, for people. Those that would have gone on with the
/// expression just read are left out when something else was possible: after `join a and b`,
/// `]` lacks a `with`, not a `|| axis`; in `[1, 2 3]`, a `,` or a `]`.
fn expected_list(expected: &[String]) -> String {
    let ends = |e: &&String| !CONTINUING.contains(&e.as_str());
    let kept: Vec<&String> = match expected.iter().any(|e| ends(&e)) {
        true => expected.iter().filter(ends).collect(),
        false => expected.iter().collect(),
    };
    let mut items: Vec<String> = kept.iter().map(|e| describe_expected(e)).collect();
    items.dedup();
    match items.len() {
        0 => "nothing".to_string(),
        1 => items.remove(0),
        n if n > 6 => "an expression".to_string(),
        _ => {
            let last = items.pop().unwrap_or_default();
            format!("{} or {last}", items.join(", "))
        }
    }
}

fn missing_terminator_help(expected: &[String]) -> Option<String> {
    let has = |t: &str| expected.iter().any(|e| e == t);
    if has("\";\"") {
        Some("every declaration ends with `;`".to_string())
    } else if has("\"end\"") {
        Some(
            "`body`, `link`, `force`, `torque`, `local` and `package` are closed by `end`"
                .to_string(),
        )
    } else {
        None
    }
}
