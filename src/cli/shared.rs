//! What the commands share: `--quiet`, usage errors (in JSON where JSON is asked for), the
//! library directories, loading and preparing a program with its diagnostics printed, writing
//! a result.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Mutex;

use clap::ValueEnum;

use lsdc::api::{Error, Override, Prepared, Program, SettingsChanges};
use lsdc::diag::{render, Diagnostic};
use lsdc::load::LoadOptions;

/// Set by `--quiet`: warnings are not printed.
static QUIET: AtomicBool = AtomicBool::new(false);

/// Set when the command line asks for JSON (`--format json`, `--report json`): usage errors are
/// then also printed as JSON on standard output, where the results would be.
static JSON_ASKED: AtomicBool = AtomicBool::new(false);

/// Reads `--quiet` and whether the arguments ask for JSON, for the rest of the process.
pub fn set_modes(quiet: bool, json_asked: bool) {
    QUIET.store(quiet, Ordering::Relaxed);
    JSON_ASKED.store(json_asked, Ordering::Relaxed);
}

/// Whether `--quiet` was given.
pub fn quiet() -> bool {
    QUIET.load(Ordering::Relaxed)
}

/// Whether the arguments ask for JSON: `--format` or `--report` followed by `json`, or
/// `--format=json`, `--report=json`. Read from the raw arguments, so that the arguments clap
/// rejects are also reported as JSON.
pub fn asks_for_json(arguments: &[String]) -> bool {
    let option = |a: &str| a == "--format" || a == "--report";
    arguments
        .windows(2)
        .any(|w| option(&w[0]) && w[1] == "json")
        || (arguments.iter()).any(|a| a == "--format=json" || a == "--report=json")
}

/// The diagnostics to print as text: without the warnings under `--quiet`.
pub fn printed(diagnostics: &[Diagnostic]) -> Vec<Diagnostic> {
    let keep = |d: &&Diagnostic| d.is_error() || !quiet();
    diagnostics.iter().filter(keep).cloned().collect()
}

/// A warning of the command line itself, on standard error (not under `--quiet`).
pub fn warn(message: &str) {
    if !quiet() {
        err(&format!("warning: {message}\n"));
    }
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Format {
    Text,
    Json,
}

/// The formats of samples (of a run, of a drag).
#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum SampleFormat {
    Csv,
    Json,
}

#[derive(clap::Args)]
pub struct LibraryArgs {
    /// Add a directory to the library search path (searched after the importing file's
    /// directory, before LSD_PATH and the standard library).
    #[arg(short = 'L', value_name = "DIR")]
    library_dirs: Vec<PathBuf>,
    /// Study the program's scene NAME (`scene NAME = ... end`): its settings, values, drives,
    /// locks, efforts and outputs, in the smallest model that serves it. Default: the first
    /// scene the program declares.
    #[arg(long, value_name = "NAME")]
    scene: Option<String>,
}

impl LibraryArgs {
    /// `--scene NAME`, when given.
    pub fn scene(&self) -> Option<&str> {
        self.scene.as_deref()
    }

    pub fn options(&self) -> LoadOptions {
        LoadOptions {
            library_dirs: self.library_dirs.clone(),
            use_environment: true,
            scene: self.scene.clone(),
        }
    }
}

/// The first write on standard output that failed (a full disk, `> /dev/full`), kept for
/// [`exit_code`] to report once the command is over.
static OUTPUT_FAILURE: Mutex<Option<String>> = Mutex::new(None);

/// Writes to standard output, the one way the commands print their results. A failed write is
/// kept and reported when the command ends ([`exit_code`]); a closed pipe (`lsdc tree f.lsd |
/// head`) is not an error worth a message: the reader has what it wanted.
pub fn out(text: &str) {
    let mut stdout = std::io::stdout().lock();
    let written = (stdout.write_all(text.as_bytes())).and_then(|()| stdout.flush());
    if let Err(error) = written {
        let mut failure = OUTPUT_FAILURE.lock().unwrap_or_else(|e| e.into_inner());
        if error.kind() != std::io::ErrorKind::BrokenPipe && failure.is_none() {
            *failure = Some(error.to_string());
        }
    }
}

/// Writes to standard error, the one way the commands print messages. A write that fails is
/// left unsaid: there is nowhere left to say it, and a panic would replace the command's exit
/// code with 101.
pub fn err(text: &str) {
    let _ = std::io::stderr().lock().write_all(text.as_bytes());
}

