//! `lsdc statics FILE --actuate JOIN.COORDINATE`: the efforts actuators must apply to hold the
//! mechanism at rest in its initial configuration.

use std::path::PathBuf;
use std::process::ExitCode;

use super::shared::{
    json, out, prepare_file, refuse_imposed_motion, usage_error, Format, LibraryArgs,
};
use lsdc::output::text;

#[derive(clap::Args)]
pub struct StaticsArgs {
    file: PathBuf,
    #[command(flatten)]
    libraries: LibraryArgs,
    /// A coordinate an actuator drives, `join.coordinate` (repeatable).
    #[arg(long = "actuate", value_name = "JOIN.COORDINATE", required = true)]
    actuated: Vec<String>,
    /// Value of an unknown, as for `simulate`. Repeatable.
    #[arg(long = "set", value_name = "NAME=VALUE")]
    sets: Vec<String>,
    #[arg(long, value_enum, default_value = "text")]
    format: Format,
}

pub fn run(args: &StaticsArgs) -> ExitCode {
    let (program, prepared) =
        match prepare_file(&args.file, &args.libraries, &args.sets, args.format) {
            Ok(prepared) => prepared,
            Err(code) => return code,
        };
    let help = "the efforts that impose the motion are `lsdc inverse`'s; for the efforts that hold the mechanism at rest, leave the motion free (remove the drive, or the time from the dof chain) and name its coordinate with --actuate";
    if let Err(code) = refuse_imposed_motion(&program, "`lsdc statics`", help, args.format) {
        return code;
    }
    let holding = match lsdc::studies::statics::holding_efforts(&prepared, &args.actuated) {
        Ok(h) => h,
        Err(error) => return usage_error(&error.to_string()),
    };
    match args.format {
        Format::Text => out(&text::holding(&holding)),
        Format::Json => out(&json(&holding)),
    }
    ExitCode::SUCCESS
}
