//! `lsdc check FILE...`: checks programs and prints a summary of the mechanism each describes.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use super::shared::{err, json, out, printed, usage_error, usage_error_json, Format, LibraryArgs};
use lsdc::api::Program;
use lsdc::diag::render;
use lsdc::output::text;

#[derive(clap::Args)]
pub struct CheckArgs {
    #[arg(required = true)]
    files: Vec<PathBuf>,
    #[command(flatten)]
    libraries: LibraryArgs,
    #[arg(long, value_enum, default_value = "text")]
    format: Format,
}

pub fn run(args: &CheckArgs) -> ExitCode {
    let (files, format) = (&args.files, args.format);
    let options = args.libraries.options();
    let mut all_ok = true;
    let mut unreadable = false;
    let mut reports = Vec::new();
    for (i, file) in files.iter().enumerate() {
        let program = match Program::from_file(file, &options) {
            Ok(program) => program,
            // In JSON every file has its entry; in text the first unreadable file stops.
            Err(error) if format == Format::Json => {
                let mut entry = usage_error_json(&error.to_string());
                entry["file"] = file.display().to_string().into();
                reports.push(entry);
                err(&format!("error: {error}\n"));
                (all_ok, unreadable) = (false, true);
                continue;
            }
            Err(error) => return usage_error(&error.to_string()),
        };
        let others = other_scenes(file, args, &program);
        all_ok &= !program.has_errors() && others.iter().all(|p| !p.has_errors());
        match format {
            Format::Text => {
                print_text_report(file, &program);
                for other in &others {
                    print_other_scene(&program, other);
                }
            }
            Format::Json => reports.push(json_report(file, &program, &others)),
        }
        if i + 1 == files.len() {
            // The process ends next: the system takes back its memory at once, whereas freeing
            // the syntax tree and the mechanism node by node is about a tenth of the command's
            // time on a large program. Earlier files are dropped, so that the peak is one file's.
            std::mem::forget(program);
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

/// The program compiled for each of its scenes but the one `program` was (every scene is
/// checked unless `--scene` names one).
fn other_scenes(file: &Path, args: &CheckArgs, program: &Program) -> Vec<Program> {
    if args.libraries.scene().is_some() {
        return Vec::new();
    }
    let others = (program.scene_names().iter()).filter(|n| Some(n.as_str()) != program.scene());
    others
        .filter_map(|name| {
            let mut options = args.libraries.options();
            options.scene = Some(name.clone());
            Program::from_file(file, &options).ok()
        })
        .collect()
}

/// What compiling another scene found that the first compilation did not (the program's own
/// declarations are the same in every scene: their diagnostics are printed once).
fn new_in_scene<'p>(first: &Program, other: &'p Program) -> Vec<&'p lsdc::diag::Diagnostic> {
    let already: Vec<_> = first.diagnostics().iter().collect();
    let seen = |d: &&lsdc::diag::Diagnostic| {
        already.iter().any(|a| {
            a.code == d.code && a.message == d.message && a.primary_span() == d.primary_span()
        })
    };
    other.diagnostics().iter().filter(|d| !seen(d)).collect()
}

fn print_other_scene(first: &Program, other: &Program) {
    let found: Vec<_> = new_in_scene(first, other).into_iter().cloned().collect();
    err(&render::to_text(other.sources(), &printed(&found)));
}

fn print_text_report(file: &Path, program: &Program) {
    let diagnostics = printed(program.diagnostics());
    err(&render::to_text(program.sources(), &diagnostics));
    match program.mechanism() {
        Ok(mechanism) => {
            out(&text::summary(file, &mechanism.summary()));
            if let Some(model) = &mechanism.scene {
                let scenes = program.scene_names().join(", ");
                out(&format!("  scenes    {scenes}\n  {}\n", model.describe()));
            }
        }
        Err(_) => {
            let errors = (program.diagnostics().iter())
                .filter(|d| d.is_error())
                .count();
            err(&format!(
                "{}: {errors} error{}\n",
                file.display(),
                if errors == 1 { "" } else { "s" }
            ));
        }
    }
}

fn json_report(file: &Path, program: &Program, others: &[Program]) -> serde_json::Value {
    let mut diagnostics: Vec<_> = program.diagnostics().to_vec();
    for other in others {
        diagnostics.extend(new_in_scene(program, other).into_iter().cloned());
    }
    let ok = !diagnostics.iter().any(|d| d.is_error());
    let mut report = serde_json::json!({
        "file": file.display().to_string(),
        "ok": ok,
        "diagnostics": render::to_json_value(program.sources(), &diagnostics),
        "summary": program.mechanism().ok().map(|m| m.summary()),
    });
    if !program.scene_names().is_empty() {
        report["scenes"] = program.scene_names().to_vec().into();
    }
    report
}
