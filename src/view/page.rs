//! The viewer's page: one HTML file holding everything it needs — three.js, the viewer's
//! script and style, the scene and the animation as JSON — so that it opens without a network
//! (`lsdc view --export`) and the server has one page to send.

use serde::Serialize;

use super::scene::{Animation, Scene};

/// three.js's minified module build (npm package `three`, MIT licence in
/// `vendor/three.LICENSE`).
const THREE_MODULE: &str = include_str!("vendor/three.module.min.js");
const TEMPLATE: &str = include_str!("viewer.html");
const VIEWER: &str = include_str!("viewer.js");

/// three.js as a classic script that defines `window.THREE`: the module's closing
/// `export{a as B, …}` becomes that object. A module cannot be inlined and imported by name in
/// a file opened from disk; a classic script can. `None` if the build has no such statement.
pub fn three_script() -> Option<String> {
    let start = THREE_MODULE.rfind("export{")?;
    let end = start + THREE_MODULE[start..].find('}')?;
    let entries: Vec<String> = THREE_MODULE[start + "export{".len()..end]
        .split(',')
        .map(|entry| match entry.split_once(" as ") {
            Some((local, exported)) => format!("{}:{}", exported.trim(), local.trim()),
            None => entry.trim().to_string(),
        })
        .collect();
    Some(format!(
        "(function(){{\"use strict\";{}window.THREE={{{}}};}})();",
        &THREE_MODULE[..start],
        entries.join(",")
    ))
}

/// JSON that can sit inside a `<script>` element, whatever its strings hold: `<`, `>` and `&`
/// (which could close the element or open `<!--`, the HTML parser's escaped state) and U+2028/9
/// (line terminators in older JavaScript) are written as `\uXXXX` escapes. Outside strings,
/// serde_json writes none of them, so the escapes land only inside strings, where they mean
/// the same characters.
pub fn embedded_json(value: &impl Serialize) -> String {
    let json = serde_json::to_string(value).unwrap_or_else(|_| "null".to_string());
    let mut escaped = String::with_capacity(json.len());
    for c in json.chars() {
        match c {
            '<' => escaped.push_str("\\u003c"),
            '>' => escaped.push_str("\\u003e"),
            '&' => escaped.push_str("\\u0026"),
            '\u{2028}' => escaped.push_str("\\u2028"),
            '\u{2029}' => escaped.push_str("\\u2029"),
            c => escaped.push(c),
        }
    }
    escaped
}

/// How the page was made: served (`live`: it can run simulations and drag through the server)
/// or exported (standalone).
#[derive(Serialize)]
struct Mode {
    live: bool,
}

/// The page showing `scene`, playing `animation` if there is one.
pub fn page(scene: &Scene, animation: Option<&Animation>, live: bool) -> String {
    let three = three_script().unwrap_or_else(|| "window.THREE=null;".to_string());
    fill(
        TEMPLATE,
        &[
            ("title", html_escape(&scene.title)),
            ("scene", embedded_json(scene)),
            ("animation", embedded_json(&animation)),
            ("mode", embedded_json(&Mode { live })),
            ("viewer", VIEWER.to_string()),
            ("three", three),
        ],
    )
}

/// The template with each `{{name}}` replaced by its value, in one pass: a value is never
/// searched for placeholders (a title `{{three}}` stays a title).
fn fill(template: &str, values: &[(&str, String)]) -> String {
    let mut page =
        String::with_capacity(template.len() + values.iter().map(|(_, v)| v.len()).sum::<usize>());
    let mut rest = template;
    while let Some(start) = rest.find("{{") {
        let name_end = rest[start..].find("}}").map(|end| start + end);
        let value = name_end.and_then(|end| {
            let name = &rest[start + 2..end];
            values
                .iter()
                .find(|(n, _)| *n == name)
                .map(|(_, v)| (v, end + 2))
        });
        match value {
            Some((value, after)) => {
                page.push_str(&rest[..start]);
                page.push_str(value);
                rest = &rest[after..];
            }
            None => {
                page.push_str(&rest[..start + 2]);
                rest = &rest[start + 2..];
            }
        }
    }
    page.push_str(rest);
    page
}

fn html_escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}
