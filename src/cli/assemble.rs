//! `lsdc assemble FILE`: assembles the mechanism from its `initial` values and prints the
//! coordinates.

use std::path::PathBuf;
use std::process::ExitCode;

use super::shared::{report, Format, LibraryArgs};
use lsdc::elab::Mechanism;

#[derive(clap::Args)]
pub struct AssembleArgs {
    file: PathBuf,
    #[command(flatten)]
    libraries: LibraryArgs,
    #[arg(long, value_enum, default_value = "text")]
    format: Format,
}

pub fn run(args: &AssembleArgs) -> ExitCode {
    let analyse = |mechanism: &Mechanism| {
        let topology = lsdc::topology::build(mechanism)?;
        lsdc::studies::analysis::assembled_model(mechanism, topology, &Default::default())
            .map(|(_, report, warnings)| (report, warnings))
    };
    let options = args.libraries.options();
    report(
        &args.file,
        &options,
        args.format,
        analyse,
        lsdc::output::text::assembly,
    )
}
