//! `lsdc inverse FILE`: inverse dynamics along the program's drives, or along a motion read
//! from a CSV file (`--motion`: coordinates, or a frame's path with `--frame` and the actuated
//! coordinates `--actuate`): the efforts that impose them, the power and, with `--reactions`,
//! every join's reaction, as CSV or JSON; `--plot` draws the run (the coordinates with the
//! efforts, and the energy).

use std::path::PathBuf;
use std::process::ExitCode;

use super::shared::{
    err, json, out, prepare_program, usage_error, Format, LibraryArgs, SampleFormat,
};
use lsdc::api::SettingsChanges;
use lsdc::prepare::Prepared;
use lsdc::studies::inverse::{check_driven, from_run};
use lsdc::studies::kinematic_models::{actuation, Output, OutputKind};
use lsdc::studies::motion_file::{read_motion, Derivation};
use lsdc::studies::trajectory::{follow_program_path, impose, Imposed, Target};

#[derive(clap::Args)]
pub struct InverseArgs {
    file: PathBuf,
    #[command(flatten)]
    libraries: LibraryArgs,
    /// Value of an unknown, as for `simulate`. Repeatable.
    #[arg(long = "set", value_name = "NAME=VALUE")]
    sets: Vec<String>,
    /// Overrides the program's `simulate` duration.
    #[arg(long, conflicts_with = "motion")]
    duration: Option<f64>,
    /// Time between rows.
    #[arg(long = "every", conflicts_with = "motion")]
    output_interval: Option<f64>,
    /// The motion from a CSV file: `time` (from 0, evenly spaced) and a column per driven
    /// coordinate (`A1.q`), or the position of the frame `--frame` (`nacelle.x`, `.y`, `.z`);
    /// rates (`A1.q'`) and accelerations (`A1.q''`) from their columns, or by a quintic spline.
    #[arg(long, value_name = "FILE.csv")]
    motion: Option<PathBuf>,
    /// The motion file is the path of this frame's origin, followed by the actuated
    /// coordinates `--actuate` through the inverse geometric model.
    #[arg(long, value_name = "FRAME", requires = "motion")]
    frame: Option<String>,
    /// An actuated coordinate `join.coordinate` driving the frame `--frame`, or the frame of
    /// the program's position drive (repeatable).
    #[arg(long = "actuate", value_name = "JOIN.COORDINATE")]
    actuated: Vec<String>,
    /// The error variance of the motion's positions for the spline of the rates and
    /// accelerations not in the file (their units squared; 0, the default: the spline
    /// interpolates).
    #[arg(long, default_value_t = 0.0, requires = "motion")]
    smoothing: f64,
    /// Add every join's reaction: the wrench it transmits to its second body, at the join, in
    /// the fixed axes (moment then force).
    #[arg(long)]
    reactions: bool,
    #[arg(long, value_enum, default_value = "csv")]
    format: SampleFormat,
    /// Draw the driven coordinates, the efforts and the energy over time to an .svg or .png.
    #[arg(long)]
    plot: Option<PathBuf>,
}

