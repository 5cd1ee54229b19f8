//! `lsdc precision FILE`: speed against error, the work-precision table of several integrators
//! and tolerances (or fixed steps) against a tight reference.

use std::path::PathBuf;
use std::process::ExitCode;

use super::shared::{err, json, prepare_file, usage_error, write_output, Format, LibraryArgs};
use super::simulate::IntegratorArg;
use lsdc::api::{Prepared, SettingsChanges};
use lsdc::studies::precision::{self, computed_reference, Method, Reference, Setting};

#[derive(clap::Args)]
pub struct PrecisionArgs {
    file: PathBuf,
    #[command(flatten)]
    libraries: LibraryArgs,
    /// Value of an unknown, as for `simulate`. Repeatable.
    #[arg(long = "set", value_name = "NAME=VALUE")]
    sets: Vec<String>,
    /// The integrators to measure.
    #[arg(
        long,
        value_enum,
        value_delimiter = ',',
        default_value = "dopri5,dop853"
    )]
    integrators: Vec<IntegratorArg>,
    /// Tolerances (relative and absolute) of the adaptive integrators.
    #[arg(long, value_delimiter = ',', default_value = "1e-4,1e-6,1e-8,1e-10")]
    tolerances: Vec<f64>,
    /// Fixed steps of rk4 and symplectic.
    #[arg(long, value_delimiter = ',', default_value = "1e-2,3e-3,1e-3")]
    steps: Vec<f64>,
    /// A CSV of reference values (lsdc's columns: `time`, `join.q`, `join.q'`; any subset of
    /// them and of the output times) instead of a reference computed by lsdc.
    #[arg(long, value_name = "CSV")]
    reference: Option<PathBuf>,
    /// The integrator of the computed reference.
    #[arg(long, value_enum, default_value = "dop853")]
    reference_integrator: IntegratorArg,
    /// The tolerance of the computed reference (default: the tightest tolerance / 1000, at
    /// least 1e-14).
    #[arg(long)]
    reference_tolerance: Option<f64>,
    /// Runs of each method; the table gives the least and the median CPU time.
    #[arg(long, default_value_t = 3)]
    repeats: usize,
    /// Recommend the cheapest method whose position error is at most this.
    #[arg(long)]
    accuracy: Option<f64>,
    #[arg(long)]
    duration: Option<f64>,
    /// Time between outputs (the errors are measured at the outputs).
    #[arg(long = "every")]
    output_interval: Option<f64>,
    #[arg(long, value_enum, default_value = "text")]
    format: Format,
    /// Write the table to this file instead of standard output.
    #[arg(short = 'o', long = "out")]
    out: Option<PathBuf>,
    /// Draw the error against the CPU time (log-log, one curve per integrator) to an .svg or
    /// .png file.
    #[arg(long)]
    plot: Option<PathBuf>,
}

pub fn run(args: &PrecisionArgs) -> ExitCode {
    if let Err(message) = check_args(args) {
        return usage_error(&message);
    }
    let (_, mut prepared) = match prepare_file(&args.file, &args.libraries, &args.sets, args.format)
    {
        Ok(prepared) => prepared,
        Err(code) => return code,
    };
    let changes = SettingsChanges {
        duration: args.duration,
        output: args.output_interval,
        ..SettingsChanges::default()
    };
    if let Err(error) = prepared.settings.apply(&changes) {
        return usage_error(&error.to_string());
    }
    let table = reference(args, &mut prepared).and_then(|reference| {
        precision::table(
            &mut prepared,
            &methods(args),
            reference,
            args.repeats,
            args.accuracy,
        )
        .map_err(|error| error.to_string())
    });
    let table = match table {
        Ok(table) => table,
        Err(message) => {
            err(&format!("error: {message}\n"));
            return ExitCode::from(1);
        }
    };
    let text = match args.format {
        Format::Text => lsdc::output::text::precision(&table),
        Format::Json => json(&table),
    };
    let written = write_output(args.out.as_deref(), &text);
    match &args.plot {
        Some(path) => match lsdc::output::precision_plot::plot(&table, path) {
            Ok(()) => written,
            Err(error) => usage_error(&format!("cannot draw `{}`: {error}", path.display())),
        },
        None => written,
    }
}

/// The methods measured: each adaptive integrator at each tolerance, each fixed-step one at
/// each step.
fn methods(args: &PrecisionArgs) -> Vec<Method> {
    let mut methods = Vec::new();
    for &integrator in &args.integrators {
        let settings: Vec<Setting> = match integrator.fixed_step() {
            true => args.steps.iter().map(|&h| Setting::Step(h)).collect(),
            false => args
                .tolerances
                .iter()
                .map(|&t| Setting::Tolerance(t))
                .collect(),
        };
        methods.extend(settings.into_iter().map(|setting| Method {
            integrator: integrator.integrator(),
            setting,
        }));
    }
    methods
}

/// The options that must be positive numbers, and a usable plot name.
fn check_args(args: &PrecisionArgs) -> Result<(), String> {
    let lists = [("tolerances", &args.tolerances), ("steps", &args.steps)];
    for (option, values) in lists {
        if values.is_empty() || values.iter().any(|v| !(v.is_finite() && *v > 0.0)) {
            return Err(format!("`--{option}` must be positive numbers"));
        }
    }
    let single = [
        ("reference-tolerance", args.reference_tolerance),
        ("accuracy", args.accuracy),
    ];
    for (option, value) in single {
        if value.is_some_and(|v| !(v.is_finite() && v > 0.0)) {
            return Err(format!("`--{option}` must be a positive number"));
        }
    }
    if args.repeats == 0 {
        return Err("`--repeats` must be at least 1".to_string());
    }
    if let Some(path) = &args.plot {
        lsdc::output::plot::check_file_name(path)
            .map_err(|error| format!("cannot draw `{}`: {error}", path.display()))?;
    }
    Ok(())
}

/// The reference: the user's CSV, or a run at a much tighter tolerance.
fn reference(args: &PrecisionArgs, prepared: &mut Prepared) -> Result<Reference, String> {
    if let Some(path) = &args.reference {
        let name = path.display().to_string();
        let text = std::fs::read_to_string(path)
            .map_err(|error| format!("cannot read `{name}`: {error}"))?;
        return Reference::from_csv(&text, &name).map_err(|error| error.to_string());
    }
    let tightest = args
        .tolerances
        .iter()
        .copied()
        .fold(f64::INFINITY, f64::min);
    let tolerance = (args.reference_tolerance).unwrap_or((tightest / 1000.0).max(1e-14));
    let integrator = args.reference_integrator.integrator();
    computed_reference(prepared, &integrator, tolerance).map_err(|error| error.to_string())
}
