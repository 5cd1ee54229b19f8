//! `lsdc kinematics FILE --actuate JOIN.COORDINATE... --point FRAME`: the velocity and
//! acceleration models (direct and inverse), their conditioning and the singularity at the
//! initial configuration or at given ones (`--at`), or the singular passages along a run or a
//! drag (`--along`).

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use super::shared::{
    err, json, out, prepare_kinematics_file, refuse_imposed_motion, usage_error, Format,
    LibraryArgs,
};
use lsdc::prepare::Prepared;
use lsdc::studies::configurations::{self, Declared};
use lsdc::studies::kinematic_models::{
    actuation, models_at, Actuation, KinematicModels, Output, OutputKind, Rows, SINGULAR_TOLERANCE,
};
use lsdc::studies::singular_points::{find, SearchOutcome, SingularPoints};
use lsdc::studies::singularities::{scan, Scan};

#[derive(clap::Args)]
#[command(group(clap::ArgGroup::new("output").required(true).args(["point", "frame"])))]
pub struct KinematicsArgs {
    file: PathBuf,
    #[command(flatten)]
    libraries: LibraryArgs,
    /// Value of an unknown, as for `simulate`. Repeatable.
    #[arg(long = "set", value_name = "NAME=VALUE")]
    sets: Vec<String>,
    /// An actuated (or chosen) coordinate, `join.coordinate` (repeatable; for a tree, every
    /// coordinate without it).
    #[arg(long = "actuate", value_name = "JOIN.COORDINATE")]
    actuated: Vec<String>,
    /// The models map to the velocity of this frame's origin (a frame the program names, or a
    /// body).
    #[arg(long, value_name = "FRAME")]
    point: Option<String>,
    /// The models map to this frame's twist (angular velocity, then its origin's velocity).
    #[arg(long, value_name = "FRAME")]
    frame: Option<String>,
    /// JSON file of configurations: {"states": [{"coordinates": {"A1.q": 0.7}, "rates":
    /// {"A1.q": 0.1}}, {"point": [0, 0, -0.3]}]}.
    #[arg(long, value_name = "FILE", conflicts_with = "along")]
    at: Option<PathBuf>,
    /// CSV of samples of a run (`lsdc simulate`) or a drag (`lsdc drag`): the singular
    /// passages along them.
    #[arg(long, value_name = "FILE")]
    along: Option<PathBuf>,
    /// Search for the singular points of the inverse geometric model (where the point held
    /// leaves an actuator free), from each configuration of `--at` (or the initial one).
    #[arg(long, conflicts_with = "along")]
    find_singular: bool,
    /// A configuration is singular where a measure falls below this.
    #[arg(long, default_value_t = SINGULAR_TOLERANCE)]
    tolerance: f64,
    #[arg(long, value_enum, default_value = "text")]
    format: Format,
}

