//! `lsdc fmt`: lays out a program's tokens and comments in the documented style
//! (`docs/formatting.md`). Only the whitespace between tokens changes, so a formatted program has
//! the same tokens and the same comments as the original: its meaning cannot change. The line
//! breaks the author chose are kept (at most one blank line in a row), every declaration starts on
//! a line of its own, lines are indented by the blocks and brackets they are in, and spaces follow
//! fixed rules. The result depends only on the tokens, the comments and the kept line breaks, so
//! formatting twice gives the same text.

use std::path::{Path, PathBuf};

use crate::diag::Diagnostic;
use crate::source::FileId;
use crate::syntax::lexer::{comments_in_gap, lex, Tok};
use crate::syntax::parser::parse;

/// The indentation of one level.
const INDENT: &str = "  ";

/// Formats a whole file. A file that does not parse is left alone: its diagnostics are returned.
pub fn format(file: FileId, text: &str) -> Result<String, Vec<Diagnostic>> {
    let (_, diagnostics) = parse(file, text);
    if diagnostics.iter().any(Diagnostic::is_error) {
        return Err(diagnostics);
    }
    let pieces = pieces(file, text);
    let mut printer = Printer {
        declaration_start: true,
        ..Printer::default()
    };
    for (index, piece) in pieces.iter().enumerate() {
        let next = pieces[index + 1..].iter().find_map(|p| match p.kind {
            PieceKind::Token(token) => Some(token),
            PieceKind::Comment(_) => None,
        });
        printer.piece(piece, next);
    }
    Ok(printer.finish())
}

/// A token or a comment, with the number of line breaks before it in the original.
struct Piece<'a> {
    kind: PieceKind<'a>,
    breaks: usize,
}

#[derive(Clone, Copy)]
enum PieceKind<'a> {
    Token(Tok<'a>),
    Comment(&'a str),
}

/// The file's tokens and comments in order.
fn pieces(file: FileId, text: &str) -> Vec<Piece<'_>> {
    let (tokens, _) = lex(file, text);
    let mut pieces = Vec::with_capacity(tokens.len());
    let mut end = 0;
    let gap_ends = tokens
        .iter()
        .map(|(start, _, _)| *start)
        .chain([text.len()]);
    for (index, gap_end) in gap_ends.enumerate() {
        let gap = &text[end..gap_end];
        let mut position = 0;
        for comment in comments_in_gap(gap) {
            pieces.push(Piece {
                kind: PieceKind::Comment(&gap[comment.clone()]),
                breaks: line_breaks(&gap[position..comment.start]),
            });
            position = comment.end;
        }
        if let Some(&(_, token, token_end)) = tokens.get(index) {
            pieces.push(Piece {
                kind: PieceKind::Token(token),
                breaks: line_breaks(&gap[position..]),
            });
            end = token_end;
        }
    }
    pieces
}

fn line_breaks(whitespace: &str) -> usize {
    whitespace.matches('\n').count()
}

/// Something opened and not yet closed: a block (`body`, `link`, `force`, `torque`, `local`,
/// `simulate`, `package`, closed by `end`) or a bracket.
struct Open {
    /// The indentation of the line it was opened on: its closer goes back to it.
    line_indent: usize,
    package: bool,
}

#[derive(Default)]
struct Printer<'a> {
    out: String,
    open: Vec<Open>,
    /// The indentation of the line being written.
    line_indent: usize,
    /// The next token starts a declaration.
    declaration_start: bool,
    /// `package P` was read and its `=` not yet: the declarations start after it.
    package_header: bool,
    /// Inside the parameters of `let f(a : vector)`, where `:` has spaces around it.
    definition_parameters: bool,
    /// The last two tokens written, latest first.
    previous: Option<Tok<'a>>,
    before_previous: Option<Tok<'a>>,
    /// The previous token ends an operand (so a following `-` is a subtraction).
    previous_ends_operand: bool,
    /// The previous token is a sign (`-x`, `+x`), written against its operand.
    previous_is_sign: bool,
    previous_is_comment: bool,
    /// The index of the line being written.
    line: usize,
    /// A comment written after code on the current line, as (line, byte in the line): it
    /// becomes a trailing comment if nothing follows it on its line.
    comment_after_code: Option<(usize, usize)>,
    /// Trailing comments, aligned in `finish` when they are on consecutive lines.
    trailing: Vec<(usize, usize)>,
}

