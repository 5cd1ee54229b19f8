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

/// JSON that can sit inside a `<script>` element: `</` is written `<\/`.
fn embedded_json(value: &impl Serialize) -> String {
    serde_json::to_string(value)
        .unwrap_or_else(|_| "null".to_string())
        .replace("</", "<\\/")
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
    TEMPLATE
        .replace("{{title}}", &html_escape(&scene.title))
        .replace("{{scene}}", &embedded_json(scene))
        .replace("{{animation}}", &embedded_json(&animation))
        .replace("{{mode}}", &embedded_json(&Mode { live }))
        .replace("{{viewer}}", VIEWER)
        .replace("{{three}}", &three)
}

fn html_escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}
