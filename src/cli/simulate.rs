//! `lsdc simulate FILE`: runs a mechanism from its `initial` values, streams its samples (CSV or
//! JSON) and prints the run report.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::ValueEnum;

use super::shared::{
    err, json, prepare_run_program, refuse_sampled, report_diagnostics, usage_error,
    usage_error_after_results, Format, LibraryArgs, SampleFormat,
};
use lsdc::api::{
    run_with, Diagnostic, Prepared, Program, Report, RunOptions, SettingsChanges, Simulation,
};
use lsdc::diag::render;
use lsdc::output::samples::{self, SampleWriter};

// The options that change a run's `simulate` declaration, read by `simulate` and `sweep`.
// (A plain comment: clap takes a flattened struct's doc comment for the description of the
// command it is flattened into.)
#[derive(clap::Args)]
pub struct RunSettingsArgs {
    /// Overrides the program's `simulate` declaration.
    #[arg(long, value_enum)]
    pub integrator: Option<IntegratorArg>,
    #[arg(long)]
    pub duration: Option<f64>,
    /// Time between outputs.
    #[arg(long = "every")]
    pub output_interval: Option<f64>,
    /// Relative and absolute tolerance of the adaptive integrators.
    #[arg(long)]
    pub tolerance: Option<f64>,
    /// Fixed step (rk4, symplectic) or first step (adaptive).
    #[arg(long)]
    pub step: Option<f64>,
    /// Most steps of the integrator, rejected ones included, before a run stops with a failure
    /// (its outputs kept).
    #[arg(long, value_name = "N", default_value_t = lsdc::prepare::settings::DEFAULT_MAX_STEPS)]
    pub max_steps: usize,
}

impl RunSettingsArgs {
    /// These options as changes to the program's `simulate` declaration.
    pub fn changes(&self) -> SettingsChanges {
        SettingsChanges {
            integrator: self.integrator.map(IntegratorArg::integrator),
            duration: self.duration,
            output: self.output_interval,
            tolerance: self.tolerance,
            step: self.step,
            max_steps: Some(self.max_steps),
            ..Default::default()
        }
    }
}