pub fn run(args: &InverseArgs) -> ExitCode {
    let changes = SettingsChanges {
        duration: args.duration,
        output: args.output_interval,
        reactions: args.reactions,
        ..Default::default()
    };
    let (program, mut prepared) = match prepare_program(
        &args.file,
        &args.libraries,
        &args.sets,
        &changes,
        Format::Text,
    ) {
        Ok(prepared) => prepared,
        Err(code) => return code,
    };
    let has_path = !prepared.model.position_drives.is_empty();
    let imposed = match (&args.motion, has_path) {
        (Some(_), true) => {
            let drive = &prepared.model.position_drives[0];
            return usage_error(&format!("the program drives the position of `{}`: a motion from a file would drive the mechanism twice (leave out `--motion`, or the position drive)", drive.frame.name));
        }
        (Some(motion), false) => match imposed_motion(args, &program, &mut prepared, motion) {
            Ok(imposed) => Some(imposed),
            Err(why) => return usage_error(&why),
        },
        // Without actuated coordinates the path's own rows impose it: the efforts are the
        // forces along x, y, z at the frame's origin.
        (None, true) if args.actuated.is_empty() => None,
        (None, true) => match follow_program_path(&mut prepared, &args.actuated) {
            Some(Ok(imposed)) => Some(imposed),
            Some(Err(why)) => return usage_error(&why),
            None => None,
        },
        (None, false) if !args.actuated.is_empty() => {
            return usage_error("`--actuate` names the coordinates that move a frame along a path: give the path with `--motion FILE --frame FRAME`, or drive the frame's position in the program (`drive position(nacelle) = [x, y, z];`)");
        }
        (None, false) => None,
    };
    if let Err(why) = check_driven(&prepared) {
        return usage_error(&why.to_string());
    }
    if let Some(path) = &args.plot {
        if let Err(error) = lsdc::output::plot::check_path(path) {
            return usage_error(&format!("cannot draw `{}`: {error}", path.display()));
        }
    }
    let simulation = lsdc::api::run(&prepared, &mut |_| {});
    let mut inverse = from_run(&prepared, &simulation);
    inverse.motion = imposed;
    match args.format {
        SampleFormat::Csv => out(&inverse.to_csv()),
        SampleFormat::Json => out(&json(&inverse)),
    }
    if let Some(path) = &args.plot {
        if let Err(error) = lsdc::output::plot::plot(&simulation, path) {
            err(&format!(
                "error: cannot draw `{}`: {error}\n",
                path.display()
            ));
        }
    }
    match &simulation.report.failure {
        Some(failure) => {
            err(&format!(
                "error: the motion stopped at t = {}: {}\n",
                failure.time, failure.message
            ));
            ExitCode::from(1)
        }
        None => ExitCode::SUCCESS,
    }
}

/// The drives of the motion file `path` added to `prepared` (see `studies::trajectory`); the
/// rates and accelerations taken from the spline are said on standard error.
fn imposed_motion(
    args: &InverseArgs,
    program: &lsdc::api::Program,
    prepared: &mut Prepared,
    path: &std::path::Path,
) -> Result<Imposed, String> {
    if args.frame.is_none() && !args.actuated.is_empty() {
        return Err("`--actuate` names the coordinates that move the frame `--frame` along the file's path: give `--frame FRAME`".to_string());
    }
    if !(args.smoothing.is_finite() && args.smoothing >= 0.0) {
        return Err("`--smoothing` must be 0 or positive".to_string());
    }
    let text = std::fs::read_to_string(path)
        .map_err(|e| format!("cannot read `{}`: {e}", path.display()))?;
    let motion = read_motion(&text, &path.display().to_string(), args.smoothing)?;
    let in_file = |why: String| format!("{}: {why}", path.display());
    let imposed = match &args.frame {
        None => impose(prepared, &motion, Target::Coordinates).map_err(in_file)?,
        Some(name) => {
            let mechanism = program
                .mechanism()
                .map_err(|_| "the program has no mechanism".to_string())?;
            let frame = lsdc::kinematics::frames::resolve(mechanism, &prepared.kinematics, name)?;
            let output = Output {
                frame,
                kind: OutputKind::Point,
            };
            if args.actuated.is_empty() {
                return Err(format!("a path of `{name}` needs the coordinates that move it: `--actuate JOIN.COORDINATE`, one per degree of freedom"));
            }
            let actuation = actuation(prepared, &args.actuated).map_err(|e| e.to_string())?;
            let target = Target::Frame {
                output: &output,
                actuation: &actuation,
            };
            impose(prepared, &motion, target).map_err(in_file)?
        }
    };
    let splined: Vec<&str> = (imposed.columns.iter())
        .filter(|c| c.rates == Derivation::Spline || c.accelerations == Derivation::Spline)
        .map(|c| c.name.as_str())
        .collect();
    if !splined.is_empty() {
        err(&format!(
            "note: the rates or accelerations of {} are those of a quintic spline of the positions (error variance {})\n",
            splined.iter().map(|n| format!("`{n}`")).collect::<Vec<_>>().join(", "),
            args.smoothing
        ));
    }
    Ok(imposed)
}
