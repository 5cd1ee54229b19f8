//! The VS Code extension packages: `editors/vscode/package.sh` writes a `.vsix` holding the
//! manifest, the TextMate grammar, the language configuration, the client and the client's
//! library. Needs node and npm (and, the first time, npm's registry or its cache): without them
//! the test says so and checks nothing.

use std::path::{Path, PathBuf};
use std::process::Command;

fn installed(tool: &str) -> bool {
    Command::new(tool)
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success())
}

/// The names of the files a zip archive holds, from its central directory (a `.vsix` is a zip).
fn zip_entries(archive: &[u8]) -> Vec<String> {
    const CENTRAL_HEADER: [u8; 4] = [0x50, 0x4b, 0x01, 0x02];
    let u16_at = |at: usize| u16::from_le_bytes([archive[at], archive[at + 1]]) as usize;
    let mut names = Vec::new();
    let mut at = 0;
    while at + 46 <= archive.len() {
        if archive[at..at + 4] != CENTRAL_HEADER {
            at += 1;
            continue;
        }
        let length = u16_at(at + 28);
        let extra = u16_at(at + 30) + u16_at(at + 32);
        let name = &archive[at + 46..at + 46 + length];
        names.push(String::from_utf8_lossy(name).into_owned());
        at += 46 + length + extra;
    }
    names
}

#[test]
fn the_extension_packages_with_grammar_configuration_and_client() {
    if !(installed("node") && installed("npm")) {
        eprintln!("skipped: node and npm are needed to package the VS Code extension");
        return;
    }
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let out_dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("vsix");
    let _ = std::fs::remove_dir_all(&out_dir);
    let output = Command::new("sh")
        .arg(root.join("editors/vscode/package.sh"))
        .arg(&out_dir)
        .output()
        .expect("sh runs");
    assert!(
        output.status.success(),
        "package.sh failed:\n{}\n{}",
        String::from_utf8_lossy(&output.stdout),
        String::from_utf8_lossy(&output.stderr)
    );
    let vsix = std::fs::read_dir(&out_dir)
        .expect("the output directory")
        .map(|e| e.expect("an entry").path())
        .find(|p| p.extension().is_some_and(|e| e == "vsix"))
        .expect("a .vsix written");
    let entries = zip_entries(&std::fs::read(&vsix).expect("readable"));
    for expected in [
        "extension/package.json",
        "extension/syntaxes/lsd.tmLanguage.json",
        "extension/language-configuration.json",
        "extension/src/extension.js",
        "extension/node_modules/vscode-languageclient/node.js",
        "extension.vsixmanifest",
    ] {
        assert!(
            entries.iter().any(|e| e == expected),
            "{expected} missing from {}: {entries:?}",
            vsix.display()
        );
    }
    // The packaging tool is for building only: it does not ship.
    assert!(!entries
        .iter()
        .any(|e| e.contains("node_modules/@vscode/vsce")));
}
