//! `lsdc workspace FILE --point FRAME --actuate JOIN.COORDINATE... [--range NAME=LOW:HIGH]`:
//! the reachable set of a point sampled over the actuated coordinates, its volume, boundary,
//! singular loci and dexterity, as CSV or JSON.

use std::path::PathBuf;
use std::process::ExitCode;

use super::shared::{
    err, json, prepare_file, usage_error, write_output, Format, LibraryArgs, SampleFormat,
};
use lsdc::output::workspace_plot::{plot, SlicePoint, Slices};
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
    /// Draw slices of the reachable set (dexterity, boundary, singular loci) to this file
    /// (`.svg` or `.png`).
    #[arg(long, value_name = "FILE")]
    plot: Option<PathBuf>,
    /// Cells per actuated coordinate (per axis with `--positions`).
    #[arg(long, default_value_t = 12)]
    samples: usize,
    #[arg(long, default_value_t = SINGULAR_TOLERANCE)]
    tolerance: f64,
    #[arg(long, value_enum, default_value = "csv")]
    format: SampleFormat,
    /// Write the samples to this file instead of standard output.
    #[arg(short = 'o', long = "out")]
    out: Option<PathBuf>,
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

/// The slices of a workspace sampled over the actuated coordinates.
fn joint_slices(workspace: &Workspace) -> Slices {
    Slices {
        title: format!(
            "workspace of `{}` over the actuated coordinates",
            workspace.point
        ),
        points: (workspace.samples.iter())
            .filter_map(|s| {
                s.point.map(|position| SlicePoint {
                    position,
                    dexterity: s.dexterity,
                    boundary: s.boundary,
                })
            })
            .collect(),
        singular: workspace.crossings.iter().map(|c| c.point).collect(),
    }
}

/// The slices of a workspace sampled over a box of positions.
fn position_slices(workspace: &PositionWorkspace) -> Slices {
    Slices {
        title: format!("workspace of `{}` over a box of positions", workspace.point),
        points: (workspace.samples.iter())
            .filter(|s| s.reachable)
            .map(|s| SlicePoint {
                position: s.point,
                dexterity: s.dexterity,
                boundary: s.boundary,
            })
            .collect(),
        singular: (workspace.samples.iter())
            .filter(|s| s.reachable && s.dexterity.is_none())
            .map(|s| s.point)
            .collect(),
    }
}

pub fn run(args: &WorkspaceArgs) -> ExitCode {
    if args.samples == 0 || !(args.tolerance.is_finite() && args.tolerance > 0.0) {
        return usage_error("`--samples` and `--tolerance` must be positive");
    }
    let given = match args
        .ranges
        .iter()
        .map(|r| parse_range(r))
        .collect::<Result<Vec<_>, _>>()
    {
        Ok(given) => given,
        Err(message) => return usage_error(&message),
    };
    let positions = match args.positions.as_deref().map(parse_box).transpose() {
        Ok(positions) => positions,
        Err(message) => return usage_error(&message),
    };
    if let Some(path) = &args.plot {
        if let Err(error) = lsdc::output::plot::check_path(path) {
            return usage_error(&format!("cannot plot to `{}`: {error}", path.display()));
        }
    }
    let (program, prepared) =
        match prepare_file(&args.file, &args.libraries, &args.sets, Format::Text) {
            Ok(prepared) => prepared,
            Err(code) => return code,
        };
    let Ok(mechanism) = program.mechanism() else {
        return ExitCode::from(1);
    };
    let frame =
        match lsdc::kinematics::frames::resolve(mechanism, &prepared.kinematics, &args.point) {
            Ok(frame) => frame,
            Err(message) => return usage_error(&message),
        };
    let output = Output {
        frame,
        kind: OutputKind::Point,
    };
    let actuation = match actuation(&prepared, &args.actuated) {
        Ok(actuation) => actuation,
        Err(error) => return usage_error(&error.to_string()),
    };
    let ranges = match ranges(&prepared, &actuation, &given) {
        Ok(ranges) => ranges,
        Err(message) => return usage_error(&message),
    };
    let failed = |error: lsdc::studies::kinematic_models::KinematicsError| {
        err(&format!("error: {error}\n"));
        ExitCode::from(1)
    };
    let (text, slices, summary) = match positions {
        Some(positions) => {
            let workspace = match sample_positions(
                &prepared,
                &actuation,
                &output,
                &ranges,
                &positions,
                args.samples,
                args.tolerance,
            ) {
                Ok(workspace) => workspace,
                Err(error) => return failed(error),
            };
            let summary = format!(
                "workspace of `{}` over a box of positions: volume {:.6e} ({} of {} positions reachable, {} on the boundary)\n",
                workspace.point,
                workspace.volume,
                workspace.reachable,
                workspace.samples.len(),
                workspace.boundary
            );
            let text = match args.format {
                SampleFormat::Csv => positions_to_csv(&workspace),
                SampleFormat::Json => json(&workspace),
            };
            (text, position_slices(&workspace), summary)
        }
        None => {
            if ranges.len() > 3 {
                return usage_error("sample at most three actuated coordinates");
            }
            let workspace = match sample(
                &prepared,
                &actuation,
                &output,
                &ranges,
                args.samples,
                args.tolerance,
            ) {
                Ok(workspace) => workspace,
                Err(error) => return failed(error),
            };
            let summary = format!(
                "workspace of `{}`: volume {:.6e} ({} of {} samples reachable, {} on the boundary, {} singular crossings)\n",
                workspace.point,
                workspace.volume,
                workspace.reachable,
                workspace.samples.len(),
                workspace.boundary,
                workspace.crossings.len()
            );
            let text = match args.format {
                SampleFormat::Csv => to_csv(&workspace),
                SampleFormat::Json => json(&workspace),
            };
            (text, joint_slices(&workspace), summary)
        }
    };
    if let Some(path) = &args.plot {
        if let Err(error) = plot(&slices, path) {
            err(&format!(
                "error: cannot plot to `{}`: {error}\n",
                path.display()
            ));
            return ExitCode::from(1);
        }
    }
    let code = write_output(args.out.as_deref(), &text);
    if code == ExitCode::SUCCESS {
        err(&summary);
    }
    code
}
