//! The repository speaks of itself: its files name its own paths relative to its root, and cite
//! notes by their titles, never by a path of the machine they were written on.

use std::path::{Path, PathBuf};

/// Folders that are not the project's own text: build output, version control, installed
/// editor packages, the fuzzers' working files.
const SKIPPED: [&str; 5] = ["target", ".git", "node_modules", "corpus", "artifacts"];

fn files(dir: &Path, into: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).expect("a readable folder") {
        let path = entry.expect("a directory entry").path();
        let name = path.file_name().unwrap().to_string_lossy().to_string();
        // `.git` is a file in a linked work tree, naming where the repository is.
        if SKIPPED.contains(&name.as_str()) {
            continue;
        }
        if path.is_dir() {
            files(&path, into);
        } else {
            into.push(path);
        }
    }
}

/// The roots of a work machine's home and work folders. Written in two pieces so that this file
/// does not name them itself.
fn machine_roots() -> Vec<String> {
    ["work", "root"]
        .iter()
        .map(|folder| format!("{}{folder}/", '/'))
        .collect()
}

#[test]
fn no_file_names_a_path_of_the_machine_it_was_written_on() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut all = Vec::new();
    files(root, &mut all);
    let roots = machine_roots();
    let mut found = Vec::new();
    for path in &all {
        // Binary files (images, fonts) are not read as text.
        let Ok(text) = std::fs::read_to_string(path) else {
            continue;
        };
        for (number, line) in text.lines().enumerate() {
            if roots.iter().any(|r| line.contains(r.as_str())) {
                let shown = path.strip_prefix(root).unwrap_or(path);
                found.push(format!(
                    "{}:{}: {}",
                    shown.display(),
                    number + 1,
                    line.trim()
                ));
            }
        }
    }
    assert!(
        found.is_empty(),
        "files name absolute paths of a machine (name the repository's own paths relatively, \
         cite notes by title):\n{}",
        found.join("\n")
    );
}