/// The command's exit code, unless a write on standard output failed: then the results are
/// lost, which is said on standard error, with exit code 2 (as for an output file that cannot
/// be written).
pub fn exit_code(command_code: ExitCode) -> ExitCode {
    let failure = OUTPUT_FAILURE.lock().unwrap_or_else(|e| e.into_inner());
    match failure.as_deref() {
        Some(error) => {
            err(&format!("error: cannot write standard output: {error}\n"));
            ExitCode::from(2)
        }
        None => command_code,
    }
}

pub fn json(value: &impl serde::Serialize) -> String {
    serde_json::to_string_pretty(value).unwrap_or_default() + "\n"
}

/// A usage error: the message on standard error, exit code 2; where JSON is asked for, also
/// `{"ok": false, "usage_error": MESSAGE}` on standard output.
pub fn usage_error(message: &str) -> ExitCode {
    if JSON_ASKED.load(Ordering::Relaxed) {
        out(&json(&usage_error_json(message)));
    }
    usage_error_after_results(message)
}

/// A usage error found after the results were printed: on standard error only, so that standard
/// output keeps one JSON document.
pub fn usage_error_after_results(message: &str) -> ExitCode {
    err(&format!("error: {message}\n"));
    ExitCode::from(2)
}

/// Arguments clap rejects: its message and usage on standard error (help and version are
/// printed as clap prints them), and in JSON where JSON is asked for.
pub fn rejected_arguments(error: clap::Error) -> ExitCode {
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

pub fn usage_error_json(message: &str) -> serde_json::Value {
    serde_json::json!({ "ok": false, "usage_error": message })
}

/// Loads one file, printing its diagnostics (in text, its warnings too); the program if it has
/// no errors.
pub fn load_program(
    file: &Path,
    options: &LoadOptions,
    format: Format,
) -> Result<Program, ExitCode> {
    let program =
        Program::from_file(file, options).map_err(|error| usage_error(&error.to_string()))?;
    if program.has_errors() || (format == Format::Text && !program.diagnostics().is_empty()) {
        report_diagnostics(&program, program.diagnostics(), format);
    }
    if program.has_errors() {
        return Err(ExitCode::from(1));
    }
    Ok(program)
}

/// Prints diagnostics about `program`, with the imports that brought libraries in: as text on
/// standard error, or as a failed JSON result on standard output.
pub fn report_diagnostics(program: &Program, diagnostics: &[Diagnostic], format: Format) {
    let diagnostics = program.in_context(diagnostics);
    let sources = program.sources();
    match format {
        Format::Text => err(&render::to_text(sources, &printed(&diagnostics))),
        Format::Json => {
            let diagnostics = render::to_json_value(sources, &diagnostics);
            out(&json(
                &serde_json::json!({ "ok": false, "diagnostics": diagnostics }),
            ));
        }
    }
}

/// Loads and prepares a file as `simulate` does (values from `given` and `--set`, the settings'
/// `changes`), printing the diagnostics when it cannot; the preparation's warnings are left to
/// the caller.
pub fn prepare_program(
    file: &Path,
    libraries: &LibraryArgs,
    sets: &[String],
    changes: &SettingsChanges,
    format: Format,
) -> Result<(Program, Prepared), ExitCode> {
    prepare_program_with(file, libraries, sets, format, |program, overrides| {
        program.prepare(overrides, changes)
    })
}

/// As [`prepare_program`] for a run (`Program::prepare_run`: a scene that asks only for
/// kinematics builds no dynamics).
pub fn prepare_run_program(
    file: &Path,
    libraries: &LibraryArgs,
    sets: &[String],
    changes: &SettingsChanges,
    format: Format,
) -> Result<(Program, Prepared), ExitCode> {
    prepare_program_with(file, libraries, sets, format, |program, overrides| {
        program.prepare_run(overrides, changes)
    })
}

fn prepare_program_with(
    file: &Path,
    libraries: &LibraryArgs,
    sets: &[String],
    format: Format,
    prepare: impl FnOnce(&Program, &[Override]) -> Result<Prepared, Error>,
) -> Result<(Program, Prepared), ExitCode> {
    let overrides = parse_sets(sets)?;
    let program = load_program(file, &libraries.options(), format)?;
    match prepare(&program, &overrides) {
        Ok(prepared) => Ok((program, prepared)),
        Err(Error::Program(diagnostics)) => {
            report_diagnostics(&program, &diagnostics, format);
            Err(ExitCode::from(1))
        }
        Err(error) => Err(usage_error(&error.to_string())),
    }
}

/// As [`prepare_program`] with the program's own settings, its warnings printed.
pub fn prepare_file(
    file: &Path,
    libraries: &LibraryArgs,
    sets: &[String],
    format: Format,
) -> Result<(Program, Prepared), ExitCode> {
    let (program, prepared) =
        prepare_program(file, libraries, sets, &SettingsChanges::default(), format)?;
    if !prepared.warnings.is_empty() {
        report_diagnostics(&program, &prepared.warnings, format);
    }
    Ok((program, prepared))
}

/// As [`prepare_file`] for a study of kinematics alone: the model without the dynamics
/// (`Program::prepare_kinematics`).
pub fn prepare_kinematics_file(
    file: &Path,
    libraries: &LibraryArgs,
    sets: &[String],
    format: Format,
) -> Result<(Program, Prepared), ExitCode> {
    let overrides = parse_sets(sets)?;
    let program = load_program(file, &libraries.options(), format)?;
    let prepared = match program.prepare_kinematics(&overrides) {
        Ok(prepared) => prepared,
        Err(Error::Program(diagnostics)) => {
            report_diagnostics(&program, &diagnostics, format);
            return Err(ExitCode::from(1));
        }
        Err(error) => return Err(usage_error(&error.to_string())),
    };
    if !prepared.warnings.is_empty() {
        report_diagnostics(&program, &prepared.warnings, format);
    }
    Ok((program, prepared))
}

/// E0491, reported, when the program imposes motions in time, which `subject` (a command,
/// "`lsdc statics`") does not handle; `help` says what to run instead.
pub fn refuse_imposed_motion(
    program: &Program,
    subject: &str,
    help: &str,
    format: Format,
) -> Result<(), ExitCode> {
    let refused = (program.mechanism().ok())
        .and_then(|m| lsdc::elab::imposed_motion::refused_by(m, subject, help));
    match refused {
        Some(diagnostic) => {
            report_diagnostics(program, &[diagnostic], format);
            Err(ExitCode::from(1))
        }
        None => Ok(()),
    }
}

/// E0498, reported, when the program has sampled states (`sample`), which `subject` (a
/// command, "`lsdc linearize`") does not handle; `help` says what to run instead.
pub fn refuse_sampled(
    program: &Program,
    prepared: &Prepared,
    subject: &str,
    help: &str,
    format: Format,
) -> Result<(), ExitCode> {
    match lsdc::dynamics::sampled::refusal(&prepared.model, subject, help) {
        Some(diagnostic) => {
            report_diagnostics(program, &[diagnostic], format);
            Err(ExitCode::from(1))
        }
        None => Ok(()),
    }
}

/// The values of `--set NAME=VALUE`.
pub fn parse_sets(sets: &[String]) -> Result<Vec<Override>, ExitCode> {
    sets.iter()
        .map(|s| s.parse())
        .collect::<Result<_, lsdc::kinematics::unknowns::OverrideError>>()
        .map_err(|error| usage_error(&error.to_string()))
}

/// Writes a command's result to `output`, or to standard output without one.
pub fn write_output(output: Option<&Path>, text: &str) -> ExitCode {
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

/// A command's result and the warnings found on the way to it.
pub type Warned<R> = (R, Vec<Diagnostic>);

/// Loads a file and returns what `analyse` makes of its mechanism (its warnings printed), or
/// the exit code once the diagnostics are printed.
pub fn analysed<R>(
    file: &Path,
    options: &LoadOptions,
    format: Format,
    analyse: impl Fn(&lsdc::elab::Mechanism) -> Result<Warned<R>, Vec<Diagnostic>>,
) -> Result<R, ExitCode> {
    let program = load_program(file, options, format)?;
    let mechanism = program.mechanism().map_err(|_| ExitCode::from(1))?;
    match analyse(mechanism) {
        Ok((result, warnings)) => {
            if !warnings.is_empty() {
                report_diagnostics(&program, &warnings, format);
            }
            Ok(result)
        }
        Err(diagnostics) => {
            report_diagnostics(&program, &diagnostics, format);
            Err(ExitCode::from(1))
        }
    }
}

/// Loads a file and prints what `analyse` makes of its mechanism: as text with `text`, or as
/// JSON.
pub fn report<R: serde::Serialize>(
    file: &Path,
    options: &LoadOptions,
    format: Format,
    analyse: impl Fn(&lsdc::elab::Mechanism) -> Result<Warned<R>, Vec<Diagnostic>>,
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
