//! The `lsdc` command line: wires the phases together, prints results and diagnostics.
//! Exit codes: 0 clean, 1 errors in the program, 2 usage errors (bad flags, unreadable files).

use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::atomic::Ordering;

use clap::{Parser, Subcommand, ValueEnum};

use lsdc::diag::{render, Diagnostic};
use lsdc::driver::{self, Compilation};
use lsdc::elab::Mechanism;
use lsdc::load::LoadOptions;
use lsdc::output::text;
use lsdc::studies::analysis;

mod cli;

#[derive(Parser)]
#[command(
    name = "lsdc",
    version,
    about = "Compiler and simulator for LSD mechanism descriptions"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
    /// Print no warnings (errors are still printed, and JSON results keep theirs).
    #[arg(short, long, global = true)]
    quiet: bool,
}

/// Set by `--quiet`: warnings are not printed.
static QUIET: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

fn quiet() -> bool {
    QUIET.load(std::sync::atomic::Ordering::Relaxed)
}

/// Set when the command line asks for JSON (`--format json`, `--report json`): usage errors are
/// then also printed as JSON on standard output, where the results would be.
static JSON_ASKED: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// Whether the arguments ask for JSON: `--format` or `--report` followed by `json`, or
/// `--format=json`, `--report=json`. Read from the raw arguments, so that the arguments clap
/// rejects are also reported as JSON.
fn asks_for_json(arguments: &[String]) -> bool {
    let option = |a: &str| a == "--format" || a == "--report";
    arguments
        .windows(2)
        .any(|w| option(&w[0]) && w[1] == "json")
        || (arguments.iter()).any(|a| a == "--format=json" || a == "--report=json")
}

/// The diagnostics to print as text: without the warnings under `--quiet`.
fn printed(diagnostics: &[Diagnostic]) -> Vec<Diagnostic> {
    let keep = |d: &&Diagnostic| d.is_error() || !quiet();
    diagnostics.iter().filter(keep).cloned().collect()
}