#[derive(clap::Args)]
pub struct SimulateArgs {
    file: PathBuf,
    #[command(flatten)]
    libraries: LibraryArgs,
    /// Value of an unknown or generic quantity: its `let` name, its generated name (see
    /// `lsdc compile --emit notation`) or its generic name (`mass(arm)`). Repeatable.
    #[arg(long = "set", value_name = "NAME=VALUE")]
    sets: Vec<String>,
    #[command(flatten)]
    run: RunSettingsArgs,
    /// Format of the samples.
    #[arg(long, value_enum, default_value = "csv")]
    format: SampleFormat,
    /// Write the samples to this file instead of standard output.
    #[arg(short = 'o', long = "out")]
    out: Option<PathBuf>,
    /// Format of the run report (written to standard error).
    #[arg(long, value_enum, default_value = "text")]
    report: Format,
    /// Draw the coordinates, the outputs and the energy over time to an .svg or .png file.
    #[arg(long)]
    plot: Option<PathBuf>,
    /// Draw only these columns (names of the samples' CSV header, separated by commas: a
    /// coordinate, its rate `name'`, `kinetic_energy`, `potential_energy`, an output), in one
    /// panel with its own scale; repeat it for more panels. Needs `--plot`.
    #[arg(long = "plot-columns", value_name = "NAMES", requires = "plot")]
    plot_columns: Vec<String>,
    /// How loops are kept closed: project the state onto the constraints after each step
    /// (exact), Baumgarte's feedback in the accelerations, or nothing.
    #[arg(long, value_enum, default_value = "projection")]
    stabilisation: StabilisationArg,
    /// Rate of Baumgarte's feedback, in 1/s (critically damped).
    #[arg(long, default_value_t = 10.0)]
    baumgarte_rate: f64,
    /// Output the reaction in every join: the wrench it transmits to its second body, at the
    /// join, in the fixed axes (moment then force).
    #[arg(long)]
    reactions: bool,
    /// Output the position, orientation (quaternion w, x, y, z), velocity and angular velocity
    /// of a frame, in the fixed frame: a frame the program names (`let tip = ... @ arm;`), a
    /// body's reference frame (its name) or `earth`. Repeatable.
    #[arg(long = "output-frame", value_name = "NAME")]
    output_frames: Vec<String>,
    /// Do not check whether an explicit integrator's steps are held by its stability region
    /// (W0901; the check costs three evaluations every 20 steps).
    #[arg(long)]
    no_stiffness_check: bool,
    /// Evaluate the equations of motion as native code: the generated C forward dynamics,
    /// compiled by the C compiler (`CC`, else `cc`) and kept in a cache (`LSDC_CACHE_DIR`,
    /// else `~/.cache/lsdc`). Trees only; where it cannot serve, a warning says why and the
    /// run goes on without it.
    #[arg(long)]
    compiled: bool,
    /// Evaluate a planar mechanism's equations of motion in planar form (3-vectors, 3 rows per
    /// loop): the same right-hand side to round-off, cheaper; off by default, since runs
    /// through singular configurations of loops amplify that round-off (docs/guarantees.md).
    #[arg(long)]
    planar: bool,
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum StabilisationArg {
    Projection,
    Baumgarte,
    None,
}

/// An integrator of the registry (`lsdc::integrators`), which gives clap its names and help.
#[derive(Clone, Copy)]
pub struct IntegratorArg(&'static lsdc::integrators::IntegratorEntry);

impl ValueEnum for IntegratorArg {
    fn value_variants<'a>() -> &'a [Self] {
        static VARIANTS: std::sync::OnceLock<Vec<IntegratorArg>> = std::sync::OnceLock::new();
        VARIANTS.get_or_init(|| {
            (lsdc::integrators::INTEGRATORS.iter())
                .map(IntegratorArg)
                .collect()
        })
    }

    fn to_possible_value(&self) -> Option<clap::builder::PossibleValue> {
        Some(clap::builder::PossibleValue::new(self.0.name).help(self.0.description))
    }
}

impl IntegratorArg {
    pub fn integrator(self) -> lsdc::prepare::Integrator {
        self.0.integrator.clone()
    }

    /// The integrator's name on the command line.
    pub fn name(self) -> &'static str {
        self.0.name
    }

    /// Whether the integrator takes a fixed step rather than tolerances.
    pub fn fixed_step(self) -> bool {
        self.0.fixed_step
    }
}

pub fn run(args: &SimulateArgs) -> ExitCode {
    let changes = settings_changes(args);
    let (program, mut prepared) = match prepare_run_program(
        &args.file,
        &args.libraries,
        &args.sets,
        &changes,
        args.report,
    ) {
        Ok(prepared) => prepared,
        Err(code) => return code,
    };
    if args.planar {
        if let Err(why) = prepared.take_planar() {
            prepared.warnings.push(not_planar_warning(&why));
        }
    }
    if !args.output_frames.is_empty() {
        if let Err(error) = program.output_frames(&mut prepared, &args.output_frames) {
            return usage_error(&error.to_string());
        }
    }
    // The plot's columns are checked before anything is written.
    let plot_columns = match lsdc::output::plot_columns::resolve(
        &prepared.coordinate_names,
        &lsdc::simulate::run::output_names_of(&prepared),
        &args.plot_columns,
    ) {
        Ok(columns) => columns,
        Err(unknown) => return usage_error(&unknown.to_string()),
    };
    if args.compiled {
        let help = "run without --compiled: the run lands on every sampling instant";
        let format = args.report;
        let refused = refuse_sampled(&program, &prepared, "`simulate --compiled`", help, format);
        if let Err(code) = refused {
            return code;
        }
        let native = program.attach_native(&mut prepared).unwrap_or_default();
        prepared.warnings.extend(native);
    }
    // Where the results go is checked before the run, not after it.
    let samples_out = match open_samples_output(args.out.as_deref()) {
        Ok(out) => out,
        Err(code) => return code,
    };
    if let Some(path) = &args.plot {
        if let Err(error) = lsdc::output::plot::check_path(path) {
            return usage_error(&format!("cannot draw `{}`: {error}", path.display()));
        }
    }
    // In JSON, the warnings of the program and of its preparation go in the report with the
    // run's own: standard output may carry the samples.
    let mut warnings = Vec::new();
    match args.report {
        Format::Json => {
            let program = program.diagnostics().iter().filter(|d| !d.is_error());
            warnings.extend(program.chain(&prepared.warnings).cloned());
        }
        Format::Text if !prepared.warnings.is_empty() => {
            report_diagnostics(&program, &prepared.warnings, Format::Text);
        }
        Format::Text => {}
    }
    let writer = samples::writer(sample_format(args.format), samples_out, &prepared);
    let (simulation, written) = run_and_write(args, &prepared, writer);
    let plotted = match &args.plot {
        Some(path) => lsdc::output::plot::plot_columns(&simulation, path, &plot_columns)
            .map_err(|error| format!("cannot draw `{}`: {error}", path.display())),
        None => Ok(()),
    };
    print_run_report(&program, &simulation.report, args.report, warnings);
    if let Err(message) = written {
        return usage_error_after_results(&message);
    }
    // A plot that cannot be drawn after the run (a run without outputs) does not change what
    // the run's exit code says.
    if let Err(message) = plotted {
        err(&format!("error: {message}\n"));
    }
    let report = &simulation.report;
    match (report.interrupted, &report.failure) {
        (Some(stop), _) => ExitCode::from((128 + stop.signal).min(255) as u8),
        (None, Some(_)) => ExitCode::from(1),
        (None, None) => ExitCode::SUCCESS,
    }
}

fn sample_format(format: SampleFormat) -> samples::SampleFormat {
    match format {
        SampleFormat::Csv => samples::SampleFormat::Csv,
        SampleFormat::Json => samples::SampleFormat::Json,
    }
}

/// The command line's changes to the program's `simulate` declaration.
fn settings_changes(args: &SimulateArgs) -> SettingsChanges {
    use lsdc::dynamics::loops::Stabilisation;
    SettingsChanges {
        stabilisation: Some(match args.stabilisation {
            StabilisationArg::Projection => Stabilisation::Projection,
            StabilisationArg::Baumgarte => Stabilisation::Baumgarte(args.baumgarte_rate),
            StabilisationArg::None => Stabilisation::None,
        }),
        reactions: args.reactions,
        no_stiffness_check: args.no_stiffness_check,
        ..args.run.changes()
    }
}

/// The file the samples go to (created, or emptied, now), or standard output.
fn open_samples_output(path: Option<&Path>) -> Result<Box<dyn Write>, ExitCode> {
    match path {
        Some(path) => match std::fs::File::create(path) {
            Ok(file) => Ok(Box::new(std::io::BufWriter::new(file))),
            Err(e) => Err(usage_error(&format!(
                "cannot write `{}`: {e}",
                path.display()
            ))),
        },
        None => Ok(Box::new(std::io::BufWriter::new(std::io::stdout()))),
    }
}

/// Runs the simulation, handing each sample to `writer` as it comes, until its end, a failure,
/// or SIGINT/SIGTERM; then ends the output.
fn run_and_write(
    args: &SimulateArgs,
    prepared: &Prepared,
    mut writer: Box<dyn SampleWriter>,
) -> (Simulation, Result<(), String>) {
    let target = (args.out.as_ref()).map_or("standard output".to_string(), |p| {
        format!("`{}`", p.display())
    });
    let options = RunOptions {
        keep_samples: args.plot.is_some() || writer.needs_kept_samples(),
        interrupt: interrupt_on_signals(),
    };
    let bar = progress_bar(prepared.settings.duration);
    let simulation = run_with(prepared, &options, &mut |sample| {
        if let Some(bar) = &bar {
            bar.set_position((sample.time * 1000.0) as u64);
        }
        writer.write_sample(sample);
    });
    if let Some(bar) = bar {
        bar.finish_and_clear();
    }
    let written = (writer.finish(&simulation)).map_err(|e| format!("cannot write {target}: {e}"));
    (simulation, written)
}

/// A progress bar on a terminal; nothing when standard error is not one (CI, pipes).
fn progress_bar(duration: f64) -> Option<indicatif::ProgressBar> {
    use std::io::IsTerminal;
    if !std::io::stderr().is_terminal() {
        return None;
    }
    let bar = indicatif::ProgressBar::new((duration * 1000.0) as u64);
    if let Ok(style) = indicatif::ProgressStyle::with_template(
        "{bar:40} {pos}/{len} ms simulated, {elapsed} elapsed",
    ) {
        bar.set_style(style);
    }
    Some(bar)
}

/// A flag that SIGINT and SIGTERM set to their number, for the run to stop between two steps
/// and its output and report to be finished; a second signal ends the process at once. `None`
/// where the handlers cannot be installed (the signals then end the process as usual).
pub fn interrupt_on_signals() -> Option<lsdc::api::Interrupt> {
    use signal_hook::consts::{SIGINT, SIGTERM};
    use std::sync::atomic::{AtomicBool, AtomicUsize};
    use std::sync::Arc;
    let requested = Arc::new(AtomicUsize::new(0));
    let signalled = Arc::new(AtomicBool::new(false));
    for signal in [SIGINT, SIGTERM] {
        let exit_code = 128 + signal;
        let installed =
            signal_hook::flag::register_conditional_shutdown(signal, exit_code, signalled.clone())
                .and_then(|_| signal_hook::flag::register(signal, signalled.clone()))
                .and_then(|_| {
                    signal_hook::flag::register_usize(signal, requested.clone(), signal as usize)
                });
        installed.ok()?;
    }
    Some(lsdc::api::Interrupt(requested))
}

/// The warnings the run found and its report, on standard error (in JSON, the warnings inside
/// the report: standard output may carry the samples).
fn print_run_report(
    program: &Program,
    report: &Report,
    format: Format,
    earlier_warnings: Vec<Diagnostic>,
) {
    let warnings: Vec<Diagnostic> = earlier_warnings
        .into_iter()
        .chain(report.warnings())
        .collect();
    match format {
        Format::Text => {
            report_diagnostics(program, &warnings, Format::Text);
            err(&lsdc::output::text::run_report(report));
        }
        Format::Json => {
            let mut value = serde_json::to_value(report).unwrap_or_default();
            if !warnings.is_empty() {
                value["warnings"] = render::to_json_value(program.sources(), &warnings);
            }
            err(&format!("{}\n", json(&value)));
        }
    }
}

/// Why `--planar` leaves the run in the spatial form (W0906).
fn not_planar_warning(why: &str) -> Diagnostic {
    Diagnostic::warning(
        "W0906",
        format!("--planar: the mechanism is not planar ({why}); the run keeps the spatial form"),
    )
    .help("`lsdc tree --format json` says whether the joints are planar, and if not, why; the efforts and the gravity field must be written in the plane too")
}
