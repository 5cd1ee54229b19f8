//! Runs the front end's phases in order: load (parse and follow imports), check, elaborate.
//! Each phase runs only if the previous one found no errors.

use std::path::PathBuf;

use crate::check::{self, Checked};
use crate::diag::{Diagnostic, Diagnostics};
use crate::elab::{self, Mechanism, Perturbation};
use crate::load::{self, LoadError, LoadOptions, Workspace};

pub struct Compilation {
    pub workspace: Workspace,
    pub diagnostics: Vec<Diagnostic>,
    /// Present when the program has no errors.
    pub mechanism: Option<Mechanism>,
}

impl Compilation {
    pub fn has_errors(&self) -> bool {
        self.diagnostics.iter().any(Diagnostic::is_error)
    }
}

/// What becomes of the root files' syntax trees once the mechanism is elaborated.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Tree {
    /// Kept in the compilation's workspace.
    Keep,
    /// Each top-level declaration freed once it has been elaborated
    /// (`elab::elaborate_consuming`).
    Free,
}

/// Compiles files from disk.
#[cfg(lsdc_internals)]
pub fn compile_files(paths: &[PathBuf], options: &LoadOptions) -> Result<Compilation, LoadError> {
    compile_files_perturbed(paths, options, None)
}

/// As [`compile_files`], for commands that need only the mechanism, the diagnostics and the
/// sources: the syntax tree of each root file is freed as the mechanism is elaborated, so that
/// the front end's peak memory is the larger of the tree and the mechanism, not their sum. The
/// compilation's root modules have no declarations left.
pub fn compile_files_lean(
    paths: &[PathBuf],
    options: &LoadOptions,
) -> Result<Compilation, LoadError> {
    let (workspace, diagnostics) = load::load_files(paths, options)?;
    Ok(finish(workspace, diagnostics.list, None, Tree::Free))
}

/// Compiles files from disk, with the numbers written with a decimal point moved by `numbers`
/// (a round-off probe of the geometry: `lsdc test --calibrate`, `--perturb`).
pub fn compile_files_perturbed(
    paths: &[PathBuf],
    options: &LoadOptions,
    numbers: Option<Perturbation>,
) -> Result<Compilation, LoadError> {
    let (workspace, diagnostics) = load::load_files(paths, options)?;
    Ok(finish(workspace, diagnostics.list, numbers, Tree::Keep))
}

/// Compiles a program given as text; `dir` is where its relative imports are looked up.
pub fn compile_text(
    name: &str,
    text: &str,
    dir: Option<&std::path::Path>,
    options: &LoadOptions,
) -> Compilation {
    let (workspace, diagnostics) = load::load_text(name, text, dir, options);
    finish(workspace, diagnostics.list, None, Tree::Keep)
}

fn finish(
    mut workspace: Workspace,
    mut diagnostics: Vec<Diagnostic>,
    numbers: Option<Perturbation>,
    tree: Tree,
) -> Compilation {
    let mut mechanism = None;
    if !diagnostics.iter().any(Diagnostic::is_error) {
        let (checked, check_diagnostics) = check::check(&workspace);
        mechanism = check_and_elaborate(check_diagnostics, &mut diagnostics, || match tree {
            Tree::Keep => elab::elaborate_perturbed(&workspace, &checked, numbers),
            Tree::Free => elab::elaborate_consuming(&mut workspace, &checked, numbers),
        });
        mechanism = mechanism.map(|m| for_scene(m, &workspace, &mut diagnostics));
    }
    in_import_context(workspace, diagnostics, mechanism)
}

/// The mechanism reduced for the selected scene (`elab::scene`), when the program has scenes.
fn for_scene(
    mechanism: Mechanism,
    workspace: &Workspace,
    diagnostics: &mut Vec<Diagnostic>,
) -> Mechanism {
    let scenes = &workspace.scenes;
    let Some(name) = &scenes.selected else {
        return mechanism;
    };
    let (reduced, warnings) = elab::scene::reduce(mechanism, name, scenes.selected_span);
    diagnostics.extend(warnings);
    reduced
}

/// Compiles a program given as text for an editor: as [`compile_text`], and `inspect` sees the
/// checker's results (its scopes and name resolutions) and the mechanism. The checker runs even
/// when loading found errors, on what could be parsed, so that names can be resolved in a file
/// being typed; the diagnostics are those the command line reports.
pub fn compile_text_inspected<R>(
    name: &str,
    text: &str,
    dir: Option<&std::path::Path>,
    options: &LoadOptions,
    inspect: impl FnOnce(&Workspace, &Checked, Option<&Mechanism>) -> R,
) -> (Compilation, R) {
    let (workspace, diagnostics) = load::load_text(name, text, dir, options);
    let mut diagnostics = diagnostics.list;
    let load_failed = diagnostics.iter().any(Diagnostic::is_error);
    let (checked, check_diagnostics) = check::check(&workspace);
    let mechanism = if load_failed {
        None
    } else {
        check_and_elaborate(check_diagnostics, &mut diagnostics, || {
            elab::elaborate(&workspace, &checked)
        })
    };
    let inspected = inspect(&workspace, &checked, mechanism.as_ref());
    drop(checked);
    let compilation = in_import_context(workspace, diagnostics, mechanism);
    (compilation, inspected)
}

/// Adds the checker's diagnostics and, when it found no errors, elaborates the mechanism,
/// adding the elaborator's warnings or error.
fn check_and_elaborate(
    check_diagnostics: Diagnostics,
    diagnostics: &mut Vec<Diagnostic>,
    elaborate: impl FnOnce() -> Result<(Mechanism, Vec<Diagnostic>), Diagnostic>,
) -> Option<Mechanism> {
    let failed = check_diagnostics.has_errors();
    diagnostics.extend(check_diagnostics.list);
    if failed {
        return None;
    }
    match elaborate() {
        Ok((mechanism, warnings)) => {
            diagnostics.extend(warnings);
            Some(mechanism)
        }
        Err(diagnostic) => {
            diagnostics.push(diagnostic);
            None
        }
    }
}

fn in_import_context(
    workspace: Workspace,
    mut diagnostics: Vec<Diagnostic>,
    mechanism: Option<Mechanism>,
) -> Compilation {
    for diagnostic in &mut diagnostics {
        workspace.add_import_context(diagnostic);
    }
    Compilation {
        workspace,
        diagnostics,
        mechanism,
    }
}
