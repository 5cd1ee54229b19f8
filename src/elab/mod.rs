//! Elaboration: evaluates a checked program into a [`Mechanism`]. Runs only on programs without
//! errors, following the checker's name resolutions. Each `?s` occurrence evaluated creates a
//! fresh unknown; a `let` evaluates its value once, when first used, so `let L = ?s;` is one
//! shared unknown and an unused definition costs nothing.

mod aim;
mod arrays;
mod constants;
mod decls;
mod effort_choice;
mod elaborator;
mod eval;
mod fields;
pub mod imposed_motion;
mod inputs;
mod instances;
mod laws;
pub mod mechanism;
pub mod model_laws;
mod operations;
mod output;
mod own_join;
mod owned;
mod piecewise;
pub mod scene;
pub mod scene_model;
mod states;
pub mod value;

use crate::check::Checked;
use crate::diag::Diagnostic;
use crate::load::Workspace;
pub use constants::constant_values;
use elaborator::Elaborator;
pub use elaborator::Perturbation;
pub use mechanism::{Mechanism, Summary};
use owned::OwnedDecls;

/// Evaluates every module of a checked workspace into one mechanism, with warnings about what
/// is legal but probably not meant.
pub fn elaborate(
    workspace: &Workspace,
    checked: &Checked,
) -> Result<(Mechanism, Vec<Diagnostic>), Diagnostic> {
    elaborate_perturbed(workspace, checked, None)
}

/// As [`elaborate`], with the numbers written with a decimal point moved by `numbers`.
pub fn elaborate_perturbed(
    workspace: &Workspace,
    checked: &Checked,
    numbers: Option<Perturbation>,
) -> Result<(Mechanism, Vec<Diagnostic>), Diagnostic> {
    run(Elaborator::new(workspace, checked), numbers)
}

/// As [`elaborate_perturbed`], freeing the syntax tree of the root files as it goes: each
/// top-level declaration once it has been elaborated (see `decls.rs`), so that the tree and the
/// mechanism are not both whole at once. The root files' declarations are gone afterwards
/// (`program.decls` is empty): for commands that need only the mechanism and the sources.
pub fn elaborate_consuming(
    workspace: &mut Workspace,
    checked: &Checked,
    numbers: Option<Perturbation>,
) -> Result<(Mechanism, Vec<Diagnostic>), Diagnostic> {
    let mut owned: Vec<Option<OwnedDecls>> = Vec::new();
    owned.resize_with(workspace.modules.len(), || None);
    for &root in &workspace.roots {
        let program = &mut workspace.modules[root.0 as usize].program;
        owned[root.0 as usize] = Some(OwnedDecls::new(std::mem::take(&mut program.decls)));
    }
    let mut elaborator = Elaborator::new(workspace, checked);
    elaborator.owned = owned;
    run(elaborator, numbers)
}

fn run(
    mut elaborator: Elaborator<'_, '_>,
    numbers: Option<Perturbation>,
) -> Result<(Mechanism, Vec<Diagnostic>), Diagnostic> {
    let workspace = elaborator.workspace;
    elaborator.perturbation = numbers;
    for &root in &workspace.roots {
        elaborator.module(root)?;
    }
    if let Some(filter) = &elaborator.effort_filter {
        if let Some(unanswered) = filter.unanswered() {
            return Err(unanswered);
        }
        elaborator.mechanism.applications_not_chosen = filter.left_out;
    }
    elaborator.apply_fields()?;
    for &root in &workspace.roots {
        elaborator.name_frames(root)?;
    }
    Ok((elaborator.mechanism, elaborator.warnings))
}
