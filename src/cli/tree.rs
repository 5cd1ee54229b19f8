//! `lsdc tree FILE`: the breadth-first numbering, principal and complementary links, joint
//! kinds and the mobility.

use std::path::PathBuf;
use std::process::ExitCode;

use super::shared::{report, Format, LibraryArgs};
use lsdc::elab::Mechanism;

#[derive(clap::Args)]
pub struct TreeArgs {
    file: PathBuf,
    #[command(flatten)]
    libraries: LibraryArgs,
    #[arg(long, value_enum, default_value = "text")]
    format: Format,
}

pub fn run(args: &TreeArgs) -> ExitCode {
    let analyse = |mechanism: &Mechanism| {
        lsdc::studies::analysis::tree(mechanism).map(|mut report| {
            let warnings = std::mem::take(&mut report.warnings);
            (report, warnings)
        })
    };
    let options = args.libraries.options();
    report(
        &args.file,
        &options,
        args.format,
        analyse,
        lsdc::output::text::tree,
    )
}