/// A warning of the command line itself, on standard error (not under `--quiet`).
fn warn(message: &str) {
    if !quiet() {
        eprintln!("warning: {message}");
    }
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum Format {
    Text,
    Json,
}

#[derive(clap::Args)]
struct SimulateArgs {
    file: PathBuf,
    #[command(flatten)]
    libraries: LibraryArgs,
    /// Value of an unknown or generic quantity: its `let` name, its generated name (see
    /// `lsdc compile --emit notation`) or its generic name (`mass(arm)`). Repeatable.
    #[arg(long = "set", value_name = "NAME=VALUE")]
    sets: Vec<String>,
    /// Overrides the program's `simulate` declaration.
    #[arg(long, value_enum)]
    integrator: Option<IntegratorArg>,
    #[arg(long)]
    duration: Option<f64>,
    /// Time between outputs.
    #[arg(long = "every")]
    output_interval: Option<f64>,
    /// Relative and absolute tolerance of the adaptive integrators.
    #[arg(long)]
    tolerance: Option<f64>,
    /// Fixed step (rk4, symplectic) or first step (adaptive).
    #[arg(long)]
    step: Option<f64>,
    /// Format of the samples.
    #[arg(long, value_enum, default_value = "csv")]
    format: SampleFormat,
    /// Write the samples to this file instead of standard output.
    #[arg(short = 'o', long = "out")]
    out: Option<PathBuf>,
    /// Format of the run report (written to standard error).
    #[arg(long, value_enum, default_value = "text")]
    report: Format,
    /// Draw the coordinates and the energy over time to an .svg or .png file.
    #[arg(long)]
    plot: Option<PathBuf>,
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
    /// Most steps of the integrator, rejected ones included, before the run stops with a
    /// failure (its outputs kept).
    #[arg(long, value_name = "N", default_value_t = lsdc::prepare::settings::DEFAULT_MAX_STEPS)]
    max_steps: usize,
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
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum StabilisationArg {
    Projection,
    Baumgarte,
    None,
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum IntegratorArg {
    Rk4,
    Dopri5,
    Dop853,
    Implicit,
    Symplectic,
}

impl IntegratorArg {
    fn integrator(self) -> lsdc::prepare::Integrator {
        use lsdc::prepare::Integrator;
        match self {
            IntegratorArg::Rk4 => Integrator::Rk4,
            IntegratorArg::Dopri5 => Integrator::DormandPrince,
            IntegratorArg::Dop853 => Integrator::Dop853,
            IntegratorArg::Implicit => Integrator::Implicit,
            IntegratorArg::Symplectic => Integrator::Symplectic,
        }
    }

    /// Whether the integrator takes a fixed step rather than tolerances.
    fn fixed_step(self) -> bool {
        matches!(self, IntegratorArg::Rk4 | IntegratorArg::Symplectic)
    }
}

#[derive(clap::Args)]
struct PrecisionArgs {
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

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum SampleFormat {
    Csv,
    Json,
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum Emit {
    Notation,
    Equations,
    Rust,
    C,
}

/// How `--emit equations` writes them.
#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum EquationsFormat {
    Text,
    Latex,
    Sympy,
    Json,
}

#[derive(clap::Args)]
struct LibraryArgs {
    /// Add a directory to the library search path (searched after the importing file's
    /// directory, before LSD_PATH and the standard library).
    #[arg(short = 'L', value_name = "DIR")]
    library_dirs: Vec<PathBuf>,
}

impl LibraryArgs {
    fn options(&self) -> LoadOptions {
        LoadOptions {
            library_dirs: self.library_dirs.clone(),
            use_environment: true,
        }
    }
}

#[derive(Subcommand)]
enum Command {
    /// Check programs and print a summary of the mechanism each describes.
    Check {
        #[arg(required = true)]
        files: Vec<PathBuf>,
        #[command(flatten)]
        libraries: LibraryArgs,
        #[arg(long, value_enum, default_value = "text")]
        format: Format,
    },
    /// Show the breadth-first numbering, principal and complementary links, joint kinds and
    /// the mobility.
    Tree {
        file: PathBuf,
        #[command(flatten)]
        libraries: LibraryArgs,
        #[arg(long, value_enum, default_value = "text")]
        format: Format,
    },
    /// Assemble the mechanism from its `initial` values and print the coordinates.
    Assemble {
        file: PathBuf,
        #[command(flatten)]
        libraries: LibraryArgs,
        #[arg(long, value_enum, default_value = "text")]
        format: Format,
    },
    /// Simulate a mechanism (tree or closed loops) from its `initial` values; write the samples
    /// (CSV or JSON) and a run report.
    Simulate(SimulateArgs),
    /// Speed against error: simulate with several integrators and tolerances (or fixed steps),
    /// compare each run with a tight reference at the outputs, and print the work-precision
    /// table (errors, closure, energy drift, steps, evaluations, CPU time).
    Precision(PrecisionArgs),
    /// Drag a point of a body along a path of targets, quasi-statically: the configuration at
    /// each target, the distance left, the loops' residual or the joints' gap, the energy.
    Drag(cli::drag::DragArgs),
    /// Show the mechanism in 3D in a web page: served on 127.0.0.1 (simulations on demand,
    /// bodies dragged with the mouse), or exported as one standalone HTML file.
    View(cli::view::ViewArgs),
    /// The efforts actuators must apply along the given coordinates to hold the mechanism at
    /// rest in its initial (assembled) configuration.
    Statics {
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
    },
    /// Compile a program and print what `--emit` asks for.
    Compile {
        file: PathBuf,
        #[command(flatten)]
        libraries: LibraryArgs,
        /// `notation`: the thesis-style notation table (structure, variables, declared and
        /// deduced assignments). `equations`: the equations of motion M q' = S + F + Δᵀ Λ,
        /// Δ q' + Δ̇q = 0 in the `--format` given. `rust`, `c`: source code that evaluates them
        /// and the forward dynamics.
        #[arg(long, value_enum)]
        emit: Emit,
        /// Format of `--emit equations` (default text).
        #[arg(long, value_enum)]
        format: Option<EquationsFormat>,
        /// Write to this file instead of standard output.
        #[arg(short = 'o', long = "out")]
        out: Option<PathBuf>,
    },
    /// Evaluate inverse dynamics (RNEA), the mass matrix (CRBA), forward dynamics (ABA) and the
    /// bodies' poses at a list of states; print JSON. A quantity that cannot be computed at a
    /// state (ABA with a singular mass matrix) is null, with the reason in the state's `errors`
    /// and a warning on standard error.
    Eval {
        file: PathBuf,
        #[command(flatten)]
        libraries: LibraryArgs,
        /// JSON file of states: {"states": [{"q": [..], "v": [..], "a": [..], "tau": [..]}]}.
        #[arg(long)]
        states: PathBuf,
        /// Value of an unknown, as for `simulate`. Repeatable.
        #[arg(long = "set", value_name = "NAME=VALUE")]
        sets: Vec<String>,
    },
    /// Write a tree mechanism as a URDF robot description: a link per body, a joint per join.
    ExportUrdf {
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
    },
    /// Translate a URDF robot description into an LSD program (standard output, or `-o`).
    ImportUrdf {
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
    },
    /// Print the syntax tree of a file (for debugging the parser).
    Parse { file: PathBuf },
    /// Run the regression cases of test manifests (`lsdtest.toml`): simulate each program,
    /// compare its outputs with a reference within per-variable tolerances, make its checks.
    /// Exit code 0 when every case passes, 1 when one fails, 2 for a manifest that cannot be
    /// read.
    Test(TestArgs),
    /// Format LSD files in place (`docs/formatting.md`); directories are searched for `.lsd`
    /// files. Only whitespace changes: every token and comment is kept.
    Fmt {
        #[arg(required = true)]
        paths: Vec<PathBuf>,
        /// Change nothing; list the files that are not formatted and fail if there are any.
        #[arg(long)]
        check: bool,
    },
    /// Run the language server on standard input and output (`docs/editors.md`).
    Lsp,
}

#[derive(clap::Args)]
struct TestArgs {
    /// Manifests, or folders searched for `lsdtest.toml` files (default: the current folder).
    paths: Vec<PathBuf>,
    /// Cases run at once (default: the number of processors).
    #[arg(short = 'j', long = "jobs", value_parser = clap::value_parser!(u16).range(1..))]
    jobs: Option<u16>,
    /// Only the cases whose name contains this text.
    #[arg(long)]
    case: Option<String>,
    #[arg(long, value_enum, default_value = "text")]
    format: Format,
    /// Also write the results as JUnit XML to this file.
    #[arg(long, value_name = "FILE")]
    junit: Option<PathBuf>,
    /// Re-record the references from runs, and say what moved.
    #[arg(long, conflicts_with = "calibrate")]
    update: bool,
    /// Run each case at its tolerance (or step) and a finer one, and propose tolerances.
    #[arg(long)]
    calibrate: bool,
    /// Move each number written with a decimal point in the programs by this relative amount,
    /// up or down as `--seed` decides: are the tolerances robust to round-off of the geometry?
    #[arg(long, value_name = "RELATIVE", conflicts_with_all = ["calibrate", "update"])]
    perturb: Option<f64>,
    /// The directions of `--perturb`'s moves (a different seed, other directions).
    #[arg(long, default_value_t = 1, requires = "perturb")]
    seed: u64,
}

fn main() -> ExitCode {
    let arguments: Vec<String> = std::env::args_os()
        .map(|a| a.to_string_lossy().into_owned())
        .collect();
    JSON_ASKED.store(asks_for_json(&arguments), Ordering::Relaxed);
    let cli = match Cli::try_parse_from(&arguments) {
        Ok(cli) => cli,
        Err(error) => return rejected_arguments(error),
    };
    QUIET.store(cli.quiet, std::sync::atomic::Ordering::Relaxed);
    match cli.command {
        Command::Check {
            files,
            libraries,
            format,
        } => check(&files, &libraries.options(), format),
        Command::Tree {
            file,
            libraries,
            format,
        } => tree(&file, &libraries.options(), format),
        Command::Assemble {
            file,
            libraries,
            format,
        } => assemble(&file, &libraries.options(), format),
        Command::Compile {
            file,
            libraries,
            emit,
            format,
            out: output,
        } => compile(&file, &libraries.options(), emit, format, output.as_deref()),
        Command::Simulate(args) => simulate(&args),
        Command::Precision(args) => precision(&args),
        Command::Drag(args) => cli::drag::drag(&args),
        Command::View(args) => cli::view::view(&args),
        Command::Statics {
            file,
            libraries,
            actuated,
            sets,
            format,
        } => statics(&file, &libraries.options(), &actuated, &sets, format),
        Command::Eval {
            file,
            libraries,
            states,
            sets,
        } => eval(&file, &libraries.options(), &states, &sets),
        Command::ExportUrdf {
            file,
            libraries,
            sets,
            out: output,
            name,
        } => export_urdf(
            &file,
            &libraries.options(),
            &sets,
            output.as_deref(),
            name.as_deref(),
        ),
        Command::ImportUrdf {
            file,
            floating_base,
            no_gravity,
            out: output,
        } => {
            let options = lsdc::load::urdf::ImportOptions {
                floating_base,
                gravity: !no_gravity,
            };
            import_urdf(&file, &options, output.as_deref())
        }
        Command::Parse { file } => parse(&file),
        Command::Test(args) => test(&args),
        Command::Fmt { paths, check } => format_files(&paths, check),
        Command::Lsp => match lsdc::ide::server::run_stdio() {
            Ok(()) => ExitCode::SUCCESS,
            Err(error) => {
                eprintln!("error: the language server stopped: {error}");
                ExitCode::from(1)
            }
        },
    }
}

/// Writes to standard output. A closed pipe (`lsdc tree f.lsd | head`) is not an error worth a
/// message: the reader has what it wanted.
fn out(text: &str) {
    let _ = std::io::stdout().lock().write_all(text.as_bytes());
}

fn json(value: &impl serde::Serialize) -> String {
    serde_json::to_string_pretty(value).unwrap_or_default() + "\n"
}

/// A usage error: the message on standard error, exit code 2; where JSON is asked for, also
/// `{"ok": false, "usage_error": MESSAGE}` on standard output.
fn usage_error(message: &str) -> ExitCode {
    if JSON_ASKED.load(Ordering::Relaxed) {
        out(&json(&usage_error_json(message)));
    }
    usage_error_after_results(message)
}

/// A usage error found after the results were printed: on standard error only, so that standard
/// output keeps one JSON document.
fn usage_error_after_results(message: &str) -> ExitCode {
    eprintln!("error: {message}");
    ExitCode::from(2)
}

/// Arguments clap rejects: its message and usage on standard error (help and version are
/// printed as clap prints them), and in JSON where JSON is asked for.
fn rejected_arguments(error: clap::Error) -> ExitCode {
    use clap::error::ErrorKind;
    if matches!(
        error.kind(),
        ErrorKind::DisplayHelp | ErrorKind::DisplayVersion
    ) {
        error.exit();
    }
    if JSON_ASKED.load(Ordering::Relaxed) {
        let text = error.render().to_string();
        let message = text.split("\n\n").next().unwrap_or(&text);
        let message = message.strip_prefix("error: ").unwrap_or(message);
        out(&json(&usage_error_json(message.trim_end())));
    }
    let _ = error.print();
    ExitCode::from(2)
}

fn usage_error_json(message: &str) -> serde_json::Value {
    serde_json::json!({ "ok": false, "usage_error": message })
}

fn check(files: &[PathBuf], options: &LoadOptions, format: Format) -> ExitCode {
    let mut all_ok = true;
    let mut unreadable = false;
    let mut reports = Vec::new();
    for (i, file) in files.iter().enumerate() {
        let compilation = match driver::compile_files_lean(std::slice::from_ref(file), options) {
            Ok(c) => c,
            // In JSON every file has its entry; in text the first unreadable file stops.
            Err(error) if format == Format::Json => {
                let mut entry = usage_error_json(&error.to_string());
                entry["file"] = file.display().to_string().into();
                reports.push(entry);
                eprintln!("error: {error}");
                (all_ok, unreadable) = (false, true);
                continue;
            }
            Err(error) => return usage_error(&error.to_string()),
        };
        all_ok &= !compilation.has_errors();
        match format {
            Format::Text => print_text_report(file, &compilation),
            Format::Json => reports.push(json_report(file, &compilation)),
        }
        if i + 1 == files.len() {
            // The process ends next: the system takes back its memory at once, whereas freeing
            // the syntax tree and the mechanism node by node is about a tenth of the command's
            // time on a large program. Earlier files are dropped, so that the peak is one file's.
            std::mem::forget(compilation);
        }
    }
    if format == Format::Json {
        let value = serde_json::json!({ "ok": all_ok, "files": reports });
        out(&json(&value));
    }
    if unreadable {
        ExitCode::from(2)
    } else if all_ok {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    }
}

fn print_text_report(file: &std::path::Path, compilation: &Compilation) {
    let diagnostics = printed(&compilation.diagnostics);
    let rendered = render::to_text(&compilation.workspace.sources, &diagnostics);
    eprint!("{rendered}");
    match &compilation.mechanism {
        Some(mechanism) => out(&text::summary(file, &mechanism.summary())),
        None => {
            let errors = compilation
                .diagnostics
                .iter()
                .filter(|d| d.is_error())
                .count();
            eprintln!(
                "{}: {errors} error{}",
                file.display(),
                if errors == 1 { "" } else { "s" }
            );
        }
    }
}

fn json_report(file: &std::path::Path, compilation: &Compilation) -> serde_json::Value {
    serde_json::json!({
        "file": file.display().to_string(),
        "ok": !compilation.has_errors(),
        "diagnostics": render::to_json_value(&compilation.workspace.sources, &compilation.diagnostics),
        "summary": compilation.mechanism.as_ref().map(|m| m.summary()),
    })
}

/// Compiles one file, printing its diagnostics; the mechanism if it has no errors.
fn compile_one(
    file: &std::path::Path,
    options: &LoadOptions,
    format: Format,
) -> Result<Compilation, ExitCode> {
    let compilation = driver::compile_files_lean(&[file.to_path_buf()], options)
        .map_err(|error| usage_error(&error.to_string()))?;
    if compilation.has_errors() || (format == Format::Text && !compilation.diagnostics.is_empty()) {
        report_diagnostics(&compilation, &compilation.diagnostics, format);
    }
    if compilation.has_errors() {
        return Err(ExitCode::from(1));
    }
    Ok(compilation)
}

fn report_diagnostics(
    compilation: &Compilation,
    diagnostics: &[lsdc::diag::Diagnostic],
    format: Format,
) {
    let mut diagnostics = diagnostics.to_vec();
    for d in &mut diagnostics {
        compilation.workspace.add_import_context(d);
    }
    match format {
        Format::Text => eprint!(
            "{}",
            render::to_text(&compilation.workspace.sources, &printed(&diagnostics))
        ),
        Format::Json => {
            let value = serde_json::json!({ "ok": false, "diagnostics": render::to_json_value(&compilation.workspace.sources, &diagnostics) });
            out(&json(&value));
        }
    }
}

/// Compiles a file and prints what `analyse` makes of its mechanism: as text with `text`, or as
/// JSON.
fn report<R: serde::Serialize>(
    file: &std::path::Path,
    options: &LoadOptions,
    format: Format,
    analyse: impl Fn(&Mechanism) -> Result<Warned<R>, Vec<Diagnostic>>,
    text: impl Fn(&R) -> String,
) -> ExitCode {
    match analysed(file, options, format, analyse) {
        Ok(result) => {
            match format {
                Format::Text => out(&text(&result)),
                Format::Json => out(&json(&result)),
            }
            ExitCode::SUCCESS
        }
        Err(code) => code,
    }
}

/// A command's result and the warnings found on the way to it.
type Warned<R> = (R, Vec<Diagnostic>);

/// Compiles a file and returns what `analyse` makes of its mechanism (its warnings printed), or
/// the exit code once the diagnostics are printed.
fn analysed<R>(
    file: &std::path::Path,
    options: &LoadOptions,
    format: Format,
    analyse: impl Fn(&Mechanism) -> Result<Warned<R>, Vec<Diagnostic>>,
) -> Result<R, ExitCode> {
    let compilation = compile_one(file, options, format)?;
    let Some(mechanism) = &compilation.mechanism else {
        return Err(ExitCode::from(1));
    };
    match analyse(mechanism) {
        Ok((result, warnings)) => {
            if !warnings.is_empty() {
                report_diagnostics(&compilation, &warnings, format);
            }
            Ok(result)
        }
        Err(diagnostics) => {
            report_diagnostics(&compilation, &diagnostics, format);
            Err(ExitCode::from(1))
        }
    }
}

fn tree(file: &std::path::Path, options: &LoadOptions, format: Format) -> ExitCode {
    let analyse = |mechanism: &Mechanism| analysis::tree(mechanism).map(|r| (r, Vec::new()));
    report(file, options, format, analyse, text::tree)
}

fn assemble(file: &std::path::Path, options: &LoadOptions, format: Format) -> ExitCode {
    let analyse = |mechanism: &Mechanism| {
        let topology = lsdc::topology::build(mechanism)?;
        analysis::assembled_model(mechanism, topology, &Default::default())
            .map(|(_, report, warnings)| (report, warnings))
    };
    report(file, options, format, analyse, text::assembly)
}

fn compile(
    file: &std::path::Path,
    options: &LoadOptions,
    emit: Emit,
    format: Option<EquationsFormat>,
    output: Option<&std::path::Path>,
) -> ExitCode {
    if format.is_some() && emit != Emit::Equations {
        return usage_error("`--format` applies to `--emit equations` only");
    }
    let source = file.display().to_string();
    let analyse = |mechanism: &Mechanism| {
        let topology = lsdc::topology::build(mechanism)?;
        if emit == Emit::Notation {
            return Ok((
                lsdc::topology::notation::notation(mechanism, &topology),
                Vec::new(),
            ));
        }
        let equations = lsdc::symbolic::generate(mechanism, &topology)?;
        use lsdc::symbolic::emit;
        let text = match (emit, format.unwrap_or(EquationsFormat::Text)) {
            (Emit::Rust, _) => emit::rust(&equations, &source),
            (Emit::C, _) => emit::c(&equations, &source),
            (_, EquationsFormat::Text) => emit::text(&equations, &source),
            (_, EquationsFormat::Latex) => emit::latex(&equations, &source),
            (_, EquationsFormat::Sympy) => emit::sympy(&equations, &source),
            (_, EquationsFormat::Json) => emit::json(&equations, &source),
        };
        Ok((text, Vec::new()))
    };
    let text = match analysed(file, options, Format::Text, analyse) {
        Ok(text) => text,
        Err(code) => return code,
    };
    write_output(output, &text)
}

/// Writes a command's result to `output`, or to standard output without one.
fn write_output(output: Option<&std::path::Path>, text: &str) -> ExitCode {
    match output {
        Some(path) => match std::fs::write(path, text) {
            Ok(()) => ExitCode::SUCCESS,
            Err(e) => usage_error(&format!("cannot write `{}`: {e}", path.display())),
        },
        None => {
            out(text);
            ExitCode::SUCCESS
        }
    }
}

fn parse_sets(sets: &[String]) -> Result<Vec<lsdc::prepare::Override>, ExitCode> {
    sets.iter()
        .map(|s| s.parse())
        .collect::<Result<_, lsdc::kinematics::unknowns::OverrideError>>()
        .map_err(|error| usage_error(&error.to_string()))
}

fn simulate(args: &SimulateArgs) -> ExitCode {
    use lsdc::prepare::{prepare, Settings};
    let overrides = match parse_sets(&args.sets) {
        Ok(o) => o,
        Err(code) => return code,
    };
    let compilation = match compile_one(&args.file, &args.libraries.options(), args.report) {
        Ok(c) => c,
        Err(code) => return code,
    };
    let Some(mechanism) = &compilation.mechanism else {
        return ExitCode::from(1);
    };
    let mut prepared = match prepare(mechanism, &overrides, &Settings::default()) {
        Ok(p) => p,
        Err(diagnostics) => {
            report_diagnostics(&compilation, &diagnostics, args.report);
            return ExitCode::from(1);
        }
    };
    if let Err(error) = prepared.settings.apply(&settings_changes(args)) {
        return usage_error(&error.to_string());
    }
    let frames = match resolve_frames(mechanism, &prepared, &args.output_frames) {
        Ok(frames) => frames,
        Err(message) => return usage_error(&message),
    };
    if args.compiled {
        let native = lsdc::simulate::compiled::attach_with_warnings(&mut prepared, mechanism);
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
            let program = compilation.diagnostics.iter().filter(|d| !d.is_error());
            warnings.extend(program.chain(&prepared.warnings).cloned());
        }
        Format::Text if !prepared.warnings.is_empty() => {
            report_diagnostics(&compilation, &prepared.warnings, Format::Text);
        }
        Format::Text => {}
    }
    let (simulation, written) = run_and_write(args, &prepared, &frames, samples_out);
    let plotted = match &args.plot {
        Some(path) => lsdc::output::plot::plot(&simulation, path)
            .map_err(|error| format!("cannot draw `{}`: {error}", path.display())),
        None => Ok(()),
    };
    print_run_report(&compilation, &simulation.report, args.report, warnings);
    if let Err(message) = written {
        return usage_error_after_results(&message);
    }
    // A plot that cannot be drawn after the run (a run without outputs) does not change what
    // the run's exit code says.
    if let Err(message) = plotted {
        eprintln!("error: {message}");
    }
    let report = &simulation.report;
    match (report.interrupted, &report.failure) {
        (Some(stop), _) => ExitCode::from((128 + stop.signal).min(255) as u8),
        (None, Some(_)) => ExitCode::from(1),
        (None, None) => ExitCode::SUCCESS,
    }
}

/// The command line's changes to the program's `simulate` declaration.
fn settings_changes(args: &SimulateArgs) -> lsdc::prepare::settings::SettingsChanges {
    use lsdc::dynamics::loops::Stabilisation;
    lsdc::prepare::settings::SettingsChanges {
        integrator: args.integrator.map(IntegratorArg::integrator),
        duration: args.duration,
        output: args.output_interval,
        tolerance: args.tolerance,
        step: args.step,
        stabilisation: Some(match args.stabilisation {
            StabilisationArg::Projection => Stabilisation::Projection,
            StabilisationArg::Baumgarte => Stabilisation::Baumgarte(args.baumgarte_rate),
            StabilisationArg::None => Stabilisation::None,
        }),
        reactions: args.reactions,
        max_steps: Some(args.max_steps),
        no_stiffness_check: args.no_stiffness_check,
    }
}

/// The frames `--output-frame` names, resolved on the mechanism.
fn resolve_frames(
    mechanism: &Mechanism,
    prepared: &lsdc::prepare::Prepared,
    names: &[String],
) -> Result<Vec<lsdc::kinematics::frames::FramePoint>, String> {
    names
        .iter()
        .map(|name| lsdc::kinematics::frames::resolve(mechanism, &prepared.kinematics, name))
        .collect()
}

/// The file the samples go to (created, or emptied, now), or standard output.
fn open_samples_output(path: Option<&std::path::Path>) -> Result<Box<dyn Write>, ExitCode> {
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

/// Runs the simulation, streaming CSV rows to `out` as they come (JSON is one document,
/// written at the end), until its end, a failure, or SIGINT/SIGTERM; then ends the file.
fn run_and_write(
    args: &SimulateArgs,
    prepared: &lsdc::prepare::Prepared,
    frames: &[lsdc::kinematics::frames::FramePoint],
    out: Box<dyn Write>,
) -> (lsdc::simulate::run::Simulation, Result<(), String>) {
    use lsdc::kinematics::frames::{column_names, states};
    use lsdc::simulate::run::{run_with, RunOptions, Sample};
    let target = args
        .out
        .as_ref()
        .map_or("standard output".to_string(), |p| {
            format!("`{}`", p.display())
        });
    let options = RunOptions {
        keep_samples: args.plot.is_some() || args.format == SampleFormat::Json,
        interrupt: interrupt_on_signals(),
    };
    let mut csv = (args.format == SampleFormat::Csv).then(|| {
        let names = &prepared.coordinate_names;
        let reactions = lsdc::simulate::run::reaction_names_of(prepared);
        let extra: Vec<String> = (prepared.outputs.names.iter().cloned())
            .chain(column_names(frames))
            .collect();
        lsdc::output::csv::CsvWriter::new(out, names, &reactions, &extra)
    });
    let frame_values = |sample: &Sample| -> Vec<f64> {
        let found = states(
            &prepared.kinematics,
            frames,
            &sample.coordinates,
            &sample.rates,
        );
        // The run evaluated these chains at every step: they cannot fail here.
        found.map_or_else(
            |_| vec![f64::NAN; 13 * frames.len()],
            |states| states.iter().flat_map(|s| s.values()).collect(),
        )
    };
    let bar = progress_bar(prepared.settings.duration);
    let mut sink = |sample: &Sample| {
        if let Some(bar) = &bar {
            bar.set_position((sample.time * 1000.0) as u64);
        }
        if let Some(csv) = &mut csv {
            csv.write_sample(sample, &frame_values(sample));
        }
    };
    let simulation = run_with(prepared, &options, &mut sink);
    if let Some(bar) = bar {
        bar.finish_and_clear();
    }
    let written = match csv {
        Some(csv) => csv.finish(&simulation.report),
        None => write_json_samples(&simulation, prepared, frames, args.out.as_deref()),
    };
    let written = written.map_err(|e| format!("cannot write {target}: {e}"));
    (simulation, written)
}

/// The simulation as JSON; with `--output-frame`, each sample also has `frames`: each frame's
/// state by name.
fn write_json_samples(
    simulation: &lsdc::simulate::run::Simulation,
    prepared: &lsdc::prepare::Prepared,
    frames: &[lsdc::kinematics::frames::FramePoint],
    path: Option<&std::path::Path>,
) -> std::io::Result<()> {
    let mut value = serde_json::to_value(simulation).unwrap_or_default();
    if !frames.is_empty() {
        let samples = value["samples"].as_array_mut().into_iter().flatten();
        for (json_sample, sample) in samples.zip(&simulation.samples) {
            let states = lsdc::kinematics::frames::states(
                &prepared.kinematics,
                frames,
                &sample.coordinates,
                &sample.rates,
            );
            let by_name: serde_json::Map<String, serde_json::Value> = frames
                .iter()
                .zip(states.unwrap_or_default())
                .map(|(f, s)| (f.name.clone(), serde_json::json!(s)))
                .collect();
            json_sample["frames"] = serde_json::Value::Object(by_name);
        }
    }
    match path {
        Some(path) => std::fs::write(path, json(&value)),
        None => {
            out(&json(&value));
            Ok(())
        }
    }
}

/// A flag that SIGINT and SIGTERM set to their number, for the run to stop between two steps
/// and its output and report to be finished; a second signal ends the process at once. `None`
/// where the handlers cannot be installed (the signals then end the process as usual).
fn interrupt_on_signals() -> Option<lsdc::integrate::Interrupt> {
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
    Some(lsdc::integrate::Interrupt(requested))
}

/// The warnings the run found and its report, on standard error (in JSON, the warnings inside
/// the report: standard output may carry the samples).
fn print_run_report(
    compilation: &Compilation,
    report: &lsdc::simulate::run::Report,
    format: Format,
    earlier_warnings: Vec<Diagnostic>,
) {
    let run_warnings = [
        lsdc::simulate::run::stiffness_warning(report),
        lsdc::simulate::run::step_error_warning(report),
        lsdc::simulate::run::passage_output_warning(report),
    ];
    let warnings: Vec<_> = earlier_warnings
        .into_iter()
        .chain(run_warnings.into_iter().flatten())
        .collect();
    match format {
        Format::Text => {
            report_diagnostics(compilation, &warnings, Format::Text);
            eprint!("{}", text::run_report(report));
        }
        Format::Json => {
            let mut value = serde_json::to_value(report).unwrap_or_default();
            if !warnings.is_empty() {
                let sources = &compilation.workspace.sources;
                value["warnings"] = render::to_json_value(sources, &warnings);
            }
            eprintln!("{}", json(&value));
        }
    }
}

/// The methods `lsdc precision` measures: each adaptive integrator at each tolerance, each
/// fixed-step one at each step.
fn precision_methods(args: &PrecisionArgs) -> Vec<lsdc::studies::precision::Method> {
    use lsdc::studies::precision::{Method, Setting};
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

/// The options of `lsdc precision` that must be positive numbers, and a usable plot name.
fn check_precision_args(args: &PrecisionArgs) -> Result<(), String> {
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

/// The reference of `lsdc precision`: the user's CSV, or a run at a much tighter tolerance.
fn precision_reference(
    args: &PrecisionArgs,
    prepared: &mut lsdc::prepare::Prepared,
) -> Result<lsdc::studies::precision::Reference, String> {
    use lsdc::studies::precision::{computed_reference, Reference};
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

fn precision(args: &PrecisionArgs) -> ExitCode {
    use lsdc::prepare::settings::SettingsChanges;
    if let Err(message) = check_precision_args(args) {
        return usage_error(&message);
    }
    let options = args.libraries.options();
    let mut prepared = match prepare_file(&args.file, &options, &args.sets, args.format) {
        Ok(p) => p,
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
    let table = precision_reference(args, &mut prepared).and_then(|reference| {
        let methods = precision_methods(args);
        lsdc::studies::precision::table(
            &mut prepared,
            &methods,
            reference,
            args.repeats,
            args.accuracy,
        )
        .map_err(|error| error.to_string())
    });
    let table = match table {
        Ok(table) => table,
        Err(message) => {
            eprintln!("error: {message}");
            return ExitCode::from(1);
        }
    };
    let text = match args.format {
        Format::Text => text::precision(&table),
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

fn statics(
    file: &std::path::Path,
    options: &LoadOptions,
    actuated: &[String],
    sets: &[String],
    format: Format,
) -> ExitCode {
    let prepared = match prepare_file(file, options, sets, format) {
        Ok(p) => p,
        Err(code) => return code,
    };
    let holding = match lsdc::studies::statics::holding_efforts(&prepared, actuated) {
        Ok(h) => h,
        Err(error) => return usage_error(&error.to_string()),
    };
    match format {
        Format::Text => out(&text::holding(&holding)),
        Format::Json => out(&json(&holding)),
    }
    ExitCode::SUCCESS
}

fn eval(
    file: &std::path::Path,
    options: &LoadOptions,
    states: &std::path::Path,
    sets: &[String],
) -> ExitCode {
    use lsdc::studies::batch::{evaluate_states, parse_states};
    let inputs = match std::fs::read_to_string(states)
        .map_err(|e| e.to_string())
        .and_then(|text| parse_states(&text).map_err(|e| e.to_string()))
    {
        Ok(inputs) => inputs,
        Err(message) => {
            return usage_error(&format!(
                "cannot read states from `{}`: {message}",
                states.display()
            ))
        }
    };
    let prepared = match prepare_file(file, options, sets, Format::Text) {
        Ok(p) => p,
        Err(code) => return code,
    };
    match evaluate_states(&prepared, &inputs) {
        Ok(evaluation) => {
            for (index, state) in evaluation
                .states
                .iter()
                .enumerate()
                .filter(|(_, s)| !s.errors.is_empty())
            {
                let errors: Vec<String> = state
                    .errors
                    .iter()
                    .map(|(quantity, message)| format!("{quantity}: {message}"))
                    .collect();
                warn(&format!("state {index}: {}", errors.join("; ")));
            }
            out(&json(&evaluation));
            ExitCode::SUCCESS
        }
        Err(error) => {
            eprintln!("error: {error}");
            ExitCode::from(1)
        }
    }
}

/// Prepares a file's mechanism as `simulate` does (values from `given` and `--set`), printing
/// the diagnostics when it cannot.
fn prepare_file(
    file: &std::path::Path,
    options: &LoadOptions,
    sets: &[String],
    format: Format,
) -> Result<lsdc::prepare::Prepared, ExitCode> {
    use lsdc::prepare::{prepare, Settings};
    let overrides = parse_sets(sets)?;
    let compilation = compile_one(file, options, format)?;
    let Some(mechanism) = &compilation.mechanism else {
        return Err(ExitCode::from(1));
    };
    match prepare(mechanism, &overrides, &Settings::default()) {
        Ok(prepared) => {
            if !prepared.warnings.is_empty() {
                report_diagnostics(&compilation, &prepared.warnings, format);
            }
            Ok(prepared)
        }
        Err(diagnostics) => {
            report_diagnostics(&compilation, &diagnostics, format);
            Err(ExitCode::from(1))
        }
    }
}

fn export_urdf(
    file: &std::path::Path,
    options: &LoadOptions,
    sets: &[String],
    output: Option<&std::path::Path>,
    name: Option<&str>,
) -> ExitCode {
    let prepared = match prepare_file(file, options, sets, Format::Text) {
        Ok(p) => p,
        Err(code) => return code,
    };
    let stem = file.file_stem().map(|s| s.to_string_lossy().into_owned());
    let name = name
        .map(str::to_string)
        .or(stem)
        .unwrap_or_else(|| "robot".to_string());
    let urdf = match lsdc::output::urdf::export_urdf(&prepared.model, &name) {
        Ok(text) => text,
        Err(e) => {
            eprintln!("error: {}", e.message(&file.display().to_string()));
            return ExitCode::from(1);
        }
    };
    if let Some(dropped) = lsdc::output::urdf::dropped_efforts(&prepared.model) {
        warn(&dropped);
    }
    write_output(output, &urdf)
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

/// Prints the LSD program imported from a URDF file, its warnings to standard error.
fn import_urdf(
    file: &std::path::Path,
    options: &lsdc::load::urdf::ImportOptions,
    output: Option<&std::path::Path>,
) -> ExitCode {
    let text = match lsdc::load::read_source(file) {
        Ok(t) => t,
        Err(e) => return usage_error(&format!("cannot read `{}`: {e}", file.display())),
    };
    let mut sources = lsdc::source::SourceMap::new();
    let name = file.display().to_string();
    let id = sources.add(name.clone(), text);
    let imported =
        match lsdc::load::urdf::import_urdf_at(id, &name, &sources.file(id).text, options) {
            Ok(imported) => imported,
            Err(error) => {
                eprint!("{}", render::to_text(&sources, &[error]));
                return ExitCode::from(1);
            }
        };
    eprint!(
        "{}",
        render::to_text(&sources, &printed(&imported.warnings))
    );
    write_output(output, &imported.text)
}

fn parse(file: &std::path::Path) -> ExitCode {
    let text = match lsdc::load::read_source(file) {
        Ok(t) => t,
        Err(e) => return usage_error(&format!("cannot read `{}`: {e}", file.display())),
    };
    let mut sources = lsdc::source::SourceMap::new();
    let id = sources.add(file.display().to_string(), text);
    let (program, diagnostics) = lsdc::syntax::parser::parse(id, &sources.file(id).text);
    out(&lsdc::syntax::debug_tree::pretty(&format!("{program:?}")));
    out("\n");
    eprint!("{}", render::to_text(&sources, &diagnostics));
    if diagnostics.is_empty() {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    }
}

fn test(args: &TestArgs) -> ExitCode {
    use lsdc::testing::{self, calibrate, record, report};
    let mut cases = match test_cases(args) {
        Ok(cases) => cases,
        Err(message) => return usage_error(&message),
    };
    if args.calibrate || args.update {
        // Only the cases compared with a reference have one to record or tolerances to propose.
        cases.retain(|c| c.reference.is_some());
    }
    if let Some(relative) = args.perturb {
        let numbers = lsdc::elab::Perturbation {
            relative,
            seed: args.seed,
        };
        cases.iter_mut().for_each(|c| c.numbers = Some(numbers));
    }
    let jobs = (args.jobs.map(usize::from))
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, usize::from));
    let start = std::time::Instant::now();
    let outcomes = match (args.calibrate, args.update) {
        (true, _) => testing::for_each_case(&cases, jobs, |c| named(c, calibrate::calibrate(c)))
            .map(|proposals| print_each(&proposals, args.format, calibrate::as_manifest)),
        (_, true) => testing::for_each_case(&cases, jobs, |c| named(c, record::record(c)))
            .map(|recorded| print_each(&recorded, args.format, report::recorded_text)),
        _ => testing::run_all(&cases, jobs).map(|outcomes| {
            let summary = report::Summary::new(&outcomes, jobs, start.elapsed().as_secs_f64());
            print_summary(&summary, args)
        }),
    };
    outcomes.unwrap_or_else(|message| usage_error(&message))
}

/// The cases of the manifests under the paths given (the current folder by default), those
/// named by `--case` only.
fn test_cases(args: &TestArgs) -> Result<Vec<lsdc::testing::Case>, String> {
    let paths = match args.paths.is_empty() {
        true => vec![PathBuf::from(".")],
        false => args.paths.clone(),
    };
    let mut cases = lsdc::testing::load(&paths).map_err(|error| error.to_string())?;
    if let Some(text) = &args.case {
        cases.retain(|c| c.name.contains(text.as_str()));
    }
    match cases.is_empty() {
        true => Err("no test case found (manifests are named `lsdtest.toml`)".into()),
        false => Ok(cases),
    }
}

/// Prints the results (text or JSON), writes the JUnit file; exit code 0 if every case passed.
fn print_summary(summary: &lsdc::testing::report::Summary, args: &TestArgs) -> ExitCode {
    use lsdc::testing::report;
    match args.format {
        Format::Text => out(&report::text(summary)),
        Format::Json => out(&json(summary)),
    }
    if let Some(path) = &args.junit {
        if let Err(error) = std::fs::write(path, report::junit(summary)) {
            return usage_error_after_results(&format!(
                "cannot write `{}`: {error}",
                path.display()
            ));
        }
    }
    match summary.all_passed() {
        true => ExitCode::SUCCESS,
        false => ExitCode::from(1),
    }
}

/// An error of a case, with the case's name.
fn named<T>(case: &lsdc::testing::Case, result: Result<T, String>) -> Result<T, String> {
    result.map_err(|error| format!("{}: {error}", case.name))
}

/// Prints what `--calibrate` or `--update` made of each case (text or JSON), the cases it could
/// not be done for on standard error; exit code 1 if there was one.
fn print_each<T: serde::Serialize>(
    results: &[Result<T, String>],
    format: Format,
    text: impl Fn(&T) -> String,
) -> ExitCode {
    let done: Vec<&T> = results.iter().filter_map(|r| r.as_ref().ok()).collect();
    match format {
        Format::Text => done.iter().for_each(|d| out(&text(d))),
        Format::Json => out(&json(&done)),
    }
    let failures: Vec<&String> = results.iter().filter_map(|r| r.as_ref().err()).collect();
    failures.iter().for_each(|f| eprintln!("error: {f}"));
    match failures.is_empty() {
        true => ExitCode::SUCCESS,
        false => ExitCode::from(1),
    }
}

/// `lsdc fmt`: formats each file in place, or with `check` lists those that would change.
/// Exit status 1 when a file cannot be read or parsed, or (with `check`) is not formatted.
fn format_files(paths: &[PathBuf], check: bool) -> ExitCode {
    let files = match lsdc::ide::format::lsd_files(paths) {
        Ok(files) => files,
        Err(error) => return usage_error(&error),
    };
    let mut failed = false;
    for file in files {
        let text = match std::fs::read_to_string(&file) {
            Ok(text) => text,
            Err(e) => {
                eprintln!("error: cannot read `{}`: {e}", file.display());
                failed = true;
                continue;
            }
        };
        let mut sources = lsdc::source::SourceMap::new();
        let id = sources.add(file.display().to_string(), text);
        let text = &sources.file(id).text;
        let formatted = match lsdc::ide::format::format(id, text) {
            Ok(formatted) => formatted,
            Err(diagnostics) => {
                eprint!("{}", render::to_text(&sources, &diagnostics));
                failed = true;
                continue;
            }
        };
        if formatted == *text {
            continue;
        }
        if check {
            println!("{}: not formatted", file.display());
            failed = true;
        } else if let Err(e) = std::fs::write(&file, formatted) {
            eprintln!("error: cannot write `{}`: {e}", file.display());
            failed = true;
        }
    }
    if failed {
        ExitCode::from(1)
    } else {
        ExitCode::SUCCESS
    }
}
