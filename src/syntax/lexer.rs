//! The LSD lexer (logos). Produces `(start, token, end)` triples for the LALRPOP parser and turns
//! every lexical error into a diagnostic instead of stopping: the parser then sees the tokens
//! around the bad character and can report the program's other errors in the same run.

use logos::{FilterResult, Logos};

use crate::diag::Diagnostic;
use crate::source::{FileId, Span};

#[derive(Clone, Debug, Default, PartialEq)]
pub enum LexError {
    #[default]
    UnexpectedCharacter,
    /// `(*` with no matching `*)`; the span of the error is the opening.
    UnterminatedComment,
    UnterminatedString,
}

#[derive(Logos, Clone, Copy, Debug, PartialEq)]
#[logos(error = LexError)]
#[logos(skip r"[ \t\r\n\f]+")]
pub enum Tok<'input> {
    #[token("(*", nested_comment)]
    Comment,

    #[token("and")]
    And,
    #[token("apply")]
    Apply,
    #[token("as")]
    As,
    #[token("between")]
    Between,
    #[token("body")]
    Body,
    #[token("end")]
    End,
    #[token("force")]
    Force,
    #[token("given")]
    Given,
    #[token("import")]
    Import,
    #[token("fixed")]
    Fixed,
    #[token("guess")]
    Guess,
    #[token("in")]
    In,
    #[token("initial")]
    Initial,
    #[token("join")]
    Join,
    #[token("let")]
    Let,
    #[token("link")]
    Link,
    #[token("local")]
    Local,
    #[token("on")]
    On,
    #[token("output")]
    Output,
    #[token("package")]
    Package,
    #[token("scene")]
    Scene,
    #[token("simulate")]
    Simulate,
    #[token("torque")]
    Torque,
    #[token("with")]
    With,

    #[token("^")]
    Caret,
    #[token(":")]
    Colon,
    #[token(",")]
    Comma,
    #[token("[")]
    LBracket,
    #[token("]")]
    RBracket,
    #[token("(")]
    LParen,
    #[token(")")]
    RParen,
    #[token(".")]
    Dot,
    #[token("..")]
    DotDot,
    #[token("=")]
    Equal,
    #[token("+")]
    Plus,
    #[token("++")]
    PlusPlus,
    #[token("*")]
    Star,
    #[token("-")]
    Minus,
    #[token("/")]
    Slash,
    #[token("@")]
    At,
    #[token("||")]
    Parallel,
    #[token(";")]
    Semicolon,
    #[token("'")]
    Prime,

    /// Integers; signs are unary operators, so `x -1` is a subtraction.
    #[regex(r"[0-9]+", |lex| lex.slice())]
    Int(&'input str),
    #[regex(r"[0-9]+(\.[0-9]+([eE][+-]?[0-9]+)?|(\.[0-9]+)?[eE][+-]?[0-9]+)", |lex| lex.slice())]
    Float(&'input str),
    /// Identifiers are Unicode: a letter or `_`, then letters, marks, digits or `_` (`rotoïde`).
    #[regex(r"[_\p{L}][_\p{L}\p{M}\p{N}]*", |lex| lex.slice())]
    Ident(&'input str),
    /// Unknowns: `?s`, `?fs`, `?k_2` (a letter, then letters, digits, underscores).
    #[regex(r"\?\p{L}[_\p{L}\p{M}\p{N}]*", |lex| &lex.slice()[1..])]
    Unknown(&'input str),
    /// Import paths: `"lib/joints.lsd"`, no escapes.
    #[regex(r#""[^"\n]*""#, |lex| { let s = lex.slice(); &s[1..s.len() - 1] })]
    Str(&'input str),
    #[regex(r#""[^"\n]*"#, unterminated_string)]
    UnterminatedStr,

    /// `// ...`, a comment in other languages: reported and skipped, never given to the parser.
    #[regex(r"//[^\n]*", allow_greedy = true)]
    SlashComment,
    /// `.5`: reported, then given to the parser as the number it means.
    #[regex(r"\.[0-9]+([eE][+-]?[0-9]+)?", |lex| lex.slice())]
    LeadingDot(&'input str),
}

fn unterminated_string<'input>(_: &mut logos::Lexer<'input, Tok<'input>>) -> Result<(), LexError> {
    Err(LexError::UnterminatedString)
}

/// Skips a comment `(* ... *)`, which may contain nested comments.
fn nested_comment<'input>(
    lex: &mut logos::Lexer<'input, Tok<'input>>,
) -> FilterResult<(), LexError> {
    let rest = lex.remainder();
    match comment_rest_length(rest) {
        Some(length) => {
            lex.bump(length);
            FilterResult::Skip
        }
        None => {
            // Everything after an unclosed `(*` is comment: consume it so it is not read as code.
            lex.bump(rest.len());
            FilterResult::Error(LexError::UnterminatedComment)
        }
    }
}

/// The length of a comment's text after its opening `(*`, up to and including the `*)` that
/// closes it (comments nest); `None` when it is never closed.
fn comment_rest_length(rest: &str) -> Option<usize> {
    let rest = rest.as_bytes();
    let mut depth = 1usize;
    let mut i = 0;
    while i < rest.len() {
        match (rest[i], rest.get(i + 1)) {
            (b'(', Some(b'*')) => {
                depth += 1;
                i += 2;
            }
            (b'*', Some(b')')) => {
                depth -= 1;
                i += 2;
                if depth == 0 {
                    return Some(i);
                }
            }
            _ => i += 1,
        }
    }
    None
}

/// The comments in the text between two tokens (which holds only spaces and comments), as
/// byte ranges relative to `gap`. The parser never sees comments; the formatter and the editor
/// support put them back.
pub fn comments_in_gap(gap: &str) -> Vec<std::ops::Range<usize>> {
    let mut comments = Vec::new();
    let mut i = 0;
    while let Some(offset) = gap[i..].find("(*") {
        let start = i + offset;
        let length = comment_rest_length(&gap[start + 2..]).unwrap_or(gap.len() - start - 2);
        comments.push(start..start + 2 + length);
        i = start + 2 + length;
    }
    comments
}

impl std::fmt::Display for Tok<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Tok::Int(s) | Tok::Float(s) | Tok::Ident(s) => write!(f, "`{s}`"),
            Tok::Unknown(s) => write!(f, "`?{s}`"),
            Tok::Str(s) => write!(f, "\"{s}\""),
            other => write!(f, "`{}`", other.text()),
        }
    }
}

