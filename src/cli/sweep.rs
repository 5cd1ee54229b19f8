//! `lsdc sweep FILE`: the program run over a grid (`--grid`), a list (`--values`) or a sample
//! (`--vary` with `--sample`) of initial values and values of the program, in one process on
//! every core; a row per run (CSV or Parquet, `-o`), every sample with `--samples`, a journal
//! to `--resume` from, `--shard K/N` for a job array. `lsdc sweep gather PART... -o FILE` merges
//! the shards' files.

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

use clap::ValueEnum;

use super::shared::{
    err, json, load_program, parse_sets, refuse_sampled, report_diagnostics, usage_error, warn,
    Format, LibraryArgs,
};
use super::simulate::{interrupt_on_signals, RunSettingsArgs};
use lsdc::api::Program;
use lsdc::studies::sweep::design::{self, Design, GridAxis, Sampling};
use lsdc::studies::sweep::distribution::Distribution;
use lsdc::studies::sweep::record::{runs_table, samples_table, Status};
use lsdc::studies::sweep::runs::{PrepareError, Stop, Sweep};
use lsdc::studies::sweep::table::TableFormat;
use lsdc::studies::sweep::{self, journal, Execution, Outcome, Shard};

#[derive(clap::Args)]
#[command(args_conflicts_with_subcommands = true, subcommand_negates_reqs = true)]
pub struct SweepArgs {
    #[command(subcommand)]
    command: Option<SweepCommand>,
    #[command(flatten)]
    run: RunArgs,
}

#[derive(clap::Subcommand)]
enum SweepCommand {
    /// Merge the files of a sweep's shards (`--shard K/N` parts' `-o` files, or their
    /// `--samples` files) into the file of the whole sweep, identical to the one an unsharded
    /// sweep writes.
    Gather(GatherArgs),
}

#[derive(clap::Args)]
struct GatherArgs {
    /// The parts' files, in any order (`.csv` or `.parquet`, mixed as they may be).
    #[arg(required = true)]
    parts: Vec<PathBuf>,
    /// The merged file: Parquet when its name ends in `.parquet`, else CSV.
    #[arg(short = 'o', long = "out", required = true)]
    out: PathBuf,
}