impl<'a> Printer<'a> {
    fn piece(&mut self, piece: &Piece<'a>, next: Option<Tok<'a>>) {
        match piece.kind {
            PieceKind::Comment(comment) => {
                self.separate(piece.breaks, None, true);
                let line_start = self.out.rfind('\n').map_or(0, |i| i + 1);
                let after_code = !self.out[line_start..].trim().is_empty();
                if after_code && !comment.contains('\n') {
                    self.comment_after_code = Some((self.line, self.out.len() - line_start));
                }
                self.line += line_breaks(comment);
                self.out.push_str(comment);
                self.previous_is_comment = true;
            }
            PieceKind::Token(token) => {
                let breaks = match self.previous {
                    // A declaration ends with its `;`: the next one starts on a new line.
                    Some(Tok::Semicolon) if self.declaration_start => piece.breaks.max(1),
                    _ => piece.breaks,
                };
                self.separate(breaks, Some(token), false);
                self.out.push_str(&token_text(token));
                self.after_token(token, next);
                self.previous_is_comment = false;
            }
        }
    }

    /// Writes what goes between the previous piece and this one: line breaks and indentation,
    /// or a space or nothing.
    fn separate(&mut self, breaks: usize, token: Option<Tok<'_>>, comment: bool) {
        let comment_after_code = self.comment_after_code.take();
        if self.out.is_empty() {
            self.line_indent = self.indent_for(token);
            self.out.push_str(&INDENT.repeat(self.line_indent));
            return;
        }
        if breaks > 0 {
            self.trailing.extend(comment_after_code);
            self.line += breaks.min(2);
            let kept = self.out.trim_end_matches([' ', '\t']).len();
            self.out.truncate(kept);
            self.out.push_str(&"\n".repeat(breaks.min(2)));
            self.line_indent = self.indent_for(token);
            self.out.push_str(&INDENT.repeat(self.line_indent));
        } else if comment || self.previous_is_comment || self.space_before(token) {
            self.out.push(' ');
        }
    }

    /// The indentation of a line that starts with `token` (`None`: a comment).
    fn indent_for(&self, token: Option<Tok<'_>>) -> usize {
        let closes = matches!(
            token,
            Some(Tok::End | Tok::RParen | Tok::RBracket | Tok::In)
        );
        match self.open.last() {
            Some(open) if closes => open.line_indent,
            Some(open) if !open.package => open.line_indent + 1,
            innermost => {
                let declarations = innermost.map_or(0, |open| open.line_indent + 1);
                declarations + usize::from(!self.declaration_start)
            }
        }
    }

    fn space_before(&self, token: Option<Tok<'_>>) -> bool {
        let Some(token) = token else {
            return true;
        };
        let Some(previous) = self.previous else {
            return false;
        };
        match (previous, token) {
            (_, Tok::Semicolon) => true,
            (_, Tok::Comma | Tok::RParen | Tok::RBracket | Tok::Dot | Tok::Prime) => false,
            (Tok::LParen | Tok::LBracket | Tok::Dot, _) => false,
            // `+ +x` and `- -x` stay apart (`++` is an operator of its own).
            (Tok::Plus, Tok::Plus | Tok::PlusPlus) => true,
            _ if self.previous_is_sign => false,
            (Tok::Ident(_) | Tok::Unknown(_) | Tok::Link, Tok::LParen) => false,
            // An index: `P[k]:x`, `package P[i in 1 .. 3]`.
            (Tok::Ident(_), Tok::LBracket) => false,
            (Tok::Colon, _) | (_, Tok::Colon) => self.definition_parameters,
            _ => true,
        }
    }

