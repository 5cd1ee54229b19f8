//! `lsdc identify FILE --data MEASURED.csv --parameters NAME...`: the parameters that enter
//! inverse dynamics linearly (bodies' inertial parameters, joints' friction) estimated from
//! measured coordinates and efforts by least squares on their base parameters, with standard
//! deviations, the condition number and the residual, as text or JSON; values of the program
//! and initial values fitted to measured quantities of whole runs by Levenberg–Marquardt.

use std::path::PathBuf;
use std::process::ExitCode;

use super::shared::LibraryArgs;
use super::shared::{
    err, json, out, parse_sets, prepare_file, report_diagnostics, usage_error, Format,
};
use lsdc::diag::Diagnostic;
use lsdc::prepare::settings::SettingsChanges;
use lsdc::studies::identify::measured::read_measured;
use lsdc::studies::identify::nonlinear::{
    identify_nonlinear, NonlinearError, NonlinearIdentification, Problem, Table,
};
use lsdc::studies::identify::parameters::{resolve, NameError};
use lsdc::studies::identify::{check_supported, identify, Identification, IdentifyError};
use lsdc::studies::motion_file::Derivation;
use lsdc::studies::sensitivity::parameters::resolve as sensitivity_parameters;

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
    /// `JOIN.damping` (viscous), by linear least squares on measured efforts; or values of the
    /// program (`L`, `mass(rod)`) and initial values (`swing.q`), by the nonlinear fit on
    /// measured quantities of the run. The others keep the program's values.
    #[arg(long, value_name = "NAME", num_args = 1.., required = true)]
    parameters: Vec<String>,
    /// The error variance of the positions (and rates) for the spline of the rates and
    /// accelerations not in the file (their units squared; 0, the default: it interpolates).
    #[arg(long, default_value_t = 0.0)]
    smoothing: f64,
    /// The runs' relative and absolute tolerance in the nonlinear fit (the program's
    /// `simulate` settings otherwise).
    #[arg(long)]
    tolerance: Option<f64>,
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
    let names = &args.parameters;
    let each: Vec<Result<_, NameError>> = (names.iter())
        .map(|name| resolve(&prepared.model, mechanism, std::slice::from_ref(name)))
        .collect();
    let nonlinear = |r: &Result<_, NameError>| {
        matches!(
            r,
            Err(NameError::ProgramUnknown { .. }) | Err(NameError::Unknown { .. })
        )
    };
    if each.iter().any(|r| r.is_err()) {
        if let Some(Err(why)) = each.iter().find(|r| r.is_err() && !nonlinear(r)) {
            return usage_error(&why.to_string());
        }
        if each.iter().any(|r| r.is_ok()) {
            let linear: Vec<String> = (names.iter().zip(&each))
                .filter(|(_, r)| r.is_ok())
                .map(|(n, _)| format!("`{n}`"))
                .collect();
            return match each.iter().find_map(|r| match r {
                Err(NameError::ProgramUnknown { name, span }) => Some((name, *span)),
                _ => None,
            }) {
                Some((name, span)) => located(
                    "E0871",
                    format!("`{name}` is fitted to measured motion by the nonlinear fit, {} to measured efforts by the linear one: `identify` does one fit at a time", linear.join(", ")),
                    span,
                    "declared here",
                    "ask for the program's values and initial values (`L`, `swing.q`) in one `identify`, for bodies' inertial parameters and joints' friction in another",
                ),
                None => match each.iter().find(|r| r.is_err()) {
                    Some(Err(why)) => usage_error(&why.to_string()),
                    _ => usage_error("`--parameters`: mixed parameters"),
                },
            };
        }
        return identify_nonlinear_run(args, &program, mechanism, &each);
    }
    if let Err(IdentifyError::Unsupported { what, span }) =
        check_supported(&prepared.model, mechanism)
    {
        return located(
            "E0870",
            what,
            span,
            "not identified",
            "identify a tree of joints of their own coordinates (revolute, prismatic), or a mechanism whose ball joints are on closed loops",
        );
    }
    let asked = match resolve(&prepared.model, mechanism, &args.parameters) {
        Ok(asked) => asked,
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

/// The nonlinear fit of values of the program and initial values (`each`: the linear fit's
/// refusal of each name) to the quantities of the file.
fn identify_nonlinear_run(
    args: &IdentifyArgs,
    program: &lsdc::api::Program,
    mechanism: &lsdc::elab::Mechanism,
    each: &[Result<lsdc::studies::identify::parameters::Asked, NameError>],
) -> ExitCode {
    let overrides = match parse_sets(&args.sets) {
        Ok(overrides) => overrides,
        Err(code) => return code,
    };
    if let Err(diagnostics) = sensitivity_parameters(mechanism, &overrides, &args.parameters) {
        // A name neither fit knows: the linear fit's suggestion, as before the nonlinear one.
        if let Some(Err(why @ NameError::Unknown { .. })) = each.iter().find(|r| r.is_err()) {
            return usage_error(&why.to_string());
        }
        report_diagnostics(program, &diagnostics, args.format);
        return ExitCode::from(1);
    }
    if args.tolerance.is_some_and(|t| !(t.is_finite() && t > 0.0)) {
        return usage_error("`--tolerance` must be positive");
    }
    let text = match std::fs::read_to_string(&args.data) {
        Ok(text) => text,
        Err(e) => return usage_error(&format!("cannot read `{}`: {e}", args.data.display())),
    };
    let file = args.data.display().to_string();
    let table = match Table::read(&text, &file) {
        Ok(table) => table,
        Err(why) => return usage_error(&why),
    };
    let changes = SettingsChanges {
        tolerance: args.tolerance,
        ..Default::default()
    };
    let problem = Problem {
        mechanism,
        overrides: &overrides,
        changes: &changes,
        names: &args.parameters,
    };
    let identification = match identify_nonlinear(&problem, &table) {
        Ok(identification) => identification,
        Err(NonlinearError::Program(diagnostics)) => {
            report_diagnostics(program, &diagnostics, args.format);
            return ExitCode::from(1);
        }
        Err(why @ NonlinearError::Usage(_)) => return usage_error(&why.to_string()),
        Err(why) => return usage_error(&format!("{file}: {why}")),
    };
    match args.format {
        Format::Json => out(&json(&identification)),
        Format::Text => out(&nonlinear_text(&identification)),
    }
    ExitCode::SUCCESS
}

/// The nonlinear fit's estimates as a table, then the condition, the residual and the cost.
fn nonlinear_text(identification: &NonlinearIdentification) -> String {
    let width = (identification.parameters.iter())
        .map(|e| e.name.chars().count())
        .max()
        .unwrap_or(9)
        .max(9);
    let mut text = format!(
        "{:width$}  {:>13}  {:>10}  {:>13}\n",
        "parameter", "estimate", "std", "start"
    );
    for e in &identification.parameters {
        text += &format!(
            "{:width$}  {:>13.6e}  {:>10.3e}  {:>13.6e}\n",
            e.name, e.value, e.std, e.model
        );
    }
    let residual = &identification.residual;
    let fitted: Vec<String> = identification
        .fitted
        .iter()
        .map(|n| format!("`{n}`"))
        .collect();
    text += &format!(
        "fitted to {} at {} samples ({} equations); condition number {:.3e}; residual rms {:.3e} ({:.3e} of the measurements), σ {:.3e}; {} steps, {} runs\n",
        fitted.join(", "),
        identification.samples,
        identification.equations,
        identification.condition,
        residual.rms,
        residual.relative,
        residual.sigma,
        identification.iterations,
        identification.runs,
    );
    text
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
