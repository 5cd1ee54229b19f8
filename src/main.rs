//! The `lsdc` command line: wires the phases together, prints results and diagnostics.
//! Exit codes: 0 clean, 1 errors in the program, 2 usage errors (bad flags, unreadable files).

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand, ValueEnum};

use lsdc::diag::render;
use lsdc::driver::{self, Compilation};
use lsdc::elab::Summary;
use lsdc::load::LoadOptions;

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
    /// Print the syntax tree of a file (for debugging the parser).
    Parse { file: PathBuf },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match cli.command {
        Command::Check { files, libraries, format } => check(&files, &libraries.options(), format),
        Command::Parse { file } => parse(&file),
    }
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
        println!("{}", serde_json::to_string_pretty(&value).unwrap_or_default());
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
        Some(mechanism) => print!("{}", summary_text(file, &mechanism.summary())),
        None => {
            let errors = compilation.diagnostics.iter().filter(|d| d.is_error()).count();
            eprintln!("{}: {errors} error{}", file.display(), if errors == 1 { "" } else { "s" });
        }
    }
}

fn summary_text(file: &std::path::Path, s: &Summary) -> String {
    let plural = |n: usize, word: &str| format!("{n} {word}{}", if n == 1 { "" } else { "s" });
    let mut out = format!("{}: ok\n", file.display());
    out += &format!("  bodies    {}", s.bodies);
    if !s.body_names.is_empty() {
        out += &format!(" ({})", s.body_names.join(", "));
    }
    out += &format!("\n  links     {}\n  joins     {}\n", s.links, s.joins);
    out += &format!(
        "  applied   {}, {}\n",
        plural(s.applied_forces, "force"),
        plural(s.applied_torques, "torque")
    );
    out += &format!(
        "  unknowns  {} (?s), {} (?v), {} (?f)\n",
        plural(s.unknown_scalars, "scalar"),
        plural(s.unknown_vectors / 3, "vector"),
        plural(s.unknown_functions, "function")
    );
    out
}

fn json_report(file: &std::path::Path, compilation: &Compilation) -> serde_json::Value {
    serde_json::json!({
        "file": file.display().to_string(),
        "ok": !compilation.has_errors(),
        "diagnostics": render::to_json_value(&compilation.workspace.sources, &compilation.diagnostics),
        "summary": compilation.mechanism.as_ref().map(|m| m.summary()),
    })
}

fn parse(file: &std::path::Path) -> ExitCode {
    let text = match std::fs::read_to_string(file) {
        Ok(t) => t,
        Err(e) => return usage_error(&format!("cannot read `{}`: {e}", file.display())),
    };
    let mut sources = lsdc::source::SourceMap::new();
    let id = sources.add(file.display().to_string(), text);
    let (program, diagnostics) = lsdc::syntax::parser::parse(id, &sources.file(id).text);
    println!("{program:#?}");
    eprint!("{}", render::to_text(&sources, &diagnostics));
    if diagnostics.is_empty() {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    }
}
