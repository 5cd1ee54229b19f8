//! Elaboration: evaluates a checked program into a [`Mechanism`]. Runs only on programs without
//! errors, following the checker's name resolutions. Each `?s` occurrence evaluated creates a
//! fresh unknown; a `let` evaluates its value once, when first used, so `let L = ?s;` is one
//! shared unknown and an unused definition costs nothing.

mod arrays;
mod elaborator;
mod eval;
mod fields;
mod instances;
pub mod mechanism;
mod operations;
mod output;
mod own_join;
pub mod value;

use crate::check::Checked;
use crate::diag::Diagnostic;
use crate::load::Workspace;
use elaborator::Elaborator;
pub use mechanism::{Mechanism, Summary};
use rustc_hash::FxHashMap;

/// Evaluates every module of a checked workspace into one mechanism, with warnings about what
/// is legal but probably not meant.
pub fn elaborate(
    workspace: &Workspace,
    checked: &Checked<'_>,
) -> Result<(Mechanism, Vec<Diagnostic>), Diagnostic> {
    let mut elaborator = Elaborator {
        workspace,
        checked,
        globals: FxHashMap::default(),
        mechanism: Mechanism::default(),
        elaborated_modules: Vec::new(),
        depth: 0,
        fields: Vec::new(),
        literals: FxHashMap::default(),
        own_join: None,
        instances: Default::default(),
        aliases: FxHashMap::default(),
        warnings: Vec::new(),
    };
    for &root in &workspace.roots {
        elaborator.module(root)?;
    }
    elaborator.apply_fields()?;
    for &root in &workspace.roots {
        elaborator.name_frames(root)?;
    }
    Ok((elaborator.mechanism, elaborator.warnings))
}
