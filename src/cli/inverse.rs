//! `lsdc inverse FILE`: inverse dynamics along the program's drives: the efforts that impose
//! them, the power and, with `--reactions`, every join's reaction, as CSV or JSON; `--plot`
//! draws the run (the coordinates with the efforts, and the energy).

use std::path::PathBuf;
use std::process::ExitCode;

use super::shared::{
    err, json, out, prepare_program, usage_error, Format, LibraryArgs, SampleFormat,
};
use lsdc::api::SettingsChanges;
use lsdc::studies::inverse::{check_driven, from_run};

#[derive(clap::Args)]
pub struct InverseArgs {
    file: PathBuf,
    #[command(flatten)]
    libraries: LibraryArgs,
    /// Value of an unknown, as for `simulate`. Repeatable.
    #[arg(long = "set", value_name = "NAME=VALUE")]
    sets: Vec<String>,
    /// Overrides the program's `simulate` duration.
    #[arg(long)]
    duration: Option<f64>,
    /// Time between rows.
    #[arg(long = "every")]
    output_interval: Option<f64>,
    /// Add every join's reaction: the wrench it transmits to its second body, at the join, in
    /// the fixed axes (moment then force).
    #[arg(long)]
    reactions: bool,
    #[arg(long, value_enum, default_value = "csv")]
    format: SampleFormat,
    /// Draw the driven coordinates, the efforts and the energy over time to an .svg or .png.
    #[arg(long)]
    plot: Option<PathBuf>,
}

pub fn run(args: &InverseArgs) -> ExitCode {
    let changes = SettingsChanges {
        duration: args.duration,
        output: args.output_interval,
        reactions: args.reactions,
        ..Default::default()
    };
    let (_, prepared) = match prepare_program(
        &args.file,
        &args.libraries,
        &args.sets,
        &changes,
        Format::Text,
    ) {
        Ok(prepared) => prepared,
        Err(code) => return code,
    };
    if let Err(why) = check_driven(&prepared) {
        return usage_error(&why.to_string());
    }
    if let Some(path) = &args.plot {
        if let Err(error) = lsdc::output::plot::check_path(path) {
            return usage_error(&format!("cannot draw `{}`: {error}", path.display()));
        }
    }
    let simulation = lsdc::api::run(&prepared, &mut |_| {});
    let inverse = from_run(&prepared, &simulation);
    match args.format {
        SampleFormat::Csv => out(&inverse.to_csv()),
        SampleFormat::Json => out(&json(&inverse)),
    }
    if let Some(path) = &args.plot {
        if let Err(error) = lsdc::output::plot::plot(&simulation, path) {
            err(&format!(
                "error: cannot draw `{}`: {error}\n",
                path.display()
            ));
        }
    }
    match &simulation.report.failure {
        Some(failure) => {
            err(&format!(
                "error: the motion stopped at t = {}: {}\n",
                failure.time, failure.message
            ));
            ExitCode::from(1)
        }
        None => ExitCode::SUCCESS,
    }
}
