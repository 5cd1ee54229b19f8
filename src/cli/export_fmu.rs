//! `lsdc export-fmu FILE -o model.fmu`: the program as an FMI unit (FMI 3.0, or 2.0 with
//! `--fmi 2`) for co-simulation, run inside by lsdc's own integrator, events and loop
//! projection, and for model exchange where the mechanism is a tree without events (its
//! equations integrated by the importer), as `--kind` chooses.
//! The unit holds the model description, the program's files with a description of the
//! variables (`resources/lsdc/`), and the shared library of `fmi/` under the model's identifier,
//! which loads the program at instantiation (docs/fmi.md).

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use super::fmi_library;
use super::shared::{err, out, parse_sets, prepare_file, usage_error, Format, LibraryArgs};
use lsdc::api::{model_exchange_refusal, output_names, Equations, Program, Simulator};
use lsdc::kinematics::unknowns::Override;
use lsdc::output::fmi::archive::Archive;
use lsdc::output::fmi::model_description::{model_description, Identity, Kind, Version};
use lsdc::output::fmi::variables::{parameters, variables, Variable};

#[derive(clap::Args)]
pub struct ExportFmuArgs {
    file: PathBuf,
    #[command(flatten)]
    libraries: LibraryArgs,
    /// Value of an unknown, as for `simulate`: a parameter of the unit, with this start value.
    /// Repeatable.
    #[arg(long = "set", value_name = "NAME=VALUE")]
    sets: Vec<String>,
    /// An input of the unit besides the program's `input` declarations: the generalised effort
    /// along this velocity (`swing.q`), held over each communication step, named
    /// `swing.q.effort`, starting at 0. Repeatable.
    #[arg(long = "input", value_name = "JOIN.COORD")]
    inputs: Vec<String>,
    /// The FMI version: 3 (FMI 3.0) or 2 (FMI 2.0).
    #[arg(long = "fmi", default_value = "3", value_parser = ["2", "3"])]
    fmi: String,
    /// The interfaces of the unit: `co-simulation` (lsdc's integrator inside), `model-exchange`
    /// (the importer integrates the equations: trees without events only) or `both`. By
    /// default both where the mechanism allows model exchange, else co-simulation.
    #[arg(long = "kind", value_parser = ["co-simulation", "model-exchange", "both"])]
    kind: Option<String>,
    /// Write the unit to this file.
    #[arg(
        short = 'o',
        long = "out",
        required_unless_present = "model_description"
    )]
    out: Option<PathBuf>,
    /// Put this shared library in the unit instead of the one built from the repository's
    /// `fmi/` crate (or the one LSDC_FMI_LIBRARY names).
    #[arg(long = "library", value_name = "PATH")]
    library: Option<PathBuf>,
    /// Print the model description on standard output instead of writing a unit.
    #[arg(long = "model-description")]
    model_description: bool,
}

/// The unit's own description of its program and variables, `resources/lsdc/unit.json`: what
/// the shared library reads at instantiation.
#[derive(serde::Serialize)]
struct UnitFile<'a> {
    token: &'a str,
    /// The root file, relative to `resources/lsdc/program/`.
    program: String,
    /// `-L` directories, relative to the same folder.
    library_dirs: Vec<String>,
    scene: Option<&'a str>,
    /// Whether the unit provides model exchange (the library then accepts its instantiation).
    model_exchange: bool,
    /// The velocities the inputs act along, in order.
    inputs: &'a [String],
    variables: &'a [Variable],
}

/// Inputs with their start values, each replaced by the last `--set` that names it.
fn with_sets(inputs: Vec<(String, f64)>, sets: &[Override]) -> Vec<(String, f64)> {
    (inputs.into_iter())
        .map(|(name, start)| {
            let set = sets.iter().rev().find(|set| set.name == name);
            let start = set.map_or(start, |set| set.value);
            (name, start)
        })
        .collect()
}

