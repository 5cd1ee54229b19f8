//! Text made safe for XML attributes and content (the URDF export, JUnit reports).

/// `text` with the five markup characters as entities, and the control characters XML 1.0 does
/// not allow (all but tab, newline and carriage return) as spaces.
pub fn escape(text: &str) -> String {
    let mut escaped = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => escaped.push_str("&amp;"),
            '<' => escaped.push_str("&lt;"),
            '>' => escaped.push_str("&gt;"),
            '"' => escaped.push_str("&quot;"),
            '\'' => escaped.push_str("&apos;"),
            c if c.is_control() && !matches!(c, '\n' | '\t' | '\r') => escaped.push(' '),
            c => escaped.push(c),
        }
    }
    escaped
}