impl Tok<'_> {
    /// The fixed text of keyword and punctuation tokens.
    pub fn text(&self) -> &'static str {
        match self {
            Tok::Comment => "(*",
            Tok::UnterminatedStr => "\"",
            Tok::And => "and",
            Tok::Apply => "apply",
            Tok::As => "as",
            Tok::Between => "between",
            Tok::Body => "body",
            Tok::End => "end",
            Tok::Force => "force",
            Tok::Given => "given",
            Tok::Import => "import",
            Tok::Fixed => "fixed",
            Tok::Guess => "guess",
            Tok::In => "in",
            Tok::Initial => "initial",
            Tok::Join => "join",
            Tok::Let => "let",
            Tok::Link => "link",
            Tok::Local => "local",
            Tok::On => "on",
            Tok::Output => "output",
            Tok::Package => "package",
            Tok::Scene => "scene",
            Tok::Simulate => "simulate",
            Tok::Torque => "torque",
            Tok::With => "with",
            Tok::Caret => "^",
            Tok::Colon => ":",
            Tok::Comma => ",",
            Tok::LBracket => "[",
            Tok::RBracket => "]",
            Tok::LParen => "(",
            Tok::RParen => ")",
            Tok::Dot => ".",
            Tok::DotDot => "..",
            Tok::Equal => "=",
            Tok::Plus => "+",
            Tok::PlusPlus => "++",
            Tok::Star => "*",
            Tok::Minus => "-",
            Tok::Slash => "/",
            Tok::At => "@",
            Tok::Parallel => "||",
            Tok::Semicolon => ";",
            Tok::Prime => "'",
            Tok::Int(_) => "integer",
            Tok::Float(_) => "number",
            Tok::Ident(_) => "identifier",
            Tok::Unknown(_) => "unknown",
            Tok::Str(_) => "string",
            Tok::SlashComment => "//",
            Tok::LeadingDot(_) => "number",
        }
    }
}

pub type Spanned<'input> = (usize, Tok<'input>, usize);

/// Lexes a whole file. Lexical errors are returned as diagnostics beside the good tokens.
pub fn lex(file: FileId, text: &str) -> (Vec<Spanned<'_>>, Vec<Diagnostic>) {
    let mut tokens = Tokens::new(file, text);
    let good = tokens
        .by_ref()
        .map(|token| token.expect("lex errors are set aside"))
        .collect();
    (good, tokens.errors)
}

/// The good tokens of a file one at a time, for the parser to read as they come (a file's
/// tokens held all at once take 40 bytes each, about five times the text); lexical errors are
/// set aside in `errors`. Never yields an `Err`: the item type is the one the parser reads.
pub struct Tokens<'input> {
    file: FileId,
    lexer: logos::Lexer<'input, Tok<'input>>,
    pub errors: Vec<Diagnostic>,
    /// Repairs of recognised slips, by the offset of the token they apply to, in order.
    repairs: Vec<(usize, Repair)>,
    /// A token held back while an inserted one is read.
    held: Option<Spanned<'input>>,
}

