//! `lsdc drag FILE --point FRAME --path targets.csv`.

use std::path::PathBuf;
use std::process::ExitCode;

use clap::ValueEnum;

use super::shared::{
    err, json, load_program, parse_sets, report_diagnostics, usage_error, write_output, Format,
    LibraryArgs, SampleFormat,
};
use lsdc::kinematics::assembly::AssemblyOptions;
use lsdc::kinematics::drag::{DragError, DragOptions};
use lsdc::kinematics::frames::{self, FramePoint};
use lsdc::kinematics::model::KinematicModel;
use lsdc::kinematics::penalty::{self, Stiffness};
use lsdc::studies::drag::{follow_exact, follow_penalty, parse_targets, DragRun, PenaltyOptions};

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum DragMethod {
    /// Loops closed exactly, the point a soft goal (least squares).
    Exact,
    /// The planar penalty method: pivots as stiff springs, one linearised solve per move.
    Penalty,
}

#[derive(clap::Args)]
pub struct DragArgs {
    file: PathBuf,
    #[command(flatten)]
    libraries: LibraryArgs,
    /// Value of an unknown, as for `simulate` (over the program's `given`). Repeatable.
    #[arg(long = "set", value_name = "NAME=VALUE")]
    sets: Vec<String>,
    /// The frame whose origin is dragged: a frame the program names, or a body.
    #[arg(long, value_name = "FRAME")]
    point: String,
    /// The targets, one per line: `x,y` or `x,y,z` (a header line and `#` comments allowed).
    #[arg(long, value_name = "FILE")]
    path: PathBuf,
    #[arg(long, value_enum, default_value = "exact")]
    method: DragMethod,
    /// K_L, the pivots' stiffness (penalty method).
    #[arg(long, default_value_t = 1e6)]
    link_stiffness: f64,
    /// K_M, the stiffness of the spring pulling the point to the target.
    #[arg(long, default_value_t = 1.0)]
    mouse_stiffness: f64,
    /// Linearised solves per target (penalty method; 1 is the seed's one solve per move).
    /// Without it, as many as move the configuration, up to 100.
    #[arg(long)]
    iterations: Option<usize>,
    /// A target is reached when the point ends this close to it.
    #[arg(long, default_value_t = 1e-9)]
    reach_tolerance: f64,
    #[arg(long, value_enum, default_value = "csv")]
    format: SampleFormat,
    /// Write the rows to this file instead of standard output.
    #[arg(short = 'o', long = "out")]
    out: Option<PathBuf>,
}

pub fn run(args: &DragArgs) -> ExitCode {
    let positive = [
        args.link_stiffness,
        args.mouse_stiffness,
        args.reach_tolerance,
    ];
    if positive.iter().any(|v| !(v.is_finite() && *v > 0.0)) || args.iterations == Some(0) {
        return usage_error(
            "the stiffnesses, `--reach-tolerance` and `--iterations` must be positive",
        );
    }
    let overrides = match parse_sets(&args.sets) {
        Ok(o) => o,
        Err(code) => return code,
    };
    let program = match load_program(&args.file, &args.libraries.options(), Format::Text) {
        Ok(program) => program,
        Err(code) => return code,
    };
    let Ok(mechanism) = program.mechanism() else {
        return ExitCode::from(1);
    };
    let assembled = lsdc::topology::build(mechanism).and_then(|topology| {
        let options = AssemblyOptions::default();
        lsdc::studies::analysis::assembled_model_with(mechanism, topology, &options, &overrides)
    });
    let (model, report) = match assembled {
        Ok((model, report, warnings)) => {
            if !warnings.is_empty() {
                report_diagnostics(&program, &warnings, Format::Text);
            }
            (model, report)
        }
        Err(diagnostics) => {
            report_diagnostics(&program, &diagnostics, Format::Text);
            return ExitCode::from(1);
        }
    };
    let frame = match frames::resolve(mechanism, &model, &args.point) {
        Ok(frame) => frame,
        Err(message) => return usage_error(&message),
    };
    let q = report.coordinates_vector();
    let run = read_targets(args, &model, &frame, &q).and_then(|targets| match args.method {
        DragMethod::Exact => exact(args, &model, &frame, &q, &targets),
        DragMethod::Penalty => penalty_run(args, mechanism, &model, &frame, &q, &targets),
    });
    let run = match run {
        Ok(run) => run,
        Err(message) => {
            err(&format!("error: {message}\n"));
            return ExitCode::from(1);
        }
    };
    let text = match args.format {
        SampleFormat::Csv => lsdc::studies::drag::to_csv(&run),
        SampleFormat::Json => json(&run),
    };
    let written = write_output(args.out.as_deref(), &text);
    if written != ExitCode::SUCCESS {
        return written;
    }
    report_unreached(&run)
}

/// The path file's targets; a target without z takes the point's starting z.
fn read_targets(
    args: &DragArgs,
    model: &KinematicModel,
    frame: &FramePoint,
    q: &[f64],
) -> Result<Vec<lsdc::studies::drag::Target>, String> {
    let name = args.path.display().to_string();
    let text =
        std::fs::read_to_string(&args.path).map_err(|e| format!("cannot read `{name}`: {e}"))?;
    let configuration = lsdc::kinematics::forward::forward(model, q)
        .map_err(|_| "the starting configuration cannot be evaluated".to_string())?;
    let z = frame.pose(&configuration).translation.vector.z;
    parse_targets(&text, &name, z)
}

fn exact(
    args: &DragArgs,
    model: &KinematicModel,
    frame: &FramePoint,
    q: &[f64],
    targets: &[lsdc::studies::drag::Target],
) -> Result<DragRun, String> {
    let options = DragOptions {
        reach_tolerance: args.reach_tolerance,
        ..DragOptions::default()
    };
    follow_exact(model, frame, q, targets, args.mouse_stiffness, &options).map_err(|e| match e {
        DragError::Evaluation(_) => "a configuration on the path cannot be evaluated".to_string(),
        DragError::NoAssembly { loop_residual } => {
            format!("the loops cannot be closed on the path (residual {loop_residual:.3e} left)")
        }
    })
}

fn penalty_run(
    args: &DragArgs,
    mechanism: &lsdc::elab::Mechanism,
    model: &KinematicModel,
    frame: &FramePoint,
    q: &[f64],
    targets: &[lsdc::studies::drag::Target],
) -> Result<DragRun, String> {
    let names = model
        .topology
        .bodies
        .iter()
        .map(|&b| mechanism.body_name(lsdc::elab::value::BodyRef::Body(b)))
        .collect();
    let planar = penalty::planar_model(model, names)?;
    let options = PenaltyOptions {
        stiffness: Stiffness {
            link: args.link_stiffness,
            mouse: args.mouse_stiffness,
        },
        iterations: args.iterations,
        reach_tolerance: args.reach_tolerance,
    };
    follow_penalty(model, &planar, frame, q, targets, &options)
        .map_err(|_| "the starting configuration cannot be evaluated".to_string())
}

/// Says which targets were out of reach (exit 1), if any.
fn report_unreached(run: &DragRun) -> ExitCode {
    let unreached: Vec<_> = run.unreached().collect();
    let Some((first, row)) = unreached.first() else {
        return ExitCode::SUCCESS;
    };
    err(&format!(
        "warning: {} of {} targets out of reach; the first, target {} at {:?}, is left {:.3e} away\n",
        unreached.len(),
        run.rows.len(),
        first + 1,
        row.target,
        row.distance
    ));
    ExitCode::from(1)
}
