//! Reading a URDF file as an LSD program: `lsdc import-urdf`, and `.urdf` files given to any
//! command (the loader imports them with the default options).
//!
//! The translation (documented for users in `docs/commands.md`):
//!
//! - each URDF link is a body whose reference frame is the link frame. Its `iframe` is the
//!   inertial origin turned onto the principal axes of the inertia tensor, `inertia` the
//!   principal moments. A link without mass and inertia is a massless body;
//! - each URDF joint is `join ORIGIN @ PARENT and CHILD with J as NAME`: URDF puts the child link
//!   frame at parent · origin · motion(q), which is LSD's dof chain from a join's first frame to
//!   its second;
//! - the root link is welded to earth, or joined to it by `free` for a floating base; gravity is
//!   the standard library's `weight` on every link with mass.
//!
//! Nothing is dropped silently: what LSD does not express (effort limits, geometry,
//! transmissions...) is a warning at the URDF element, and so is every name that had to change.
//! urdf-rs reads the values but keeps no positions, so the text is also parsed with roxmltree
//! (`document`), to point each diagnostic at its element and to report malformed XML where it
//! is. What urdf-rs would reject is checked first (`check`), so that the error has a place.
//!
//! The files: `document` locates, `check` validates, `tree` orders the links,
//! `program` writes the LSD program and its warnings, with `lsd` (LSD text), `inertia`
//! (mass properties) and `names` (LSD names).

mod check;
pub mod document;
pub mod inertia;
pub mod lsd;
mod names;
mod options;
mod program;
mod tree;

use crate::diag::Diagnostic;
use crate::source::FileId;
use document::Source;
#[cfg(lsdc_internals)]
pub use names::lsd_name;
pub use options::ImportOptions;
use program::Importer;
use tree::Tree;

#[derive(Clone, Debug)]
pub struct Imported {
    /// The LSD program.
    pub text: String,
    /// What the program leaves out of the URDF and the names it changed, in the order of the
    /// URDF text.
    pub warnings: Vec<Diagnostic>,
}

/// Imports a URDF text. `name` is the file name shown in the program's header. The
/// diagnostics' spans are in `FileId(0)`: render them against a `SourceMap` whose first file is
/// `xml` (use [`import_urdf_at`] for another file).
#[cfg(lsdc_internals)]
pub fn import_urdf(name: &str, xml: &str, options: &ImportOptions) -> Result<Imported, Diagnostic> {
    import_urdf_at(FileId(0), name, xml, options)
}

/// Imports a URDF text whose diagnostics point into `file`, the id `xml` has in the caller's
/// `SourceMap`.
pub fn import_urdf_at(
    file: FileId,
    name: &str,
    xml: &str,
    options: &ImportOptions,
) -> Result<Imported, Diagnostic> {
    let source = Source::parse(file, xml)?;
    check::check_structure(&source)?;
    let robot = urdf_rs::read_from_string(&source.urdf_text())
        .map_err(|e| check::rejected(&source, &e.to_string()))?;
    let tree = Tree::build(&robot, &source)?;
    let (text, mut warnings) = Importer::new(&robot, &source, &tree, options).program(name)?;
    warnings.sort_by_key(|d| d.primary_span().map(|s| s.start()));
    Ok(Imported { text, warnings })
}
