//! `lsdc view FILE [--results run.json] [--port P | --export page.html]`.

use std::path::PathBuf;
use std::process::ExitCode;

use super::shared::{err, out, prepare_program, usage_error, Format, LibraryArgs};
use super::workspace::{check_sampling, sample_workspace, Sampling};
use lsdc::view::scene::read_results;
use lsdc::view::{server, Viewer};

#[derive(clap::Args)]
pub struct ViewArgs {
    file: PathBuf,
    #[command(flatten)]
    libraries: LibraryArgs,
    /// Value of an unknown, as for `simulate`. Repeatable.
    #[arg(long = "set", value_name = "NAME=VALUE")]
    sets: Vec<String>,
    /// Play these results (`lsdc simulate --format json` output) instead of running.
    #[arg(long, value_name = "RUN.JSON")]
    results: Option<PathBuf>,
    /// Write one standalone HTML file (no server, no network needed) instead of serving.
    #[arg(long, value_name = "PAGE.HTML")]
    export: Option<PathBuf>,
    /// Duration of the simulation an exported page plays (without `--results`).
    #[arg(long)]
    duration: Option<f64>,
    /// The port on 127.0.0.1 to serve on (0: any free port).
    #[arg(long, default_value_t = 8000)]
    port: u16,
    /// Show the workspace of this frame's origin as a layer, sampled as `lsdc workspace
    /// --point FRAME` samples it (with the options below).
    #[arg(long, value_name = "FRAME")]
    workspace: Option<String>,
    #[command(flatten)]
    sampling: Sampling,
}

pub fn run(args: &ViewArgs) -> ExitCode {
    if args.workspace.is_none() && args.sampling.given() {
        return usage_error(
            "`--actuate`, `--range` and `--positions` sample a workspace: give `--workspace FRAME`",
        );
    }
    let request = match check_sampling(&args.sampling) {
        Ok(request) => request,
        Err(code) => return code,
    };
    let changes = Default::default();
    let (program, prepared) = match prepare_program(
        &args.file,
        &args.libraries,
        &args.sets,
        &changes,
        Format::Text,
    ) {
        Ok(prepared) => prepared,
        Err(code) => return code,
    };
    let Ok(mechanism) = program.mechanism().cloned() else {
        return ExitCode::from(1);
    };
    let title = args
        .file
        .file_stem()
        .map_or("mechanism".into(), |s| s.to_string_lossy().to_string());
    let sampled = match &args.workspace {
        Some(point) => match sample_workspace(&request, point, &mechanism, &prepared) {
            Ok(sampled) => Some(sampled),
            Err(code) => return code,
        },
        None => None,
    };
    let mut viewer = match Viewer::new(mechanism, prepared, &title) {
        Ok(v) => v,
        Err(message) => return usage_error(&message),
    };
    if let Some(sampled) = sampled {
        err(&sampled.summary());
        viewer.show_workspace(&sampled.slices());
    }
    if let Some(path) = &args.results {
        let name = path.display().to_string();
        let recorded = std::fs::read_to_string(path)
            .map_err(|e| format!("cannot read `{name}`: {e}"))
            .and_then(|text| read_results(&text, &name, &viewer.prepared));
        if let Err(message) = recorded.and_then(|r| viewer.play(&r)) {
            return usage_error(&message);
        }
    }
    match &args.export {
        Some(path) => export(&mut viewer, args.duration, path),
        None => serve(&mut viewer, args.port),
    }
}

/// Writes the standalone page, with a run of the program's simulation if no results were
/// given.
fn export(viewer: &mut Viewer, duration: Option<f64>, path: &std::path::Path) -> ExitCode {
    if viewer.results.is_none() {
        match viewer.simulate(duration) {
            Ok(animation) => viewer.results = Some(animation),
            Err(message) => return usage_error(&message),
        }
    }
    match std::fs::write(path, viewer.page(false)) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => usage_error(&format!("cannot write `{}`: {e}", path.display())),
    }
}

fn serve(viewer: &mut Viewer, port: u16) -> ExitCode {
    let listener = match std::net::TcpListener::bind(("127.0.0.1", port)) {
        Ok(l) => l,
        Err(e) => return usage_error(&format!("cannot listen on 127.0.0.1:{port}: {e}")),
    };
    let address = listener
        .local_addr()
        .map_or(format!("127.0.0.1:{port}"), |a| a.to_string());
    out(&format!("lsdc view: http://{address}/ (Ctrl+C to stop)\n"));
    match server::serve(&listener, viewer, None) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => usage_error(&format!("the server stopped: {e}")),
    }
}