    /// Updates what is open and what the token was.
    fn after_token(&mut self, token: Tok<'a>, next: Option<Tok<'a>>) {
        let sign = matches!(token, Tok::Minus | Tok::Plus) && !self.previous_ends_operand;
        let field_name = self.previous == Some(Tok::Dot) || next == Some(Tok::Equal);
        match token {
            Tok::LParen => {
                let parameters = matches!(self.previous, Some(Tok::Ident(_)))
                    && self.before_previous == Some(Tok::Let);
                self.definition_parameters = parameters;
                self.push(false);
            }
            Tok::LBracket => self.push(false),
            Tok::Body | Tok::Force | Tok::Torque if !field_name => self.push(false),
            Tok::Link | Tok::Local | Tok::Simulate => self.push(false),
            Tok::Package | Tok::Scene => {
                self.push(true);
                self.package_header = true;
            }
            Tok::End | Tok::RParen | Tok::RBracket => {
                self.open.pop();
                self.definition_parameters = false;
            }
            _ => {}
        }
        let at_declaration_level = self.open.last().is_none_or(|open| open.package);
        self.declaration_start = match token {
            Tok::Semicolon => at_declaration_level,
            Tok::Equal if self.package_header => {
                self.package_header = false;
                true
            }
            _ => false,
        };
        self.previous_ends_operand = match token {
            Tok::Ident(_) | Tok::Int(_) | Tok::Float(_) | Tok::Unknown(_) | Tok::Str(_) => true,
            Tok::RParen | Tok::RBracket | Tok::Prime | Tok::End => true,
            Tok::Body | Tok::Force | Tok::Torque => self.previous == Some(Tok::Dot),
            _ => false,
        };
        self.previous_is_sign = sign;
        self.before_previous = self.previous;
        self.previous = Some(token);
    }

    fn push(&mut self, package: bool) {
        self.open.push(Open {
            line_indent: self.line_indent,
            package,
        });
    }

    fn finish(mut self) -> String {
        self.trailing.extend(self.comment_after_code.take());
        let kept = self.out.trim_end().len();
        self.out.truncate(kept);
        if self.out.is_empty() {
            return String::new();
        }
        let mut text = align_trailing_comments(&self.out, &self.trailing);
        text.push('\n');
        text
    }
}

/// Trailing comments of consecutive lines start in one column, a space after the longest code.
/// `trailing` holds (line, byte where the comment starts), in line order.
fn align_trailing_comments(text: &str, trailing: &[(usize, usize)]) -> String {
    let mut lines: Vec<String> = text.split('\n').map(str::to_string).collect();
    let mut run_start = 0;
    while run_start < trailing.len() {
        let mut run_end = run_start + 1;
        while run_end < trailing.len() && trailing[run_end].0 == trailing[run_end - 1].0 + 1 {
            run_end += 1;
        }
        let run = &trailing[run_start..run_end];
        let code_width =
            |&(line, start): &(usize, usize)| lines[line][..start].trim_end().chars().count();
        let column = run.iter().map(code_width).max().unwrap_or(0) + 1;
        for &(line, start) in run {
            let code = lines[line][..start].trim_end().to_string();
            let padding = column - code.chars().count();
            lines[line] = format!("{code}{}{}", " ".repeat(padding), &lines[line][start..]);
        }
        run_start = run_end;
    }
    lines.join("\n")
}

/// The token as written in the source.
fn token_text(token: Tok<'_>) -> String {
    match token {
        Tok::Int(s) | Tok::Float(s) | Tok::Ident(s) => s.to_string(),
        Tok::Unknown(s) => format!("?{s}"),
        Tok::Str(s) => format!("\"{s}\""),
        other => other.text().to_string(),
    }
}

/// The files `lsdc fmt` is given: files as they are, directories searched (recursively) for
/// `.lsd` files, in name order.
pub fn lsd_files(paths: &[PathBuf]) -> Result<Vec<PathBuf>, String> {
    let mut files = Vec::new();
    for path in paths {
        if path.is_dir() {
            collect_lsd_files(path, &mut files)
                .map_err(|e| format!("cannot read `{}`: {e}", path.display()))?;
        } else {
            files.push(path.clone());
        }
    }
    Ok(files)
}

fn collect_lsd_files(dir: &Path, files: &mut Vec<PathBuf>) -> std::io::Result<()> {
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir)?
        .map(|entry| entry.map(|e| e.path()))
        .collect::<Result<_, _>>()?;
    entries.sort();
    for entry in entries {
        if entry.is_dir() {
            collect_lsd_files(&entry, files)?;
        } else if entry.extension().is_some_and(|e| e == "lsd") {
            files.push(entry);
        }
    }
    Ok(())
}
