//! `lsdc export-urdf FILE`: a tree mechanism as a URDF robot description.

use std::path::PathBuf;
use std::process::ExitCode;

use super::shared::{err, prepare_file, warn, write_output, Format, LibraryArgs};
use lsdc::output::urdf;

#[derive(clap::Args)]
pub struct ExportUrdfArgs {
    file: PathBuf,
    #[command(flatten)]
    libraries: LibraryArgs,
    /// Value of an unknown, as for `simulate`. Repeatable.
    #[arg(long = "set", value_name = "NAME=VALUE")]
    sets: Vec<String>,
    /// Write the URDF to this file instead of standard output.
    #[arg(short = 'o', long = "out")]
    out: Option<PathBuf>,
    /// The robot's name (default: the file's name without its extension).
    #[arg(long)]
    name: Option<String>,
}

pub fn run(args: &ExportUrdfArgs) -> ExitCode {
    let file = &args.file;
    let (_, prepared) = match prepare_file(file, &args.libraries, &args.sets, Format::Text) {
        Ok(prepared) => prepared,
        Err(code) => return code,
    };
    let stem = file.file_stem().map(|s| s.to_string_lossy().into_owned());
    let name = (args.name.clone())
        .or(stem)
        .unwrap_or_else(|| "robot".to_string());
    let text = match urdf::export_urdf(&prepared.model, &name) {
        Ok(text) => text,
        Err(e) => {
            err(&format!(
                "error: {}\n",
                e.message(&file.display().to_string())
            ));
            return ExitCode::from(1);
        }
    };
    if let Some(dropped) = urdf::dropped_efforts(&prepared.model) {
        warn(&dropped);
    }
    write_output(args.out.as_deref(), &text)
}
