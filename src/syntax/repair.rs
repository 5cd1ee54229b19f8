//! Slips a newcomer makes that the parser can read past once recognised: a missing comma
//! between fields, a string where a name is expected, a unit after a number. Each is reported
//! with the fix, and the file is parsed again with the token stream repaired, so the errors
//! after it (and the checker's) are still found.

use lalrpop_util::ParseError;

use crate::diag::Diagnostic;
use crate::source::{FileId, Span};
use crate::syntax::lexer::{LexError, Repair, Spanned, Tok};

/// A recognised slip: where to repair the token stream, how, and the error to report.
pub(super) struct Slip {
    pub(super) offset: usize,
    pub(super) repair: Repair,
    pub(super) diagnostic: Diagnostic,
}

/// The slip behind a syntax error, if it is one of those recognised. `tokens` are the file's
/// tokens, unrepaired.
pub(super) fn recognise(
    file: FileId,
    tokens: &[Spanned<'_>],
    error: &ParseError<usize, Tok<'_>, LexError>,
) -> Option<Slip> {
    let ParseError::UnrecognizedToken {
        token: (start, token, end),
        expected,
    } = error
    else {
        return None;
    };
    let at = tokens.partition_point(|(s, _, _)| s < start);
    let previous = at.checked_sub(1).and_then(|i| tokens.get(i));
    let next = tokens.get(at + 1).map(|(_, t, _)| *t);
    let expects = |t: &str| expected.iter().any(|e| e == t);
    let span = Span::new(file, *start, *end);
    let slip = |repair, diagnostic| {
        Some(Slip {
            offset: *start,
            repair,
            diagnostic,
        })
    };
    match (token, previous) {
        (Tok::Ident(_) | Tok::Force | Tok::Torque | Tok::Body | Tok::Output, Some(previous))
            if expects("\",\"") && next == Some(Tok::Equal) =>
        {
            slip(Repair::InsertComma, missing_comma(file, span, previous))
        }
        (Tok::Str(name), _) if expects("Identifier") && is_name(name) => {
            slip(Repair::Unquote, quoted_name(span, name))
        }
        (
            Tok::Ident(unit),
            Some(&(number_start, Tok::Int(number) | Tok::Float(number), number_end)),
        ) => {
            let (replacement, help) = unit_conversion(unit, number)?;
            let diagnostic = Diagnostic::error("E0206", "a number has no unit in LSD")
                .primary(span, "a unit")
                .help(help);
            let diagnostic = match replacement {
                Some(product) => diagnostic.fix(Span::new(file, number_start, *end), product),
                None => diagnostic.fix(Span::new(file, number_end, *end), ""),
            };
            slip(Repair::Skip, diagnostic)
        }
        _ => None,
    }
}

/// E0204: `mass = 1 iframe = 1`.
fn missing_comma(file: FileId, span: Span, previous: &Spanned<'_>) -> Diagnostic {
    let &(_, previous_token, previous_end) = previous;
    Diagnostic::error("E0204", "missing `,` between fields")
        .primary(span, "a new field starts here")
        .help(format!(
            "fields (and named arguments) are separated by commas: insert `,` after {previous_token}"
        ))
        .fix(Span::new(file, previous_end, previous_end), ",")
}

/// E0205: `integrator = "rk4"`.
fn quoted_name(span: Span, name: &str) -> Diagnostic {
    Diagnostic::error("E0205", "a string where a name is expected")
        .primary(span, "a string")
        .help(format!(
            "strings are only the file paths of `import \"file.lsd\"`: write the name without quotes, `{name}`"
        ))
        .fix(span, name)
}

fn is_name(text: &str) -> bool {
    let mut chars = text.chars();
    chars.next().is_some_and(|c| c.is_alphabetic() || c == '_')
        && chars.all(|c| c.is_alphanumeric() || c == '_')
}

/// For `30 deg`: the number in LSD's units when a product converts it (`Some("30 * pi /
/// 180")`), or `None` when the unit is the SI one and is simply removed; and the help.
fn unit_conversion(unit: &str, number: &str) -> Option<(Option<String>, String)> {
    let factor = match unit {
        "deg" | "degree" | "degrees" => {
            let product = format!("{number} * pi / 180");
            let help = format!("angles are in radians: write `{product}`");
            return Some((Some(product), help));
        }
        "rad" | "radian" | "radians" => {
            return Some((
                None,
                format!("angles are in radians already: write `{number}`"),
            ))
        }
        "m" | "kg" | "s" | "N" | "Nm" => None,
        "mm" | "g" | "ms" => Some("/ 1000"),
        "cm" => Some("/ 100"),
        "km" => Some("* 1000"),
        _ => return None,
    };
    let si = "values are in SI units (metres, kilograms, seconds, newtons, radians)";
    Some(match factor {
        None => (None, format!("{si}: write `{number}`")),
        Some(factor) => {
            let product = format!("{number} {factor}");
            let help = format!("{si}: write `{product}`");
            (Some(product), help)
        }
    })
}
