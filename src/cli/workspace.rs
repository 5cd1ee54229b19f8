//! `lsdc workspace FILE --point FRAME --actuate JOIN.COORDINATE... [--range NAME=LOW:HIGH]`:
//! the reachable set of a point sampled over the actuated coordinates, its volume, boundary,
//! singular loci and dexterity, as CSV or JSON.

use std::path::PathBuf;
use std::process::ExitCode;

use super::shared::{
    err, json, prepare_kinematics_file, usage_error, write_output, Format, LibraryArgs,
    SampleFormat,
};
use lsdc::elab::mechanism::Mechanism;
use lsdc::output::workspace_plot::{plot, Slices};
use lsdc::prepare::Prepared;
use lsdc::studies::kinematic_models::{actuation, Output, OutputKind, SINGULAR_TOLERANCE};
use lsdc::studies::workspace::{ranges, sample, to_csv, Workspace};
use lsdc::studies::workspace_positions::{
    positions_to_csv, sample_positions, PositionBox, PositionWorkspace,
};

#[derive(clap::Args)]
pub struct WorkspaceArgs {
    file: PathBuf,
    #[command(flatten)]
    libraries: LibraryArgs,
    /// Value of an unknown, as for `simulate`. Repeatable.
    #[arg(long = "set", value_name = "NAME=VALUE")]
    sets: Vec<String>,
    /// The frame whose origin's workspace is sampled (a frame the program names, or a body).
    #[arg(long, value_name = "FRAME")]
    point: String,
    #[command(flatten)]
    sampling: Sampling,
    /// Draw slices of the reachable set (dexterity, boundary, singular loci) to this file
    /// (`.svg` or `.png`).
    #[arg(long, value_name = "FILE")]
    plot: Option<PathBuf>,
    #[arg(long, value_enum, default_value = "csv")]
    format: SampleFormat,
    /// Write the samples to this file instead of standard output.
    #[arg(short = 'o', long = "out")]
    out: Option<PathBuf>,
}

// How a workspace is sampled: shared by `lsdc workspace` and `lsdc view --workspace`.
// (A plain comment: clap takes a flattened struct's doc comment for the description of the
// command it is flattened into.)
#[derive(clap::Args)]
pub struct Sampling {
    /// An actuated coordinate, `join.coordinate` (repeatable; for a tree, every coordinate
    /// without it).
    #[arg(long = "actuate", value_name = "JOIN.COORDINATE")]
    actuated: Vec<String>,
    /// The range sampled for an actuated coordinate (without it, its two stops).
    #[arg(long = "range", value_name = "NAME=LOW:HIGH")]
    ranges: Vec<String>,
    /// Sample a box of positions of the point instead (`XLOW:XHIGH,YLOW:YHIGH,ZLOW:ZHIGH`,
    /// metres): reachable where the inverse geometric model reaches it with the actuated
    /// coordinates within their ranges.
    #[arg(long, value_name = "BOX", allow_hyphen_values = true)]
    positions: Option<String>,
    /// Cells per actuated coordinate (per axis with `--positions`).
    #[arg(long, default_value_t = 12)]
    samples: usize,
    #[arg(long, default_value_t = SINGULAR_TOLERANCE)]
    tolerance: f64,
}

/// `NAME=LOW:HIGH`.
fn parse_range(text: &str) -> Result<(String, f64, f64), String> {
    let bad = || format!("`--range {text}`: expected NAME=LOW:HIGH with LOW < HIGH");
    let (name, bounds) = text.split_once('=').ok_or_else(bad)?;
    let (low, high) = bounds.split_once(':').ok_or_else(bad)?;
    let (low, high): (f64, f64) = (
        low.trim().parse().map_err(|_| bad())?,
        high.trim().parse().map_err(|_| bad())?,
    );
    if !(low.is_finite() && high.is_finite() && low < high) {
        return Err(bad());
    }
    Ok((name.trim().to_string(), low, high))
}

/// `XLOW:XHIGH,YLOW:YHIGH,ZLOW:ZHIGH`.
fn parse_box(text: &str) -> Result<PositionBox, String> {
    let bad = || {
        format!(
            "`--positions {text}`: expected XLOW:XHIGH,YLOW:YHIGH,ZLOW:ZHIGH with each LOW < HIGH"
        )
    };
    let axes: Vec<&str> = text.split(',').collect();
    if axes.len() != 3 {
        return Err(bad());
    }
    let mut positions = PositionBox {
        lower: [0.0; 3],
        upper: [0.0; 3],
    };
    for (k, axis) in axes.iter().enumerate() {
        let (_, low, high) = parse_range(&format!("axis={axis}")).map_err(|_| bad())?;
        positions.lower[k] = low;
        positions.upper[k] = high;
    }
    Ok(positions)
}

/// A sampled workspace, over the actuated coordinates or a box of positions.
pub enum Sampled {
    Joints(Workspace),
    Positions(PositionWorkspace),
}

impl Sampled {
    pub fn slices(&self) -> Slices {
        match self {
            Sampled::Joints(workspace) => Slices::from(workspace),
            Sampled::Positions(workspace) => Slices::from(workspace),
        }
    }

