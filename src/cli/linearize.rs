//! `lsdc linearize FILE`: the linear model ẋ = A x + B u, y = C x + D u of the mechanism about
//! its initial state, the state a run reaches (`--at-time`) or an equilibrium held by the
//! inputs (`--equilibrium`).

use std::path::PathBuf;
use std::process::ExitCode;

use clap::ValueEnum;

use super::shared::{
    json, prepare_program, refuse_sampled, report_diagnostics, usage_error, write_output,
    LibraryArgs,
};
use lsdc::api::SettingsChanges;
use lsdc::output::linearization;
use lsdc::studies::linearize::{linearize_by, Derivatives, OperatingPoint, Request};

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum LinearizationFormat {
    Text,
    /// Keys `A`, `B`, `C`, `D` (arrays of rows), `states`, `inputs`, `outputs`, `eigenvalues`.
    Json,
    /// A MATLAB or GNU Octave script that builds `sys = ss(A, B, C, D, ...)`.
    Matlab,
}

#[derive(clap::Args)]
pub struct LinearizeArgs {
    file: PathBuf,
    #[command(flatten)]
    libraries: LibraryArgs,
    /// Value of an unknown, as for `simulate`. Repeatable.
    #[arg(long = "set", value_name = "NAME=VALUE")]
    sets: Vec<String>,
    /// An input (repeatable; in this order, after the program's `input` declarations): a
    /// coordinate `join.coordinate` along which a generalised force is one, or a constant
    /// state of the program (`rate voltage = 0;`) held at the input's value.
    #[arg(long = "input", value_name = "JOIN.COORDINATE|STATE")]
    inputs: Vec<String>,
    /// With closed loops: an independent coordinate (repeatable, as many as the mobility);
    /// by default, the free coordinates the run chooses.
    #[arg(long = "coordinate", value_name = "JOIN.COORDINATE")]
    coordinates: Vec<String>,
    /// Linearise at the state a simulation reaches at this time (with zero inputs).
    #[arg(long, value_name = "T", conflicts_with = "equilibrium")]
    at_time: Option<f64>,
    /// Linearise at rest at the initial configuration, the inputs at the efforts that hold it
    /// there (as `lsdc statics` finds them).
    #[arg(long)]
    equilibrium: bool,
    /// With closed loops: A's and B's accelerations' rows by central differences even where
    /// the constrained dynamics' exact derivatives cover the mechanism (to compare the two).
    #[arg(long)]
    differenced: bool,
    /// Add the natural frequencies and damping ratios of the eigenvalues.
    #[arg(long)]
    modes: bool,
    #[arg(long, value_enum, default_value = "text")]
    format: LinearizationFormat,
    /// Write the result to this file instead of standard output.
    #[arg(short = 'o', long = "out")]
    out: Option<PathBuf>,
}

pub fn run(args: &LinearizeArgs) -> ExitCode {
    let format = match args.format {
        LinearizationFormat::Json => super::shared::Format::Json,
        _ => super::shared::Format::Text,
    };
    if let Some(time) = args.at_time {
        if !(time.is_finite() && time > 0.0) {
            return usage_error("`--at-time` must be a positive number of seconds");
        }
    }
    let changes = SettingsChanges {
        duration: args.at_time,
        ..Default::default()
    };
    let (program, prepared) =
        match prepare_program(&args.file, &args.libraries, &args.sets, &changes, format) {
            Ok(prepared) => prepared,
            Err(code) => return code,
        };
    if !prepared.warnings.is_empty() {
        report_diagnostics(&program, &prepared.warnings, format);
    }
    let help = "a sampled controller is not a linear time-invariant system: linearise the mechanism without it, or write its law as a continuous one";
    if let Err(code) = refuse_sampled(&program, &prepared, "`lsdc linearize`", help, format) {
        return code;
    }
    let point = match (args.at_time, args.equilibrium) {
        (Some(_), _) => OperatingPoint::EndOfRun,
        (None, true) => OperatingPoint::Equilibrium,
        (None, false) => OperatingPoint::Initial,
    };
    // The program's declared inputs come first (`linearize`), then those named here.
    let inputs = args.inputs.clone();
    let request = Request {
        point,
        inputs,
        coordinates: args.coordinates.clone(),
    };
    let derivatives = match args.differenced {
        true => Derivatives::Differenced,
        false => Derivatives::ExactWhereCovered,
    };
    let linearization = match linearize_by(&prepared, &request, derivatives) {
        Ok(l) => l,
        Err(error) => {
            let located = program.mechanism().ok().and_then(|m| error.diagnostic(m));
            if let Some(diagnostic) = located {
                report_diagnostics(&program, &[diagnostic], format);
                return ExitCode::from(1);
            }
            return usage_error(&error.to_string());
        }
    };
    let text = match args.format {
        LinearizationFormat::Text => linearization::text(&linearization, args.modes),
        LinearizationFormat::Matlab => {
            linearization::matlab(&linearization, &args.file.display().to_string())
        }
        LinearizationFormat::Json => {
            let mut value = serde_json::to_value(&linearization).unwrap_or_default();
            if let (false, Some(object)) = (args.modes, value.as_object_mut()) {
                object.remove("modes");
            }
            json(&value)
        }
    };
    write_output(args.out.as_deref(), &text)
}