pub fn run(args: &KinematicsArgs) -> ExitCode {
    if !(args.tolerance.is_finite() && args.tolerance > 0.0) {
        return usage_error("`--tolerance` must be positive");
    }
    let (program, prepared) =
        match prepare_kinematics_file(&args.file, &args.libraries, &args.sets, args.format) {
            Ok(prepared) => prepared,
            Err(code) => return code,
        };
    let help = "its models take every coordinate as free to move: leave the motion free (remove the drive, or the time from the dof chain) and name the coordinate with --actuate";
    if let Err(code) = refuse_imposed_motion(&program, "`lsdc kinematics`", help, args.format) {
        return code;
    }
    let Ok(mechanism) = program.mechanism() else {
        return ExitCode::from(1);
    };
    let (name, kind) = match (&args.point, &args.frame) {
        (Some(point), _) => (point, OutputKind::Point),
        (None, Some(frame)) => (frame, OutputKind::Twist),
        (None, None) => return usage_error("give `--point FRAME` or `--frame FRAME`"),
    };
    let frame = match lsdc::kinematics::frames::resolve(mechanism, &prepared.kinematics, name) {
        Ok(frame) => frame,
        Err(message) => return usage_error(&message),
    };
    let output = Output { frame, kind };
    let actuation = match actuation(&prepared, &args.actuated) {
        Ok(actuation) => actuation,
        Err(error) => return usage_error(&error.to_string()),
    };
    if let Some(along) = &args.along {
        let samples = match read(along).and_then(|text| {
            configurations::read_samples(&prepared, &text, &along.display().to_string())
        }) {
            Ok(samples) => samples,
            Err(message) => return usage_error(&message),
        };
        return match scan(
            &prepared.model,
            &actuation,
            &output,
            &samples,
            args.tolerance,
        ) {
            Ok(scan) => {
                match args.format {
                    Format::Text => out(&scan_text(&scan)),
                    Format::Json => out(&json(&scan)),
                }
                ExitCode::SUCCESS
            }
            Err(error) => failed(&error.to_string()),
        };
    }
    let configurations = match &args.at {
        None => initial(&prepared),
        Some(path) => read(path).and_then(|text| {
            let requests = configurations::parse_requests(&text)
                .map_err(|e| format!("cannot read states from `{}`: {e}", path.display()))?;
            Ok(requests
                .iter()
                .map(|request| configurations::close(&prepared, request, &output.frame))
                .collect())
        }),
    };
    let configurations = match configurations {
        Ok(c) => c,
        Err(message) => return usage_error(&message),
    };
    if args.find_singular {
        if output.kind != OutputKind::Point {
            return usage_error(
                "`--find-singular` looks for positions of a point: give `--point FRAME`",
            );
        }
        let found = find(
            &prepared,
            &actuation,
            &output,
            &configurations,
            args.tolerance,
        );
        match args.format {
            Format::Text => out(&singular_points_text(&found)),
            Format::Json => out(&json(&found)),
        }
        return ExitCode::SUCCESS;
    }
    let mut results = Vec::new();
    for (index, configuration) in configurations.into_iter().enumerate() {
        let models = configuration.and_then(|declared| {
            evaluate(&prepared, &actuation, &output, &declared, args.tolerance)
                .map_err(|e| e.to_string())
        });
        match models {
            Ok(models) => results.push(models),
            Err(message) => return failed(&format!("state {index}: {message}")),
        }
    }
    match args.format {
        Format::Text => out(&results
            .iter()
            .map(models_text)
            .collect::<Vec<_>>()
            .join("\n")),
        Format::Json => out(&json(&serde_json::json!({ "configurations": results }))),
    }
    ExitCode::SUCCESS
}

fn read(path: &Path) -> Result<String, String> {
    std::fs::read_to_string(path).map_err(|e| format!("cannot read `{}`: {e}", path.display()))
}

fn failed(message: &str) -> ExitCode {
    err(&format!("error: {message}\n"));
    ExitCode::from(1)
}

/// The program's initial configuration, with its initial rates.
fn initial(prepared: &Prepared) -> Result<Vec<Result<Declared, String>>, String> {
    Ok(vec![Ok(Declared {
        coordinates: prepared.coordinates.clone(),
        rates: prepared.rates.clone(),
        time: 0.0,
    })])
}

/// The models at a closed configuration, the actuated coordinates at their declared rates.
fn evaluate(
    prepared: &Prepared,
    actuation: &Actuation,
    output: &Output,
    declared: &Declared,
    tolerance: f64,
) -> Result<KinematicModels, lsdc::studies::kinematic_models::KinematicsError> {
    let model = &prepared.model;
    let (q, v) = model.state_from_declared(&declared.coordinates, &declared.rates)?;
    let rates: Vec<f64> = actuation.velocities.iter().map(|&i| v[i]).collect();
    models_at(model, actuation, output, &q, &rates, tolerance)
}

fn matrix_text(title: &str, rows: &Rows, row_names: &[String], column_names: &[String]) -> String {
    let mut text = format!("{title}\n{:>16}", "");
    for name in column_names {
        text += &format!(" {name:>16}");
    }
    text += "\n";
    for (row, name) in rows.iter().zip(row_names) {
        text += &format!("{name:>16}");
        for value in row {
            text += &format!(" {value:>16.9e}");
        }
        text += "\n";
    }
    text
}

fn vector_text(title: &str, values: &[f64], names: &[String]) -> String {
    let mut text = format!("{title}\n");
    for (name, value) in names.iter().zip(values) {
        text += &format!("{name:>16} {value:>16.9e}\n");
    }
    text
}