#[derive(clap::Args)]
struct RunArgs {
    #[arg(required = true)]
    file: Option<PathBuf>,
    #[command(flatten)]
    libraries: LibraryArgs,
    /// A value every run takes (an unknown or generic quantity, as `lsdc simulate --set`).
    /// Repeatable.
    #[arg(long = "set", value_name = "NAME=VALUE")]
    sets: Vec<String>,
    /// An axis of a grid: COUNT values from FROM to TO (both included) of an initial value
    /// (`swing.q`, a rate `swing.q'`) or a value of the program (`--set`'s names). Repeatable:
    /// every combination, the first axis varying slowest.
    #[arg(long = "grid", value_name = "NAME=FROM:TO:COUNT", conflicts_with_all = ["values", "vary"])]
    grid: Vec<String>,
    /// The runs as a CSV file: a header of names, a row of numbers per run.
    #[arg(long = "values", value_name = "FILE", conflicts_with = "vary")]
    values: Option<PathBuf>,
    /// A name sampled from a distribution: `uniform(LOW, HIGH)`, `normal(MEAN, SD)` or
    /// `truncnormal(MEAN, SD, LOW, HIGH)`. Repeatable; needs `--sample`.
    #[arg(long = "vary", value_name = "NAME=DISTRIBUTION", requires = "sample")]
    vary: Vec<String>,
    /// The number of runs of a sample.
    #[arg(long = "sample", value_name = "N", requires = "vary")]
    sample: Option<usize>,
    /// How a sample covers its distributions: independent draws, a Latin hypercube, or a
    /// scrambled Sobol sequence.
    #[arg(long, value_enum, default_value = "random")]
    design: DesignArg,
    /// The seed of a sample's design: the same seed, the same runs.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// The program's `simulate` declaration changed for every run, as `lsdc simulate` changes it.
    #[command(flatten)]
    run: RunSettingsArgs,
    /// Evaluate a planar mechanism in planar form (as `lsdc simulate --planar`).
    #[arg(long)]
    planar: bool,
    /// Evaluate the equations of motion as native code (as `lsdc simulate --compiled`),
    /// compiled once for every run: where the runs share one prepared mechanism (only initial
    /// values vary). Elsewhere, or where it cannot serve, a warning says why and the runs go on
    /// without it.
    #[arg(long)]
    compiled: bool,
    /// The results, a row per run: Parquet when the name ends in `.parquet`, else CSV.
    /// Without it, CSV on standard output.
    #[arg(short = 'o', long = "out")]
    out: Option<PathBuf>,
    /// Every sample of every run to this file (`.parquet` or CSV): `run`, `time`, then the
    /// quantities.
    #[arg(long, value_name = "FILE")]
    samples: Option<PathBuf>,
    /// Run only the K-th of N deterministic parts of the runs (1 ≤ K ≤ N), for a job array;
    /// `lsdc sweep gather` merges the parts' files.
    #[arg(long, value_name = "K/N")]
    shard: Option<String>,
    /// With `--shard`: K counts from 0 (a Kubernetes Indexed Job's `JOB_COMPLETION_INDEX`).
    #[arg(long, requires = "shard")]
    shard_from_zero: bool,
    /// Go on with an interrupted sweep: the runs in the journal beside `-o` (`FILE.journal`)
    /// are not done again.
    #[arg(long, requires = "out")]
    resume: bool,
    /// Threads running runs (default: every core).
    #[arg(short = 'j', long = "jobs", value_name = "N")]
    jobs: Option<usize>,
    /// Start at most N runs in this process, then stop as an interruption does (exit code 3,
    /// the journal kept for `--resume`): a sweep split over time-limited slots.
    #[arg(long, value_name = "N", requires = "out")]
    max_runs: Option<usize>,
    /// Format of the summary on standard error.
    #[arg(long, value_enum, default_value = "text")]
    report: Format,
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum DesignArg {
    Random,
    Latin,
    Sobol,
}

/// The exit code of a sweep stopped by `--max-runs` before its end.
const STOPPED_BY_RUN_LIMIT: u8 = 3;

pub fn run(args: &SweepArgs) -> ExitCode {
    match &args.command {
        Some(SweepCommand::Gather(gather)) => run_gather(gather),
        None => run_sweep(&args.run),
    }
}

fn run_gather(args: &GatherArgs) -> ExitCode {
    let gathered = match sweep::gather(&args.parts) {
        Ok(gathered) => gathered,
        Err(why) => return usage_error(&format!("cannot gather: {why}")),
    };
    if let Err(why) = gathered.table.write(&args.out, TableFormat::of(&args.out)) {
        return usage_error(&format!("cannot write `{}`: {why}", args.out.display()));
    }
    let what = if gathered.samples { "samples" } else { "runs" };
    if !super::shared::quiet() {
        err(&format!(
            "gathered {} rows of {what} from {} parts into `{}`\n",
            gathered.table.row_count(),
            args.parts.len(),
            args.out.display()
        ));
    }
    ExitCode::SUCCESS
}

/// The design the arguments describe.
fn read_design(args: &RunArgs) -> Result<Design, String> {
    if !args.grid.is_empty() {
        let axes = args
            .grid
            .iter()
            .map(|a| GridAxis::parse(a))
            .collect::<Result<Vec<_>, _>>()?;
        return Ok(design::grid(&axes));
    }
    if let Some(path) = &args.values {
        let text = std::fs::read_to_string(path)
            .map_err(|e| format!("cannot read `{}`: {e}", path.display()))?;
        return design::list(&text)
            .map_err(|e| format!("{}:{}:{}: {}", path.display(), e.line, e.column, e.message));
    }
    if let Some(count) = args.sample {
        let variables = (args.vary.iter())
            .map(|text| {
                let (name, distribution) = text
                    .split_once('=')
                    .ok_or_else(|| format!("`--vary {text}`: write NAME=DISTRIBUTION, for example `L=normal(0.3, 0.001)`"))?;
                let distribution = Distribution::parse(distribution).map_err(|why| format!("`--vary {text}`: {why}"))?;
                Ok((name.trim().to_string(), distribution))
            })
            .collect::<Result<Vec<_>, String>>()?;
        let sampling = match args.design {
            DesignArg::Random => Sampling::MonteCarlo,
            DesignArg::Latin => Sampling::LatinHypercube,
            DesignArg::Sobol => Sampling::Sobol,
        };
        return design::sample(&variables, count, sampling, args.seed);
    }
    Err("no runs: give a grid (`--grid NAME=FROM:TO:COUNT`), a list (`--values runs.csv`) or a sample (`--vary NAME=DISTRIBUTION --sample N`)".to_string())
}

fn take_planar(prepared: &mut lsdc::api::Prepared) {
    // A mechanism that is not planar keeps its spatial form, as `simulate --planar` does (the
    // warning is said once, before the runs).
    let _ = prepared.take_planar();
}

fn keep_spatial(_: &mut lsdc::api::Prepared) {}

fn run_sweep(args: &RunArgs) -> ExitCode {
    let Some(file) = &args.file else {
        return usage_error("no program to sweep: `lsdc sweep FILE ...`");
    };
    let design = match read_design(args) {
        Ok(design) => design,
        Err(why) => return usage_error(&why),
    };
    let shard = match &args.shard {
        Some(text) => match Shard::parse(text, args.shard_from_zero) {
            Ok(shard) => shard,
            Err(why) => return usage_error(&why),
        },
        None => Shard::WHOLE,
    };
    if args.jobs == Some(0) {
        return usage_error("`--jobs 0`: give at least one thread");
    }
    let overrides = match parse_sets(&args.sets) {
        Ok(overrides) => overrides,
        Err(code) => return code,
    };
    let program = match load_program(file, &args.libraries.options(), args.report) {
        Ok(program) => program,
        Err(code) => return code,
    };
    let Ok(mechanism) = program.mechanism() else {
        return ExitCode::from(1);
    };
    let adjust = if args.planar {
        take_planar
    } else {
        keep_spatial
    };
    let sweep = Sweep::new(
        mechanism,
        overrides,
        args.run.changes(),
        design,
        args.samples.is_some(),
        adjust,
    );
    let mut sweep = match sweep {
        Ok(sweep) => sweep,
        Err(PrepareError::Program(diagnostics)) => {
            report_diagnostics(&program, &diagnostics, args.report);
            return ExitCode::from(1);
        }
        Err(PrepareError::Settings(why)) => return usage_error(&why),
    };
    // Why native code does not serve is said before the runs in text, in the summary in JSON.
    let mut warnings = Vec::new();
    if args.compiled {
        if let Some(shared) = sweep.shared() {
            let help = "sweep without --compiled: the runs land on every sampling instant";
            let refused = refuse_sampled(&program, shared, "`sweep --compiled`", help, args.report);
            if let Err(code) = refused {
                return code;
            }
        }
        warnings = sweep.attach_native();
        if matches!(args.report, Format::Text) {
            report_diagnostics(&program, &warnings, Format::Text);
        }
    }
    let stop = Stop::new(interrupt_on_signals(), args.max_runs);
    let execution = Execution {
        shard,
        journal: args.out.as_deref().map(journal::path_for),
        resume: args.resume,
        threads: args.jobs,
        stop: &stop,
        context: context(&program, args),
    };
    if let (Some(path), false) = (&execution.journal, args.resume) {
        if path.exists() {
            warn(&format!(
                "`{}` holds an interrupted sweep: started again (`--resume` goes on with it)",
                path.display()
            ));
        }
    }
    let (started, cpu_before) = (Instant::now(), lsdc::simulate::clock::process_cpu_seconds());
    let bar = progress_bar();
    let outcome = sweep::execute(&sweep, &execution, &mut |done, total| {
        if let Some(bar) = &bar {
            bar.set_length(total as u64);
            bar.set_position(done as u64);
        }
    });
    if let Some(bar) = bar {
        bar.finish_and_clear();
    }
    let outcome = match outcome {
        Ok(outcome) => outcome,
        Err(why) => return usage_error(&why),
    };
    let cpu = lsdc::simulate::clock::process_cpu_seconds()
        .zip(cpu_before)
        .map(|(a, b)| a - b);
    let written = match outcome.complete() {
        true => write_results(args, &sweep, &outcome),
        false => Ok(()),
    };
    let summary = Summary {
        outcome: &outcome,
        total: sweep.run_count(),
        shared: sweep.is_shared(),
        cpu_seconds: cpu,
        wall_seconds: started.elapsed().as_secs_f64(),
        signal: stop.signal(),
        warnings: (!warnings.is_empty())
            .then(|| lsdc::diag::render::to_json_value(program.sources(), &warnings)),
    };
    summary.print(args);
    if let Err(why) = written {
        return usage_error(&why);
    }
    match (outcome.complete(), stop.signal()) {
        (true, _) => ExitCode::SUCCESS,
        (false, Some(signal)) => ExitCode::from((128 + signal).min(255) as u8),
        (false, None) => ExitCode::from(STOPPED_BY_RUN_LIMIT),
    }
}

/// What the journal must match besides the design: the program's text and the options that
/// change a run.
fn context(program: &Program, args: &RunArgs) -> String {
    let sources: Vec<u8> = (program.sources().files())
        .flat_map(|(_, file)| file.name.bytes().chain(file.text.bytes()))
        .collect();
    format!(
        "program {:016x}; set {:?}; integrator {:?}; duration {:?}; every {:?}; tolerance {:?}; step {:?}; max_steps {}; planar {}; compiled {}; scene {:?}",
        journal::digest(&sources),
        args.sets,
        args.run.integrator.map(|i| i.name()),
        args.run.duration,
        args.run.output_interval,
        args.run.tolerance,
        args.run.step,
        args.run.max_steps,
        args.planar,
        args.compiled,
        args.libraries.scene(),
    )
}

/// Writes the runs' table (and the samples') of a complete sweep: to a file written whole
/// then renamed into place, or CSV on standard output.
fn write_results(args: &RunArgs, sweep: &Sweep<'_>, outcome: &Outcome) -> Result<(), String> {
    let runs = runs_table(&sweep.design.names, &sweep.quantity_names, &outcome.records);
    match &args.out {
        Some(path) => write_table(&runs, path)?,
        None => super::shared::out(&runs.to_csv()),
    }
    if let Some(path) = &args.samples {
        write_table(
            &samples_table(&sweep.quantity_names, &outcome.records),
            path,
        )?;
    }
    Ok(())
}

fn write_table(table: &sweep::table::Table, path: &std::path::Path) -> Result<(), String> {
    // Written beside the file, then renamed: a reader never sees half a file.
    let mut partial = path.as_os_str().to_owned();
    partial.push(".partial");
    let partial = PathBuf::from(partial);
    let cannot = |why: String| format!("cannot write `{}`: {why}", path.display());
    // The format is the final name's: the partial file's name ends in `.partial`.
    table
        .write(&partial, TableFormat::of(path))
        .map_err(cannot)?;
    std::fs::rename(&partial, path).map_err(|e| cannot(e.to_string()))
}

/// A progress bar over the runs on a terminal; nothing when standard error is not one.
fn progress_bar() -> Option<indicatif::ProgressBar> {
    use std::io::IsTerminal;
    if !std::io::stderr().is_terminal() {
        return None;
    }
    let bar = indicatif::ProgressBar::new(0);
    if let Ok(style) = indicatif::ProgressStyle::with_template(
        "{bar:40} {pos}/{len} runs, {elapsed} elapsed, {eta} left",
    ) {
        bar.set_style(style);
    }
    Some(bar)
}

/// What the sweep did, on standard error.
struct Summary<'a> {
    outcome: &'a Outcome,
    total: usize,
    shared: bool,
    cpu_seconds: Option<f64>,
    wall_seconds: f64,
    signal: Option<usize>,
    /// The warnings said before the runs, for the JSON summary.
    warnings: Option<serde_json::Value>,
}

