//! `lsdc sensitivity FILE --parameters NAME...`: the derivatives of a run's coordinates, rates,
//! states and outputs with respect to initial values and values of the program, along the run,
//! by the forward sensitivity equations (CSV or JSON, a report on standard error, a plot).

use std::path::PathBuf;
use std::process::ExitCode;

use super::shared::{
    err, json, load_program, parse_sets, refuse_imposed_motion, report_diagnostics, usage_error,
    write_output, Format, LibraryArgs, SampleFormat,
};
use super::simulate::RunSettingsArgs;
use lsdc::output::sensitivity;
use lsdc::studies::sensitivity::{sensitivities, SensitivityError};

#[derive(clap::Args)]
pub struct SensitivityArgs {
    file: PathBuf,
    #[command(flatten)]
    libraries: LibraryArgs,
    /// The parameters: an initial value (`swing.q`, its rate `swing.q'`) or a value of the
    /// program (an unknown or a `given` value, by any name `--set` accepts).
    #[arg(long = "parameters", value_name = "NAME", num_args = 1.., required = true)]
    parameters: Vec<String>,
    /// Value of an unknown, as for `simulate`. Repeatable.
    #[arg(long = "set", value_name = "NAME=VALUE")]
    sets: Vec<String>,
    #[command(flatten)]
    run: RunSettingsArgs,
    /// CSV: `time` and a column `d(QUANTITY)/d(PARAMETER)` per quantity and parameter; JSON:
    /// the values too, and the derivatives at the end of the run (`final`).
    #[arg(long, value_enum, default_value = "csv")]
    format: SampleFormat,
    /// Write the result to this file instead of standard output.
    #[arg(short = 'o', long = "out")]
    out: Option<PathBuf>,
    /// Draw the derivatives of the coordinates and outputs over time, a panel per parameter,
    /// to an .svg or .png file.
    #[arg(long)]
    plot: Option<PathBuf>,
}

pub fn run(args: &SensitivityArgs) -> ExitCode {
    // Diagnostics go as JSON where the result would.
    let format = match args.format {
        SampleFormat::Csv => Format::Text,
        SampleFormat::Json => Format::Json,
    };
    let overrides = match parse_sets(&args.sets) {
        Ok(overrides) => overrides,
        Err(code) => return code,
    };
    if let Some(path) = &args.plot {
        if let Err(error) = lsdc::output::plot::check_path(path) {
            return usage_error(&format!("`--plot {}`: {error}", path.display()));
        }
    }
    let program = match load_program(&args.file, &args.libraries.options(), format) {
        Ok(program) => program,
        Err(code) => return code,
    };
    let subject = "`lsdc sensitivity`";
    let help = "the sensitivities would need the derivatives of the imposed laws' rows: difference whole runs instead (`lsdc sweep --grid NAME=...`)";
    if let Err(code) = refuse_imposed_motion(&program, subject, help, format) {
        return code;
    }
    let Ok(mechanism) = program.mechanism() else {
        return ExitCode::from(1);
    };
    let changes = args.run.changes();
    let result = match sensitivities(mechanism, &overrides, &changes, &args.parameters) {
        Ok(result) => result,
        Err(SensitivityError::Program(diagnostics)) => {
            report_diagnostics(&program, &diagnostics, format);
            return ExitCode::from(1);
        }
        Err(SensitivityError::Settings(message)) => return usage_error(&message),
    };
    if !result.warnings.is_empty() {
        report_diagnostics(&program, &result.warnings, format);
    }
    err(&sensitivity::report(&result));
    let text = match args.format {
        SampleFormat::Csv => sensitivity::csv(&result),
        SampleFormat::Json => json(&sensitivity::json(&result)),
    };
    let written = write_output(args.out.as_deref(), &text);
    if let Some(path) = &args.plot {
        if let Err(error) = sensitivity::plot(&result, path) {
            err(&format!("error: `--plot {}`: {error}\n", path.display()));
        }
    }
    match result.report.failure {
        Some(_) => ExitCode::from(1),
        None => written,
    }
}
