//! The `lsdc` command line: wires the phases together, prints results and diagnostics.
//! Exit codes: 0 clean, 1 errors in the program, 2 usage errors (bad flags, unreadable files).

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand, ValueEnum};

use lsdc::analysis;
use lsdc::diag::{render, Diagnostic};
use lsdc::elab::Mechanism;
use lsdc::driver::{self, Compilation};
use lsdc::load::LoadOptions;
use lsdc::output::text;

#[derive(Parser)]
#[command(name = "lsdc", version, about = "Compiler and simulator for LSD mechanism descriptions")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum Format {
    Text,
    Json,
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum Emit {
    Notation,
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
        LoadOptions { library_dirs: self.library_dirs.clone(), use_environment: true }
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
    /// Compile a program and print what `--emit` asks for.
    Compile {
        file: PathBuf,
        #[command(flatten)]
        libraries: LibraryArgs,
        /// `notation`: the thesis-style notation table (structure, variables, declared and
        /// deduced assignments).
        #[arg(long, value_enum)]
        emit: Emit,
    },
    /// Print the syntax tree of a file (for debugging the parser).
    Parse { file: PathBuf },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match cli.command {
        Command::Check { files, libraries, format } => check(&files, &libraries.options(), format),
        Command::Tree { file, libraries, format } => tree(&file, &libraries.options(), format),
        Command::Assemble { file, libraries, format } => assemble(&file, &libraries.options(), format),
        Command::Compile { file, libraries, emit } => compile(&file, &libraries.options(), emit),
        Command::Parse { file } => parse(&file),
    }
}

/// Writes to standard output. A closed pipe (`lsdc tree f.lsd | head`) is not an error worth a
/// message: the reader has what it wanted.
fn out(text: &str) {
    use std::io::Write;
    let _ = std::io::stdout().lock().write_all(text.as_bytes());
}

fn json(value: &impl serde::Serialize) -> String {
    serde_json::to_string_pretty(value).unwrap_or_default() + "\n"
}

fn usage_error(message: &str) -> ExitCode {
    eprintln!("error: {message}");
    ExitCode::from(2)
}

fn check(files: &[PathBuf], options: &LoadOptions, format: Format) -> ExitCode {
    let mut all_ok = true;
    let mut reports = Vec::new();
    for file in files {
        let compilation = match driver::compile_files(std::slice::from_ref(file), options) {
            Ok(c) => c,
            Err(message) => return usage_error(&message),
        };
        all_ok &= !compilation.has_errors();
        match format {
            Format::Text => print_text_report(file, &compilation),
            Format::Json => reports.push(json_report(file, &compilation)),
        }
    }
    if format == Format::Json {
        let value = serde_json::json!({ "ok": all_ok, "files": reports });
        out(&json(&value));
    }
    if all_ok {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    }
}

fn print_text_report(file: &std::path::Path, compilation: &Compilation) {
    let rendered = render::to_text(&compilation.workspace.sources, &compilation.diagnostics);
    eprint!("{rendered}");
    match &compilation.mechanism {
        Some(mechanism) => out(&text::summary(file, &mechanism.summary())),
        None => {
            let errors = compilation.diagnostics.iter().filter(|d| d.is_error()).count();
            eprintln!("{}: {errors} error{}", file.display(), if errors == 1 { "" } else { "s" });
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
fn compile_one(file: &std::path::Path, options: &LoadOptions, format: Format) -> Result<Compilation, ExitCode> {
    let compilation = driver::compile_files(&[file.to_path_buf()], options).map_err(|m| usage_error(&m))?;
    if compilation.has_errors() || (format == Format::Text && !compilation.diagnostics.is_empty()) {
        report_diagnostics(&compilation, &compilation.diagnostics, format);
    }
    if compilation.has_errors() {
        return Err(ExitCode::from(1));
    }
    Ok(compilation)
}

fn report_diagnostics(compilation: &Compilation, diagnostics: &[lsdc::diag::Diagnostic], format: Format) {
    let mut diagnostics = diagnostics.to_vec();
    for d in &mut diagnostics {
        compilation.workspace.add_import_context(d);
    }
    match format {
        Format::Text => eprint!("{}", render::to_text(&compilation.workspace.sources, &diagnostics)),
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
    analyse: impl Fn(&Mechanism) -> Result<R, Vec<Diagnostic>>,
    text: impl Fn(&R) -> String,
) -> ExitCode {
    let compilation = match compile_one(file, options, format) {
        Ok(c) => c,
        Err(code) => return code,
    };
    let Some(mechanism) = &compilation.mechanism else { return ExitCode::from(1) };
    match analyse(mechanism) {
        Ok(result) => {
            match format {
                Format::Text => out(&text(&result)),
                Format::Json => out(&json(&result)),
            }
            ExitCode::SUCCESS
        }
        Err(diagnostics) => {
            report_diagnostics(&compilation, &diagnostics, format);
            ExitCode::from(1)
        }
    }
}

fn tree(file: &std::path::Path, options: &LoadOptions, format: Format) -> ExitCode {
    report(file, options, format, analysis::tree, text::tree)
}

fn assemble(file: &std::path::Path, options: &LoadOptions, format: Format) -> ExitCode {
    let analyse = |mechanism: &Mechanism| {
        let topology = lsdc::topology::build(mechanism)?;
        analysis::assembled_model(mechanism, topology, &Default::default()).map(|(_, report)| report)
    };
    report(file, options, format, analyse, text::assembly)
}

fn compile(file: &std::path::Path, options: &LoadOptions, emit: Emit) -> ExitCode {
    match emit {
        Emit::Notation => {
            let analyse = |mechanism: &Mechanism| {
                let topology = lsdc::topology::build(mechanism)?;
                Ok(lsdc::topology::notation::notation(mechanism, &topology))
            };
            report(file, options, Format::Text, analyse, String::clone)
        }
    }
}

fn parse(file: &std::path::Path) -> ExitCode {
    let text = match std::fs::read_to_string(file) {
        Ok(t) => t,
        Err(e) => return usage_error(&format!("cannot read `{}`: {e}", file.display())),
    };
    let mut sources = lsdc::source::SourceMap::new();
    let id = sources.add(file.display().to_string(), text);
    let (program, diagnostics) = lsdc::syntax::parser::parse(id, &sources.file(id).text);
    out(&format!("{program:#?}\n"));
    eprint!("{}", render::to_text(&sources, &diagnostics));
    if diagnostics.is_empty() {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    }
}
