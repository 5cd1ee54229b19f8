//! `lsdc test [PATH...]`: runs the regression cases of test manifests (`lsdtest.toml`).

use std::path::PathBuf;
use std::process::ExitCode;

use super::shared::{err, json, out, usage_error, usage_error_after_results, Format};
use lsdc::testing::{self, calibrate, record, report, Case};

#[derive(clap::Args)]
pub struct TestArgs {
    /// Manifests, or folders searched for `lsdtest.toml` files (default: the current folder).
    paths: Vec<PathBuf>,
    /// Cases run at once (default: the number of processors).
    #[arg(short = 'j', long = "jobs", value_parser = clap::value_parser!(u16).range(1..))]
    jobs: Option<u16>,
    /// Only the cases whose name contains this text.
    #[arg(long)]
    case: Option<String>,
    #[arg(long, value_enum, default_value = "text")]
    format: Format,
    /// Also write the results as JUnit XML to this file.
    #[arg(long, value_name = "FILE")]
    junit: Option<PathBuf>,
    /// Re-record the references from runs, and say what moved.
    #[arg(long, conflicts_with = "calibrate")]
    update: bool,
    /// Run each case at its tolerance (or step) and a finer one, and propose tolerances.
    #[arg(long)]
    calibrate: bool,
    /// Move each number written with a decimal point in the programs by this relative amount,
    /// up or down as `--seed` decides: are the tolerances robust to round-off of the geometry?
    #[arg(long, value_name = "RELATIVE", conflicts_with_all = ["calibrate", "update"])]
    perturb: Option<f64>,
    /// The directions of `--perturb`'s moves (a different seed, other directions).
    #[arg(long, default_value_t = 1, requires = "perturb")]
    seed: u64,
}

pub fn run(args: &TestArgs) -> ExitCode {
    let mut cases = match test_cases(args) {
        Ok(cases) => cases,
        Err(message) => return usage_error(&message),
    };
    if args.calibrate || args.update {
        // Only the cases compared with a reference have one to record or tolerances to propose.
        cases.retain(|c| c.reference.is_some());
    }
    if let Some(relative) = args.perturb {
        let numbers = lsdc::elab::Perturbation {
            relative,
            seed: args.seed,
        };
        cases.iter_mut().for_each(|c| c.numbers = Some(numbers));
    }
    let jobs = (args.jobs.map(usize::from))
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, usize::from));
    let start = std::time::Instant::now();
    let outcomes = match (args.calibrate, args.update) {
        (true, _) => testing::for_each_case(&cases, jobs, |c| named(c, calibrate::calibrate(c)))
            .map(|proposals| print_each(&proposals, args.format, calibrate::as_manifest)),
        (_, true) => testing::for_each_case(&cases, jobs, |c| named(c, record::record(c)))
            .map(|recorded| print_each(&recorded, args.format, report::recorded_text)),
        _ => testing::run_all(&cases, jobs).map(|outcomes| {
            let summary = report::Summary::new(&outcomes, jobs, start.elapsed().as_secs_f64());
            print_summary(&summary, args)
        }),
    };
    outcomes.unwrap_or_else(|message| usage_error(&message))
}

/// The cases of the manifests under the paths given (the current folder by default), those
/// named by `--case` only.
fn test_cases(args: &TestArgs) -> Result<Vec<Case>, String> {
    let paths = match args.paths.is_empty() {
        true => vec![PathBuf::from(".")],
        false => args.paths.clone(),
    };
    let mut cases = testing::load(&paths).map_err(|error| error.to_string())?;
    if let Some(text) = &args.case {
        cases.retain(|c| c.name.contains(text.as_str()));
    }
    match cases.is_empty() {
        true => Err("no test case found (manifests are named `lsdtest.toml`)".into()),
        false => Ok(cases),
    }
}

/// Prints the results (text or JSON), writes the JUnit file; exit code 0 if every case passed.
fn print_summary(summary: &report::Summary, args: &TestArgs) -> ExitCode {
    match args.format {
        Format::Text => out(&report::text(summary)),
        Format::Json => out(&json(summary)),
    }
    if let Some(path) = &args.junit {
        if let Err(error) = std::fs::write(path, report::junit(summary)) {
            return usage_error_after_results(&format!(
                "cannot write `{}`: {error}",
                path.display()
            ));
        }
    }
    match summary.all_passed() {
        true => ExitCode::SUCCESS,
        false => ExitCode::from(1),
    }
}

/// An error of a case, with the case's name.
fn named<T>(case: &Case, result: Result<T, String>) -> Result<T, String> {
    result.map_err(|error| format!("{}: {error}", case.name))
}

/// Prints what `--calibrate` or `--update` made of each case (text or JSON), the cases it could
/// not be done for on standard error; exit code 1 if there was one.
fn print_each<T: serde::Serialize>(
    results: &[Result<T, String>],
    format: Format,
    text: impl Fn(&T) -> String,
) -> ExitCode {
    let done: Vec<&T> = results.iter().filter_map(|r| r.as_ref().ok()).collect();
    match format {
        Format::Text => done.iter().for_each(|d| out(&text(d))),
        Format::Json => out(&json(&done)),
    }
    let failures: Vec<&String> = results.iter().filter_map(|r| r.as_ref().err()).collect();
    failures.iter().for_each(|f| err(&format!("error: {f}\n")));
    match failures.is_empty() {
        true => ExitCode::SUCCESS,
        false => ExitCode::from(1),
    }
}