/// The failures a summary lists.
const FAILURES_LISTED: usize = 10;

impl Summary<'_> {
    fn count(&self, status: Status) -> usize {
        self.outcome
            .records
            .iter()
            .filter(|r| r.status == status)
            .count()
    }

    fn print(&self, args: &RunArgs) {
        let runs = &self.outcome.runs;
        let failures: Vec<_> = (self.outcome.records.iter())
            .filter(|r| r.status != Status::Ok)
            .take(FAILURES_LISTED)
            .collect();
        let mut value = serde_json::json!({
            "runs": self.total,
            "part": [runs.start, runs.end],
            "finished": self.outcome.records.len(),
            "resumed": self.outcome.resumed,
            "complete": self.outcome.complete(),
            "ok": self.count(Status::Ok),
            "failed": self.count(Status::Failed),
            "unprepared": self.count(Status::Unprepared),
            "failures": failures.iter().map(|r| serde_json::json!({
                "run": r.run, "status": r.status.name(), "time": r.failure_time, "why": r.failure,
            })).collect::<Vec<_>>(),
            "shared_preparation": self.shared,
            "output": args.out.as_ref().map(|p| p.display().to_string()),
            "journal": (!self.outcome.complete()).then(|| args.out.as_deref().map(|p| journal::path_for(p).display().to_string())).flatten(),
            "interrupted_by_signal": self.signal,
            "cpu_seconds": self.cpu_seconds,
            "wall_seconds": self.wall_seconds,
        });
        if let Some(warnings) = &self.warnings {
            value["warnings"] = warnings.clone();
        }
        match args.report {
            Format::Json => err(&json(&value)),
            Format::Text => err(&self.text(&failures)),
        }
    }

    fn text(&self, failures: &[&lsdc::studies::sweep::record::RunRecord]) -> String {
        let runs = &self.outcome.runs;
        let part = match runs.len() == self.total {
            true => String::new(),
            false => format!(
                " (runs {} to {} of {})",
                runs.start,
                runs.end.saturating_sub(1),
                self.total
            ),
        };
        let mut text = format!(
            "sweep: {} of {} runs{part}: {} ok, {} failed, {} unprepared",
            self.outcome.records.len(),
            runs.len(),
            self.count(Status::Ok),
            self.count(Status::Failed),
            self.count(Status::Unprepared),
        );
        if self.outcome.resumed > 0 {
            text += &format!(" ({} from the journal)", self.outcome.resumed);
        }
        if let Some(cpu) = self.cpu_seconds {
            text += &format!(
                "; {cpu:.3} s of CPU, {:.3} s of wall time",
                self.wall_seconds
            );
        }
        text.push('\n');
        for record in failures {
            let when = record
                .failure_time
                .map_or(String::new(), |t| format!(" at t = {t}"));
            let why = record.failure.as_deref().unwrap_or("");
            text += &format!(
                "  run {} {}{when}: {why}\n",
                record.run,
                record.status.name()
            );
        }
        if !self.outcome.complete() {
            let by = match self.signal {
                Some(signal) => format!("signal {signal}"),
                None => "--max-runs".to_string(),
            };
            text += &format!("stopped by {by}: `--resume` goes on with the runs left\n");
        }
        text
    }
}