/// A change to the token stream that lets the parser read on past a slip it has recognised and
/// reported (see `syntax::repair`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Repair {
    /// A `,` before the token: a missing comma between fields.
    InsertComma,
    /// The string read as a name: `integrator = "rk4"`.
    Unquote,
    /// The token left out: a unit after a number (`30 deg`).
    Skip,
}

impl<'input> Tokens<'input> {
    pub fn new(file: FileId, text: &'input str) -> Tokens<'input> {
        Tokens::repaired(file, text, Vec::new())
    }

    /// The tokens with `repairs` applied, each to the token starting at its offset.
    pub fn repaired(
        file: FileId,
        text: &'input str,
        mut repairs: Vec<(usize, Repair)>,
    ) -> Tokens<'input> {
        // Popped from the end: the first repair last.
        repairs.sort_by_key(|(offset, _)| std::cmp::Reverse(*offset));
        Tokens {
            file,
            lexer: Tok::lexer(text),
            errors: Vec::new(),
            repairs,
            held: None,
        }
    }

    /// The token as the repairs make it: `None` when it is left out.
    fn repair(&mut self, token: Spanned<'input>) -> Option<Spanned<'input>> {
        let (start, tok, end) = token;
        while self
            .repairs
            .last()
            .is_some_and(|(offset, _)| *offset < start)
        {
            self.repairs.pop();
        }
        match self.repairs.last() {
            Some(&(offset, repair)) if offset == start => {
                self.repairs.pop();
                match (repair, tok) {
                    (Repair::InsertComma, _) => {
                        self.held = Some(token);
                        Some((start, Tok::Comma, start))
                    }
                    (Repair::Unquote, Tok::Str(name)) => Some((start, Tok::Ident(name), end)),
                    (Repair::Skip, _) => None,
                    (Repair::Unquote, _) => Some(token),
                }
            }
            _ => Some(token),
        }
    }
}

impl<'input> Iterator for Tokens<'input> {
    type Item = Result<Spanned<'input>, LexError>;

    fn next(&mut self) -> Option<Self::Item> {
        if let Some(held) = self.held.take() {
            return Some(Ok(held));
        }
        loop {
            let result = self.lexer.next()?;
            let range = self.lexer.span();
            let span = Span::new(self.file, range.start, range.end);
            let token = match result {
                Ok(Tok::SlashComment) => {
                    self.errors.push(slash_comment(span, self.lexer.slice()));
                    continue;
                }
                Ok(Tok::LeadingDot(number)) => {
                    self.errors.push(leading_dot(span, number));
                    Tok::Float(number)
                }
                Ok(token) => token,
                Err(error) => {
                    self.errors
                        .push(lex_diagnostic(error, span, self.lexer.slice()));
                    continue;
                }
            };
            if let Some(token) = self.repair((range.start, token, range.end)) {
                return Some(Ok(token));
            }
        }
    }
}

/// E0104: `// text`, with the LSD comment that says the same.
fn slash_comment(span: Span, slice: &str) -> Diagnostic {
    let text = slice.trim_start_matches('/').trim();
    Diagnostic::error("E0104", "`//` does not start a comment in LSD")
        .primary(span, "read as a comment, but LSD comments are `(* ... *)`")
        .help(format!("write `(* {text} *)`"))
        .fix(span, format!("(* {text} *)"))
}

/// E0105: `.5`, a number without its leading digit.
fn leading_dot(span: Span, number: &str) -> Diagnostic {
    Diagnostic::error("E0105", "a number starts with a digit")
        .primary(span, "no digit before the decimal point")
        .help(format!("write `0{number}`"))
        .fix(span, format!("0{number}"))
}

fn lex_diagnostic(error: LexError, span: Span, slice: &str) -> Diagnostic {
    match error {
        LexError::UnterminatedComment => Diagnostic::error("E0102", "unterminated comment")
            .primary(span.head(2), "this comment is never closed")
            .help("close it with `*)`; comments nest, so every `(*` inside needs its own `*)`"),
        LexError::UnterminatedString => Diagnostic::error("E0103", "unterminated string")
            .primary(span, "this string has no closing `\"` on its line"),
        LexError::UnexpectedCharacter => {
            let character = slice.chars().next().unwrap_or('?');
            let diagnostic =
                Diagnostic::error("E0101", format!("unexpected character `{character}`"))
                    .primary(span, "not part of any LSD token");
            match character {
                '?' => diagnostic
                    .help("an unknown is `?` followed by a letter, as in `?s` or `?fs(x, x')`"),
                '|' => diagnostic.help("the rotation operator is `||`, as in `th || [1,0,0]`"),
                '"' => diagnostic.help("strings appear only in `import \"file.lsd\";`"),
                '°' => diagnostic.help("angles are in radians: write `30 * pi / 180` for 30°"),
                _ => diagnostic,
            }
        }
    }
}