/// The program's files (its imports but the standard library's) under their common folder: the
/// folder and each file's path relative to it.
fn program_files(program: &Program) -> Result<(PathBuf, Vec<PathBuf>), String> {
    let mut files = Vec::new();
    for (_, file) in program.sources().files() {
        if file.name.starts_with('<') {
            continue;
        }
        let path = std::fs::canonicalize(&file.name)
            .map_err(|e| format!("cannot read `{}` again: {e}", file.name))?;
        if !files.contains(&path) {
            files.push(path);
        }
    }
    let first = files.first().ok_or("the program has no file")?;
    let mut common = first.parent().unwrap_or(Path::new("/")).to_path_buf();
    while !files.iter().all(|f| f.starts_with(&common)) {
        common.pop();
    }
    Ok((common, files))
}

/// `path` relative to `base`, with `/` between its parts.
fn relative(path: &Path, base: &Path) -> String {
    let parts = path.strip_prefix(base).unwrap_or(path).components();
    let parts: Vec<String> = parts
        .map(|c| c.as_os_str().to_string_lossy().into_owned())
        .collect();
    parts.join("/")
}

/// A C identifier made of the file's stem (FMI 3.0 §2.4.1: `modelIdentifier`).
fn model_identifier(stem: &str) -> String {
    let mut identifier: String = stem
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect();
    if !identifier.starts_with(|c: char| c.is_ascii_alphabetic()) {
        identifier.insert_str(0, "lsd_");
    }
    identifier
}

/// A token in the form of a GUID, from the bytes that make the unit (FNV-1a, 128 bits as two
/// 64-bit hashes with different offsets): the same program and variables give the same token.
fn token(parts: &[&[u8]]) -> String {
    let hash = |offset: u64| {
        let mut h = offset;
        for part in parts {
            for &b in part.iter().chain(&[0xff]) {
                h ^= u64::from(b);
                h = h.wrapping_mul(0x0100_0000_01b3);
            }
        }
        h
    };
    let (a, b) = (hash(0xcbf2_9ce4_8422_2325), hash(0x6c62_272e_07bb_0142));
    format!(
        "{{{:08x}-{:04x}-{:04x}-{:04x}-{:012x}}}",
        a >> 32,
        (a >> 16) & 0xffff,
        a & 0xffff,
        b >> 48,
        b & 0xffff_ffff_ffff
    )
}