fn condition_text(condition: Option<f64>) -> String {
    condition.map_or("infinite".to_string(), |c| format!("{c:.6e}"))
}

fn models_text(m: &KinematicModels) -> String {
    let mut text = format!(
        "motions allowed: {} ({} idle); characteristic length L = {:.6e} m\n",
        m.motions, m.idle_motions, m.characteristic_length
    );
    text += &matrix_text(
        "direct velocity model (MCD): frame motion = J · actuated rates",
        &m.direct,
        &m.outputs,
        &m.actuated,
    );
    text += &matrix_text(
        "inverse velocity model (MCI): actuated rates = J⁻¹ · frame motion",
        &m.inverse,
        &m.actuated,
        &m.outputs,
    );
    text += &format!(
        "condition numbers (lengths in L): direct {}, inverse {}\n",
        condition_text(m.direct_condition),
        condition_text(m.inverse_condition)
    );
    text += &vector_text("actuated rates", &m.actuated_rates, &m.actuated);
    text += &vector_text("frame motion at these rates", &m.output_rates, &m.outputs);
    text += &vector_text(
        "direct acceleration model (MAD): frame acceleration = J · ä + term",
        &m.direct_acceleration_term,
        &m.outputs,
    );
    text += &vector_text(
        "inverse acceleration model (MAI): ä = J⁻¹ · frame acceleration + term",
        &m.inverse_acceleration_term,
        &m.actuated,
    );
    let s = &m.singularity;
    text += &format!(
        "singularity measures (0 when singular, tolerance {:.1e}): type 1 {:.6e}, type 2 {:.6e}\n",
        s.tolerance, s.type1_measure, s.type2_measure
    );
    match s.kind {
        None => text += "not singular\n",
        Some(kind) => text += &format!("singular: {}\n", kind.describe()),
    }
    for (label, motion) in [("type 1", &s.type1_motion), ("type 2", &s.type2_motion)] {
        if let Some(motion) = motion {
            text += &format!(
                "  {label} motion moves {}{}\n",
                motion.coordinates.join(", "),
                if motion.loops.is_empty() {
                    String::new()
                } else {
                    format!(" (loops {})", motion.loops.join(", "))
                }
            );
        }
    }
    text
}

fn scan_text(scan: &Scan) -> String {
    let mut text = format!(
        "{} samples; singular passages (a measure below {:.1e}): {}\n",
        scan.samples.len(),
        scan.tolerance,
        scan.events.len()
    );
    for event in &scan.events {
        text += &format!(
            "t = {:.6} {} (measure {:.3e}, {:.3e} at the nearest sample)",
            event.time,
            event.kind.describe(),
            event.measure,
            event.sampled_measure
        );
        if let Some(motion) = &event.motion {
            text += &format!(": moves {}", motion.coordinates.join(", "));
            if !motion.loops.is_empty() {
                text += &format!(" (loops {})", motion.loops.join(", "));
            }
        }
        text += "\n";
    }
    text
}

fn singular_points_text(found: &SingularPoints) -> String {
    let mut text = format!(
        "singular points of the inverse geometric model of `{}` ({} seeds): {}\n",
        found.point,
        found.searches.len(),
        found.points.len()
    );
    for p in &found.points {
        text += &format!(
            "  ({:.9}, {:.9}, {:.9}) m: {}; {} = ({}); measures {:.1e} (second order {:.1e}), type 2 {:.1e}",
            p.point[0],
            p.point[1],
            p.point[2],
            p.kind.map_or("not classified singular", |k| k.describe()),
            found.actuated.join(", "),
            (p.actuated.iter().map(|a| format!("{a:.6}")))
                .collect::<Vec<_>>()
                .join(", "),
            p.type1_measure,
            p.second_order,
            p.type2_measure
        );
        if let Some(motion) = &p.motion {
            text += &format!("; the point held, moves {}", motion.coordinates.join(", "));
        }
        text += "\n";
    }
    for search in &found.searches {
        if let SearchOutcome::NotFound { seed, reason, .. } = search {
            text += &format!("  seed {seed}: {reason}\n");
        }
    }
    text
}
