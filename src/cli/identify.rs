//! `lsdc identify FILE --data MEASURED.csv --parameters NAME...`: the parameters that enter
//! inverse dynamics linearly (bodies' inertial parameters, joints' friction) estimated from
//! measured coordinates and efforts by least squares on their base parameters, with standard
//! deviations, the condition number and the residual, as text or JSON.

use std::path::PathBuf;
use std::process::ExitCode;

use super::shared::LibraryArgs;
use super::shared::{err, json, out, prepare_file, report_diagnostics, usage_error, Format};
use lsdc::diag::Diagnostic;
use lsdc::studies::identify::measured::read_measured;
use lsdc::studies::identify::parameters::{resolve, NameError};
use lsdc::studies::identify::{check_supported, identify, Identification, IdentifyError};
use lsdc::studies::motion_file::Derivation;

#[derive(clap::Args)]
pub struct IdentifyArgs {
    file: PathBuf,
    #[command(flatten)]
    libraries: LibraryArgs,
    /// Value of an unknown, as for `simulate`. Repeatable.
    #[arg(long = "set", value_name = "NAME=VALUE")]
    sets: Vec<String>,
    /// The measurements: `time`, every coordinate's positions (`elbow.q`), optionally its rates
    /// (`elbow.q'`) and accelerations (`elbow.q''`), and the measured efforts
    /// (`elbow.drive_effort`), as `lsdc simulate` and `lsdc inverse` write them.
    #[arg(long, value_name = "MEASURED.csv")]
    data: PathBuf,
    /// The parameters to estimate: `BODY.mass`, `BODY.mx` … `BODY.mz`, `BODY.Ixx` …
    /// `BODY.Izz` (about the body frame's origin), `BODY` for all ten, `JOIN.friction` (dry),
    /// `JOIN.damping` (viscous). The others keep the program's values.
    #[arg(long, value_name = "NAME", num_args = 1.., required = true)]
    parameters: Vec<String>,
    /// The error variance of the positions (and rates) for the spline of the rates and
    /// accelerations not in the file (their units squared; 0, the default: it interpolates).
    #[arg(long, default_value_t = 0.0)]
    smoothing: f64,
    #[arg(long, value_enum, default_value = "text")]
    format: Format,
}

pub fn run(args: &IdentifyArgs) -> ExitCode {
    let (program, prepared) =
        match prepare_file(&args.file, &args.libraries, &args.sets, args.format) {
            Ok(prepared) => prepared,
            Err(code) => return code,
        };
    let Ok(mechanism) = program.mechanism() else {
        return usage_error("the program has no mechanism");
    };
    let located = |code: &'static str, message: String, span, label: &str, help: &str| {
        let diagnostic = Diagnostic::error(code, message)
            .primary(span, label)
            .help(help);
        report_diagnostics(&program, &[diagnostic], args.format);
        ExitCode::from(1)
    };
    if let Err(IdentifyError::Unsupported { what, span }) =
        check_supported(&prepared.model, mechanism)
    {
        return located(
            "E0870",
            what,
            span,
            "not identified",
            "identify a tree of revolute and prismatic joints (joints of their own coordinates)",
        );
    }
    let asked = match resolve(&prepared.model, mechanism, &args.parameters) {
        Ok(asked) => asked,
        Err(NameError::ProgramUnknown { name, span }) => {
            return located(
                "E0871",
                format!("`{name}` may enter the dynamics nonlinearly: `identify` fits parameters that enter linearly"),
                span,
                "declared here",
                "ask for a body's inertial parameters (`BODY.mass`, `BODY.mx`, `BODY.Ixx`, …) or a joint's `friction` and `damping`; a nonlinear fit (Levenberg–Marquardt on the sensitivities of a run) is not available yet",
            )
        }
        Err(why) => return usage_error(&why.to_string()),
    };
    if !(args.smoothing.is_finite() && args.smoothing >= 0.0) {
        return usage_error("`--smoothing` must be 0 or positive");
    }
    let text = match std::fs::read_to_string(&args.data) {
        Ok(text) => text,
        Err(e) => return usage_error(&format!("cannot read `{}`: {e}", args.data.display())),
    };
    let file = args.data.display().to_string();
    let measured = match read_measured(&text, &file, &prepared.model, args.smoothing) {
        Ok(measured) => measured,
        Err(why) => return usage_error(&why),
    };
    let identification = match identify(&prepared, &measured, &asked) {
        Ok(identification) => identification,
        Err(why) => return usage_error(&format!("{file}: {why}")),
    };
    match args.format {
        Format::Json => out(&json(&identification)),
        Format::Text => {
            note_splines(&identification, args.smoothing);
            out(&as_text(&identification));
        }
    }
    ExitCode::SUCCESS
}

/// Says on standard error which rates and accelerations come from the spline.
fn note_splines(identification: &Identification, smoothing: f64) {
    let splined: Vec<String> = (identification.derivatives.iter())
        .filter(|(_, r, a)| *r == Derivation::Spline || *a == Derivation::Spline)
        .map(|(name, _, _)| format!("`{name}`"))
        .collect();
    if !splined.is_empty() {
        err(&format!(
            "note: the rates or accelerations of {} are those of a quintic spline (error variance {smoothing})\n",
            splined.join(", ")
        ));
    }
}

/// The estimates as a table, then the folded parameters, the condition and the residual.
fn as_text(identification: &Identification) -> String {
    let (estimates, folded) = &identification.parameters;
    let label = |e: &lsdc::studies::identify::Estimate| {
        e.combination.clone().unwrap_or_else(|| e.name.clone())
    };
    let width = estimates
        .iter()
        .map(|e| label(e).chars().count())
        .max()
        .unwrap_or(9)
        .max(9);
    let mut text = format!(
        "{:width$}  {:>13}  {:>10}  {:>13}\n",
        "parameter", "estimate", "std", "program"
    );
    for e in estimates {
        text += &format!(
            "{:width$}  {:>13.6e}  {:>10.3e}  {:>13.6e}\n",
            label(e),
            e.value,
            e.std,
            e.model
        );
    }
    for f in folded {
        text += &format!(
            "`{}` is identifiable only in the combinations of {}\n",
            f.name,
            (f.folded_into.iter())
                .map(|n| format!("`{n}`"))
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    if !identification.without_effect.is_empty() {
        text += &format!(
            "without effect on the measured efforts, not estimated: {}\n",
            (identification.without_effect.iter())
                .map(|n| format!("`{n}`"))
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    let residual = &identification.residual;
    text += &format!(
        "{} samples, {} equations, {} base parameters; condition number {:.3e}; residual rms {:.3e} ({:.3e} of the efforts), σ {:.3e}\n",
        identification.samples,
        identification.equations,
        estimates.len(),
        identification.condition,
        residual.rms,
        residual.relative,
        residual.sigma
    );
    text
}
