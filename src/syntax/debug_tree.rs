//! The syntax tree as `lsdc parse` prints it: the layout of Rust's pretty debug output
//! (`{:#?}`), produced from the compact debug output (`{:?}`) in one pass.
//!
//! `{:#?}` indents through one adapter per level of nesting, each byte passing through all of
//! them: printing a tree of depth d took time in d³ (a 400-term sum took minutes). The compact
//! form is written in time linear in its length, and laying it out is one pass over it, so the
//! time is linear in what is printed. (What is printed still grows with the square of the depth,
//! by its indentation; the nesting limit, E0203, bounds the depth.)

/// The indentation of one level, as `{:#?}` has it.
const INDENT: &str = "    ";

/// `compact` (the `{:?}` text of a value whose `Debug` is derived) laid out as `{:#?}` lays it
/// out: every field, element and argument on its own line, a comma after each, one indentation
/// per level. Quoted strings and characters are copied as they are.
pub fn pretty(compact: &str) -> String {
    let mut out = String::with_capacity(compact.len() * 2);
    let mut depth = 0usize;
    let mut chars = compact.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '"' | '\'' => copy_quoted(c, &mut chars, &mut out),
            '{' | '(' | '[' => {
                out.push(c);
                let close = closer(c);
                if chars.peek() == Some(&close) {
                    out.push(chars.next().unwrap_or(close));
                    continue;
                }
                // A struct's fields follow `{ `; a map's entries follow `{`.
                if c == '{' && chars.peek() == Some(&' ') {
                    chars.next();
                }
                depth += 1;
                new_line(&mut out, depth);
            }
            ',' if chars.peek() == Some(&' ') => {
                chars.next();
                out.push(',');
                new_line(&mut out, depth);
            }
            ' ' if chars.peek() == Some(&'}') => {}
            '}' | ')' | ']' => {
                depth = depth.saturating_sub(1);
                out.push(',');
                new_line(&mut out, depth);
                out.push(c);
            }
            _ => out.push(c),
        }
    }
    out
}

/// The bracket that closes `open`.
fn closer(open: char) -> char {
    match open {
        '{' => '}',
        '(' => ')',
        _ => ']',
    }
}

fn new_line(out: &mut String, depth: usize) {
    out.push('\n');
    for _ in 0..depth {
        out.push_str(INDENT);
    }
}

/// Copies a string or character literal that starts with `quote` (already read), escapes
/// included, up to its closing quote.
fn copy_quoted(quote: char, chars: &mut impl Iterator<Item = char>, out: &mut String) {
    out.push(quote);
    while let Some(c) = chars.next() {
        out.push(c);
        if c == '\\' {
            if let Some(escaped) = chars.next() {
                out.push(escaped);
            }
        } else if c == quote {
            return;
        }
    }
}