    /// The one-line summary written to standard error.
    pub fn summary(&self) -> String {
        match self {
            Sampled::Positions(workspace) => format!(
                "workspace of `{}` over a box of positions: volume {:.6e} ({} of {} positions reachable, {} on the boundary)\n",
                workspace.point,
                workspace.volume,
                workspace.reachable,
                workspace.samples.len(),
                workspace.boundary
            ),
            Sampled::Joints(workspace) => format!(
                "workspace of `{}`: volume {:.6e} ({} of {} samples reachable, {} on the boundary, {} singular crossings)\n",
                workspace.point,
                workspace.volume,
                workspace.reachable,
                workspace.samples.len(),
                workspace.boundary,
                workspace.crossings.len()
            ),
        }
    }

    fn text(&self, format: SampleFormat) -> String {
        match (self, format) {
            (Sampled::Positions(workspace), SampleFormat::Csv) => positions_to_csv(workspace),
            (Sampled::Positions(workspace), SampleFormat::Json) => json(workspace),
            (Sampled::Joints(workspace), SampleFormat::Csv) => to_csv(workspace),
            (Sampled::Joints(workspace), SampleFormat::Json) => json(workspace),
        }
    }
}

impl Sampling {
    /// Whether any option of the sampling's own is given (the coordinates, ranges or box).
    pub fn given(&self) -> bool {
        !self.actuated.is_empty() || !self.ranges.is_empty() || self.positions.is_some()
    }
}

/// The sampling's arguments read and checked, before the program is (usage errors first).
pub struct Request<'a> {
    sampling: &'a Sampling,
    given: Vec<(String, f64, f64)>,
    positions: Option<PositionBox>,
}

pub fn check_sampling(sampling: &Sampling) -> Result<Request<'_>, ExitCode> {
    if sampling.samples == 0 || !(sampling.tolerance.is_finite() && sampling.tolerance > 0.0) {
        return Err(usage_error(
            "`--samples` and `--tolerance` must be positive",
        ));
    }
    let given = (sampling.ranges.iter())
        .map(|r| parse_range(r))
        .collect::<Result<Vec<_>, _>>()
        .map_err(|message| usage_error(&message))?;
    let positions = (sampling.positions.as_deref().map(parse_box).transpose())
        .map_err(|message| usage_error(&message))?;
    Ok(Request {
        sampling,
        given,
        positions,
    })
}

/// Samples the workspace of the frame `point` of a prepared program.
pub fn sample_workspace(
    request: &Request,
    point: &str,
    mechanism: &Mechanism,
    prepared: &Prepared,
) -> Result<Sampled, ExitCode> {
    let Request {
        sampling,
        given,
        positions,
    } = request;
    let frame = lsdc::kinematics::frames::resolve(mechanism, &prepared.kinematics, point)
        .map_err(|message| usage_error(&message))?;
    let output = Output {
        frame,
        kind: OutputKind::Point,
    };
    let actuation =
        actuation(prepared, &sampling.actuated).map_err(|error| usage_error(&error.to_string()))?;
    let ranges = ranges(prepared, &actuation, given).map_err(|message| usage_error(&message))?;
    let failed = |error: lsdc::studies::kinematic_models::KinematicsError| {
        err(&format!("error: {error}\n"));
        ExitCode::from(1)
    };
    let (samples, tolerance) = (sampling.samples, sampling.tolerance);
    match positions {
        Some(positions) => sample_positions(
            prepared, &actuation, &output, &ranges, positions, samples, tolerance,
        )
        .map(Sampled::Positions)
        .map_err(failed),
        None => {
            if ranges.len() > 3 {
                return Err(usage_error("sample at most three actuated coordinates"));
            }
            sample(prepared, &actuation, &output, &ranges, samples, tolerance)
                .map(Sampled::Joints)
                .map_err(failed)
        }
    }
}

pub fn run(args: &WorkspaceArgs) -> ExitCode {
    let request = match check_sampling(&args.sampling) {
        Ok(request) => request,
        Err(code) => return code,
    };
    if let Some(path) = &args.plot {
        if let Err(error) = lsdc::output::plot::check_path(path) {
            return usage_error(&format!("cannot plot to `{}`: {error}", path.display()));
        }
    }
    let (program, prepared) =
        match prepare_kinematics_file(&args.file, &args.libraries, &args.sets, Format::Text) {
            Ok(prepared) => prepared,
            Err(code) => return code,
        };
    let Ok(mechanism) = program.mechanism() else {
        return ExitCode::from(1);
    };
    let sampled = match sample_workspace(&request, &args.point, mechanism, &prepared) {
        Ok(sampled) => sampled,
        Err(code) => return code,
    };
    if let Some(path) = &args.plot {
        if let Err(error) = plot(&sampled.slices(), path) {
            err(&format!(
                "error: cannot plot to `{}`: {error}\n",
                path.display()
            ));
            return ExitCode::from(1);
        }
    }
    let code = write_output(args.out.as_deref(), &sampled.text(args.format));
    if code == ExitCode::SUCCESS {
        err(&sampled.summary());
    }
    code
}