pub fn run(args: &ExportFmuArgs) -> ExitCode {
    let file = &args.file;
    let (program, prepared) = match prepare_file(file, &args.libraries, &args.sets, Format::Text) {
        Ok(prepared) => prepared,
        Err(code) => return code,
    };
    let Ok(mechanism) = program.mechanism() else {
        return ExitCode::from(1);
    };
    let Ok(overrides) = parse_sets(&args.sets) else {
        return ExitCode::from(2);
    };
    // The program's declared inputs (`input swing.q = 0;`, with their start values, or those
    // `--set` gives them, as every run takes them), then those named here (starting at 0).
    let mut declared = with_sets(mechanism.declared_inputs(), &overrides);
    for name in &args.inputs {
        if !declared.iter().any(|(n, _)| n == name) {
            declared.push((name.clone(), 0.0));
        }
    }
    let input_names: Vec<String> = declared.iter().map(|(n, _)| n.clone()).collect();
    // The inputs are checked as the unit will use them: a simulator starts with them.
    let inputs: Vec<&str> = input_names.iter().map(String::as_str).collect();
    if let Err(failure) = Simulator::new(&prepared, &inputs) {
        return usage_error(&format!("the unit cannot run: {}", failure.message));
    }
    let refusal = model_exchange_refusal(&prepared);
    let kind = match (args.kind.as_deref(), &refusal) {
        (None, None) => Kind::Both,
        (None, Some(_)) | (Some("co-simulation"), _) => Kind::CoSimulation,
        (Some(_), Some(reason)) => {
            return usage_error(&format!(
                "`{}` cannot be exported for model exchange: {reason}; export it for co-simulation (`--kind co-simulation`), where lsdc's own run integrates it",
                file.display()
            ));
        }
        (Some("model-exchange"), None) => Kind::ModelExchange,
        (Some(_), None) => Kind::Both,
    };
    if kind.model_exchange() {
        if let Err(reason) = Equations::new(&prepared, &inputs) {
            return usage_error(&format!("the unit cannot run: {reason}"));
        }
    }
    let parameters = parameters(mechanism, &overrides);
    let variables = variables(
        &prepared,
        &parameters,
        &declared,
        &with_sets(mechanism.declared_value_inputs(), &overrides),
        &output_names(&prepared),
        kind.model_exchange(),
    );
    let version = if args.fmi == "2" {
        Version::Fmi2
    } else {
        Version::Fmi3
    };

    let (root, files) = match program_files(&program) {
        Ok(found) => found,
        Err(message) => return usage_error(&message),
    };
    let mut contents = Vec::new();
    for path in &files {
        match std::fs::read(path) {
            Ok(bytes) => contents.push(bytes),
            Err(e) => return usage_error(&format!("cannot read `{}`: {e}", path.display())),
        }
    }
    let stem = file
        .file_stem()
        .map_or("model".into(), |s| s.to_string_lossy());
    let identifier = model_identifier(&stem);
    let variables_json = serde_json::to_vec(&variables).unwrap_or_default();
    let mut parts: Vec<&[u8]> = contents.iter().map(Vec::as_slice).collect();
    parts.push(&variables_json);
    parts.push(args.fmi.as_bytes());
    parts.push(kind.name().as_bytes());
    let token = token(&parts);
    let settings = &prepared.settings;
    let identity = Identity {
        model_name: &stem,
        model_identifier: &identifier,
        token: &token,
        description: &match &refusal {
            None => format!("the LSD program {}", file.display()),
            Some(reason) => format!(
                "the LSD program {} (co-simulation only: {reason})",
                file.display()
            ),
        },
        kind,
        generation_tool: concat!("lsdc ", env!("CARGO_PKG_VERSION")),
        stop_time: settings.duration,
        tolerance: settings.rtol,
        step_size: settings.output,
    };
    let description = model_description(version, &identity, &variables);
    if args.model_description {
        out(&description);
        return ExitCode::SUCCESS;
    }

    let library = match fmi_library::locate(args.library.as_deref()) {
        Ok(library) => library,
        Err(message) => return usage_error(&message),
    };
    let library_bytes = match std::fs::read(&library) {
        Ok(bytes) => bytes,
        Err(e) => return usage_error(&format!("cannot read `{}`: {e}", library.display())),
    };
    let canonical_file = std::fs::canonicalize(file).unwrap_or_else(|_| file.clone());
    let library_dirs: Vec<String> = (args.libraries.options().library_dirs.iter())
        .filter_map(|d| std::fs::canonicalize(d).ok())
        .filter(|d| d.starts_with(&root))
        .map(|d| relative(&d, &root))
        .collect();
    let unit = UnitFile {
        token: &token,
        program: relative(&canonical_file, &root),
        library_dirs,
        scene: program.scene(),
        model_exchange: kind.model_exchange(),
        inputs: &input_names,
        variables: &variables,
    };
    let mut archive = Archive::default();
    archive.add("modelDescription.xml", description.into_bytes());
    let platform = version.platform_folder(std::env::consts::ARCH, std::env::consts::OS);
    let binary = format!(
        "binaries/{platform}/{identifier}{}",
        std::env::consts::DLL_SUFFIX
    );
    archive.add(&binary, library_bytes);
    let unit_json = serde_json::to_vec_pretty(&unit).unwrap_or_default();
    archive.add("resources/lsdc/unit.json", unit_json);
    for (path, bytes) in files.iter().zip(contents) {
        archive.add(
            &format!("resources/lsdc/program/{}", relative(path, &root)),
            bytes,
        );
    }
    let out_path = args.out.as_deref().unwrap_or(Path::new("model.fmu"));
    let bytes = match archive.to_bytes() {
        Ok(bytes) => bytes,
        Err(message) => return usage_error(&message),
    };
    if let Err(e) = std::fs::write(out_path, bytes) {
        return usage_error(&format!("cannot write `{}`: {e}", out_path.display()));
    }
    err(&format!(
        "wrote {} (FMI {}.0 {}, {} variables)\n",
        out_path.display(),
        if version == Version::Fmi2 { 2 } else { 3 },
        kind.name(),
        variables.len() - usize::from(version == Version::Fmi2)
    ));
    ExitCode::SUCCESS
}
