//! Runs the front end's phases in order: load (parse and follow imports), check, elaborate.
//! Each phase runs only if the previous one found no errors.

use std::path::PathBuf;

use crate::check;
use crate::diag::Diagnostic;
use crate::elab::{self, Mechanism};
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

/// Compiles files from disk.
pub fn compile_files(paths: &[PathBuf], options: &LoadOptions) -> Result<Compilation, LoadError> {
    let (workspace, diagnostics) = load::load_files(paths, options)?;
    Ok(finish(workspace, diagnostics.list))
}

/// Compiles a program given as text; `dir` is where its relative imports are looked up.
pub fn compile_text(
    name: &str,
    text: &str,
    dir: Option<&std::path::Path>,
    options: &LoadOptions,
) -> Compilation {
    let (workspace, diagnostics) = load::load_text(name, text, dir, options);
    finish(workspace, diagnostics.list)
}

fn finish(workspace: Workspace, mut diagnostics: Vec<Diagnostic>) -> Compilation {
    let mut mechanism = None;
    if !diagnostics.iter().any(Diagnostic::is_error) {
        let (checked, check_diagnostics) = check::check(&workspace);
        let failed = check_diagnostics.has_errors();
        diagnostics.extend(check_diagnostics.list);
        if !failed {
            match elab::elaborate(&workspace, &checked) {
                Ok((m, warnings)) => {
                    mechanism = Some(m);
                    diagnostics.extend(warnings);
                }
                Err(d) => diagnostics.push(d),
            }
        }
    }
    for diagnostic in &mut diagnostics {
        workspace.add_import_context(diagnostic);
    }
    Compilation {
        workspace,
        diagnostics,
        mechanism,
    }
}
