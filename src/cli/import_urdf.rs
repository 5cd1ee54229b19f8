//! `lsdc import-urdf FILE`: a URDF robot description translated into an LSD program.

use std::path::PathBuf;
use std::process::ExitCode;

use super::shared::{err, printed, usage_error, write_output};
use lsdc::diag::render;
use lsdc::load::urdf::{import_urdf_at, ImportOptions};

#[derive(clap::Args)]
pub struct ImportUrdfArgs {
    file: PathBuf,
    /// Join the root link to earth by a free joint instead of welding it.
    #[arg(long)]
    floating_base: bool,
    /// Leave gravity out (by default every link with mass has its weight along -z).
    #[arg(long)]
    no_gravity: bool,
    /// Write the program to this file instead of standard output.
    #[arg(short = 'o', long = "out")]
    out: Option<PathBuf>,
}

/// Prints the LSD program imported from a URDF file, its warnings to standard error.
pub fn run(args: &ImportUrdfArgs) -> ExitCode {
    let file = &args.file;
    let options = ImportOptions {
        floating_base: args.floating_base,
        gravity: !args.no_gravity,
    };
    let text = match lsdc::load::read_source(file) {
        Ok(t) => t,
        Err(e) => return usage_error(&format!("cannot read `{}`: {e}", file.display())),
    };
    let mut sources = lsdc::source::SourceMap::new();
    let name = file.display().to_string();
    let id = sources.add(name.clone(), text);
    let imported = match import_urdf_at(id, &name, &sources.file(id).text, &options) {
        Ok(imported) => imported,
        Err(error) => {
            err(&render::to_text(&sources, &[error]));
            return ExitCode::from(1);
        }
    };
    err(&render::to_text(&sources, &printed(&imported.warnings)));
    write_output(args.out.as_deref(), &imported.text)
}
